"""FEBio's default pressure (<linear>0</linear>) on an open surface runs as a lagged follower
pressure (energies/pressure_lag.py): a hex8 block on rollers pressed through its quad4 top face
ends at the neo-Hookean closed form of a Cauchy (follower) pressure, through the model and its
converted scene alike, and the tet4 cube's open top face ends at Cauchy stress -p there."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.febio import convert_febio, load_febio
from tissuesim.scene.loader import load_scene

MODELS = Path(__file__).parent / "models"


def _run(scene, steps: int) -> np.ndarray:
    sim = scene.simulation
    for _ in range(steps):
        sim.step()
    return sim.body_positions("body")


def block_feb(p: float) -> str:
    """A unit hex8 block (2 x 2 x 2), neo-Hookean E = 1e4, nu = 0.3, on rollers at x = 0,
    y = 0 and z = 0, p on its top face ramped linearly over 2 static steps."""
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2, 2, 2), element="hex")
    P = mesh.points

    def ids(rows) -> str:
        return ",".join(str(int(i) + 1) for i in rows)

    nodes = "\n".join(f'      <node id="{i + 1}">{x:g},{y:g},{z:g}</node>'
                      for i, (x, y, z) in enumerate(P))  # fmt: skip
    cells = "\n".join(f'      <elem id="{k + 1}">{ids(c)}</elem>' for k, c in enumerate(mesh.cells))
    sets = "\n".join(
        f'    <NodeSet name="{axis}0">\n'
        + "\n".join(f'      <n id="{i + 1}"/>' for i in np.flatnonzero(P[:, k] == 0))
        + "\n    </NodeSet>"
        for k, axis in enumerate("xyz")
    )
    top = "\n".join(f'      <quad4 id="{k + 1}">{ids(f)}</quad4>'
                    for k, f in enumerate(mesh.facet_sets["zmax"]))  # fmt: skip
    bcs = "\n".join(f'    <bc type="fix" node_set="{a}0">\n      <dofs>{a}</dofs>\n    </bc>'
                    for a in "xyz")  # fmt: skip
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="3.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>2</time_steps>
    <step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="tissue" type="neo-Hookean">
      <density>1</density>
      <E>10000</E>
      <v>0.3</v>
    </material>
  </Material>
  <Mesh>
    <Nodes name="block">
{nodes}
    </Nodes>
    <Elements type="hex8" name="block">
{cells}
    </Elements>
{sets}
    <Surface name="top">
{top}
    </Surface>
  </Mesh>
  <MeshDomains>
    <SolidDomain name="block" mat="tissue"/>
  </MeshDomains>
  <Boundary>
{bcs}
  </Boundary>
  <Loads>
    <surface_load type="pressure" surface="top">
      <pressure lc="1">{p:g}</pressure>
      <linear>0</linear>
    </surface_load>
  </Loads>
  <LoadData>
    <load_controller id="1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <points>
        <point>0,0</point>
        <point>1,1</point>
      </points>
    </load_controller>
  </LoadData>
</febio_spec>
"""


def test_a_hex8_block_pressed_through_its_open_top_face_takes_the_follower_closed_form(tmp_path):
    """F = diag(a, a, s) with mu (a^2 - 1) + lam ln J = 0 and mu (s^2 - 1) + lam ln J = -p a^2 s
    (tests/core/test_follower_pressure_open.py): at p = 2000 Pa, s = 0.8094864 and
    a = 1.0637637; a dead pressure would stop at s = 0.8283110."""
    feb = tmp_path / "block.feb"
    feb.write_text(block_feb(2000.0))
    x = _run(load_febio(feb), 2)
    X = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2, 2, 2), element="hex").points
    np.testing.assert_allclose(x, X * [1.0637637, 1.0637637, 0.8094864], atol=1e-7)
    written = convert_febio(feb, tmp_path / "block.toml")
    assert "[[pressure]]" in written[0].read_text()
    assert np.array_equal(_run(load_scene(written[0]), 2), x)


def test_the_cubes_open_top_face_under_febios_default_pressure_ends_at_cauchy_stress_minus_p(
    tmp_path,
):
    """The tet4 Mooney-Rivlin cube of mooney_rivlin_pressure.feb with <linear>0</linear>: the
    top face stays flat and the load follows its area, so sigma_zz = -500 Pa (the dead load of
    the shipped model leaves -500 / a^2)."""
    text = (MODELS / "mooney_rivlin_pressure.feb").read_text()
    feb = tmp_path / "open.feb"
    feb.write_text(text.replace("<linear>1</linear>", "<linear>0</linear>"))
    results = {}
    for name, path in (("follower", feb), ("dead", MODELS / "mooney_rivlin_pressure.feb")):
        with pytest.warns(UserWarning, match="symmetric_stiffness"):
            scene = load_febio(path)
        x = _run(scene, 5)
        body = scene.simulation.body("body")
        X = body.mesh.points
        F = np.diag([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
        P = body.model.material.evaluate(F[None], 1).stress[0]
        results[name] = (P @ F.T / np.linalg.det(F), F[0, 0])
    cauchy, a = results["follower"]
    assert cauchy[2, 2] == pytest.approx(-500.0, rel=1e-6)
    assert np.abs(cauchy[:2, :2]).max() < 1e-6 * 500
    dead, a_dead = results["dead"]
    assert dead[2, 2] == pytest.approx(-500.0 / a_dead**2, rel=1e-6)
    assert cauchy[2, 2] - dead[2, 2] < -5.0  # the follower load is the larger
