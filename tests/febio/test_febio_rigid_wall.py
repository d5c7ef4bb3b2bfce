"""FEBio's rigid wall (``<Constraints>`` / ``<Contact>`` ``rigid_wall``) converted to
tissuesim's (febio/constraint_sections.py, contact/penalty/rigid_wall.py), on a deck of our own:
a 2 x 2 x 2 hex8 cube (nu = 0) held at its top, 0.1 above the plane 0,0,2,0.2 (z = 0.1, a
normal of length 2) that its offset moves. FEBio's gap is offset - |a| (a . x - d): the face
sinks until penalty x gap is the pressure, the force along the unit normal."""

from __future__ import annotations

import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest

from tissuesim.febio import convert_febio, load_febio
from tissuesim.febio.xml import FebError
from tissuesim.scene.loader import load_scene

PENALTY = 400.0


def _deck(wall: str, where: str = "Constraints") -> str:
    """The cube's deck with ``wall``'s children in a rigid_wall of <Constraints> (or of
    <Contact>)."""
    grid = np.linspace(0.0, 1.0, 3)
    ids = {}
    nodes = []
    for k, z in enumerate(grid):
        for j, y in enumerate(grid):
            for i, x in enumerate(grid):
                ids[i, j, k] = len(ids) + 1
                nodes.append(f'      <node id="{ids[i, j, k]}">{x},{y},{z + 0.2}</node>')
    elems, faces = [], []
    for k in range(2):
        for j in range(2):
            for i in range(2):
                c = [ids[i, j, k], ids[i + 1, j, k], ids[i + 1, j + 1, k], ids[i, j + 1, k]]
                c += [ids[i, j, k + 1], ids[i + 1, j, k + 1], ids[i + 1, j + 1, k + 1],
                      ids[i, j + 1, k + 1]]  # fmt: skip
                elems.append(f'      <elem id="{len(elems) + 1}">{",".join(map(str, c))}</elem>')
                if k == 0:  # the bottom face, its normal out of the cube (down)
                    q = [c[0], c[3], c[2], c[1]]
                    faces.append(f'      <quad4 id="{len(faces) + 1}">{",".join(map(str, q))}'
                                 "</quad4>")  # fmt: skip
    top = ",".join(str(ids[i, j, 2]) for j in range(3) for i in range(3))
    if where == "Constraints":
        block = (f'  <Constraints>\n    <constraint name="floor" surface="bottom" '
                 f'type="rigid_wall">\n{wall}    </constraint>\n  </Constraints>\n')  # fmt: skip
    else:
        block = (f'  <Contact>\n    <contact name="floor" surface="bottom" type="rigid_wall">\n'
                 f"{wall}    </contact>\n  </Contact>\n")  # fmt: skip
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>2</time_steps>
    <step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="rubber" type="neo-Hookean">
      <density>1</density>
      <E>1000</E>
      <v>0</v>
    </material>
  </Material>
  <Mesh>
    <Nodes name="cube">
{chr(10).join(nodes)}
    </Nodes>
    <Elements type="hex8" name="cube">
{chr(10).join(elems)}
    </Elements>
    <NodeSet name="top">{top}</NodeSet>
    <Surface name="bottom">
{chr(10).join(faces)}
    </Surface>
  </Mesh>
  <MeshDomains>
    <SolidDomain name="cube" mat="rubber"/>
  </MeshDomains>
  <Boundary>
    <bc name="hold" node_set="top" type="zero displacement">
      <x_dof>1</x_dof>
      <y_dof>1</y_dof>
      <z_dof>1</z_dof>
    </bc>
  </Boundary>
{block}  <LoadData>
    <load_controller id="1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <extend>CONSTANT</extend>
      <points>
        <pt>0,0</pt>
        <pt>1,1</pt>
      </points>
    </load_controller>
  </LoadData>
</febio_spec>
"""


PLAIN = f"""      <laugon>PENALTY</laugon>
      <penalty>{PENALTY}</penalty>
      <offset lc="1">0.6</offset>
      <plane>0,0,2,0.2</plane>
"""


def _run(text: str, tmp_path: Path):
    path = tmp_path / "wall.feb"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(path)
    sim = scene.simulation
    for _ in range(scene.run["steps"]):
        sim.step()
    return sim


@pytest.mark.parametrize("where", ["Constraints", "Contact"])
def test_the_face_sinks_by_febios_gap(where, tmp_path):
    """At t = 1 the offset is 0.6: FEBio's gap 0.6 - 2 (2 z - 0.2) = 0.6 - 4 (z - 0.1) at the
    bottom's height z (0.2 at rest: the plane reaches it at offset 0.4), and the wall's force
    on the unit face is penalty x gap, balanced by the top's reaction."""
    sim = _run(_deck(PLAIN, where), tmp_path)
    f = sim.forces()
    z = sim.positions[sim.body(next(iter(sim.bodies))).mesh.points[:, 2] < 0.2 + 1e-9, 2]
    assert f["floor"][2] > 10.0 and np.ptp(z) < 1e-9
    assert f["floor"][2] == pytest.approx(PENALTY * (0.6 - 4 * (z[0] - 0.1)), rel=1e-9)
    assert f["hold"][2] == pytest.approx(-f["floor"][2], rel=1e-7)


def test_a_penalty_on_a_load_curve_scales_with_it(tmp_path):
    """<penalty lc="1">: at t = 0.5 the penalty is half (the curve 0 -> 1 over [0, 1]) and the
    offset 0.6 (1.2 at t = 1): the force is PENALTY / 2 x (0.6 - 4 (z - 0.1))."""
    wall = PLAIN.replace("<penalty>", '<penalty lc="1">').replace(">0.6</offset>", ">1.2</offset>")
    path = tmp_path / "wall.feb"
    path.write_text(_deck(wall))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(path)
    sim = scene.simulation
    sim.step()
    assert sim.time == pytest.approx(0.5)
    z = sim.positions[sim.body(next(iter(sim.bodies))).mesh.points[:, 2] < 0.2 + 1e-9, 2]
    force = sim.forces()["floor"][2]
    assert force > 1.0
    assert force == pytest.approx(PENALTY / 2 * (0.6 - 4 * (z[0] - 0.1)), rel=1e-9)


def test_auglag_closes_febios_gap(tmp_path):
    """AUGLAG with tolerance 1e-8: the bottom ends on the moved plane, z = 0.1 + 0.6 / 4."""
    wall = PLAIN.replace("PENALTY", "AUGLAG") + "      <tolerance>1e-8</tolerance>\n"
    sim = _run(_deck(wall), tmp_path)
    z = sim.positions[sim.body(next(iter(sim.bodies))).mesh.points[:, 2] < 0.2 + 1e-9, 2]
    np.testing.assert_allclose(z, 0.25, atol=1e-6)
    assert sim.system.penalty_contacts[0].augmentations > 2


def test_the_converted_scene_has_the_wall_and_runs_alike(tmp_path):
    feb = tmp_path / "wall.feb"
    feb.write_text(_deck(PLAIN))
    scene_path = tmp_path / "wall.toml"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        convert_febio(feb, scene_path)
    table = tomllib.loads(scene_path.read_text())["rigid_wall"]
    assert len(table) == 1 and table[0]["name"] == "floor"
    # the unit plane z = 0.1, the penalty x 4 and the offset / 4: FEBio's force
    np.testing.assert_allclose(table[0]["plane"], [0, 0, 1, 0.1])
    assert table[0]["penalty"] == pytest.approx(4 * PENALTY)
    scene = load_scene(scene_path)
    for _ in range(scene.run["steps"]):
        scene.simulation.step()
    direct = _run(_deck(PLAIN), tmp_path)
    assert scene.simulation.forces()["floor"] == pytest.approx(direct.forces()["floor"])


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("<laugon>PENALTY</laugon>", "<laugon>2</laugon>", "laugon = '2'"),
        ("<laugon>PENALTY</laugon>", "<two_pass>1</two_pass>", "<two_pass> in a rigid_wall"),
        ("<plane>0,0,2,0.2</plane>", "<plane>0,0,0,0.2</plane>", "zero normal"),
        ("<plane>0,0,2,0.2</plane>", '<plane lc="1">0,0,2,0.2</plane>', 'attribute lc="1"'),
        ("<penalty>", '<penalty lc="7">', "load curve 7"),
    ],
)
def test_what_is_not_mapped_is_refused_in_one_line(old, new, message, tmp_path):
    path = tmp_path / "wall.feb"
    path.write_text(_deck(PLAIN.replace(old, new)))
    with pytest.raises(FebError, match=message) as info:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            load_febio(path)
    assert "\n" not in str(info.value) and "wall.feb:" in str(info.value)


def test_a_wall_without_penalty_pushes_nothing_as_in_febio(tmp_path):
    """FEBio's rigid wall's penalty defaults to 0: no force; the wall is left out, noted."""
    path = tmp_path / "wall.feb"
    path.write_text(_deck(PLAIN.replace(f"      <penalty>{PENALTY}</penalty>\n", "")))
    with pytest.warns(UserWarning, match="penalty 0"):
        scene = load_febio(path)
    assert "rigid_wall" not in str(scene.simulation.rigid_walls)
    assert scene.simulation.rigid_walls == []
