"""FEBio's penta6: its node order against FEBio's shape functions, a FEBio 4.0 model of wedges
(a surface that mixes tri3 and quad4 facets, a dead traction and a dead pressure) run through
``load_febio`` against the same wedges scripted through the Python API, and a misnumbered
penta6 refused at its element."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.febio import FebError, febio_scene, load_febio, read_feb
from tissuesim.mesh.cells import wedge
from tissuesim.solve.newton import NewtonOptions

E, NU, TRACTION, PRESSURE = 1e4, 0.3, (0.0, 0.0, -30.0), 20.0


def febio_penta6_shape(r, s, t):
    """FEBio's FEPenta6::shape_fnc (FECore/FESolidElementShape.cpp)."""
    return np.array(
        [
            0.5 * (1 - t) * (1 - r - s),
            0.5 * (1 - t) * r,
            0.5 * (1 - t) * s,
            0.5 * (1 + t) * (1 - r - s),
            0.5 * (1 + t) * r,
            0.5 * (1 + t) * s,
        ]
    )


def test_node_order_is_febios():
    """tissuesim's node k sits where FEBio's shape function k is 1, and both sets of shape
    functions agree everywhere: penta6 is read without a permutation."""
    febio = np.array([febio_penta6_shape(*x) for x in wedge.NODES])
    np.testing.assert_array_equal(febio, np.eye(6))
    xi = np.random.default_rng(0).uniform([0, 0, -1], [0.5, 0.5, 1], (5, 3))
    np.testing.assert_allclose(wedge.shape_functions(xi)[0].T, febio_penta6_shape(*xi.T))


def beam():
    """2 x 1 x 1: two hexahedra, each cut into two wedges."""
    return ts.box((0, 0, 0), (2, 1, 1), (2, 1, 1), element="wedge")


def feb_text(mesh: ts.Mesh, cells: np.ndarray | None = None) -> str:
    """A FEBio 4.0 model of ``mesh``: neo-Hookean, clamped at x = 0, a dead traction on the
    surface "load" (the end's quad4 and the top's tri3 facets together) and a dead pressure on
    "top" (tri3), both ramped over 2 steps."""
    cells = mesh.cells if cells is None else cells
    nodes = "\n".join(
        f'      <node id="{i + 1}">{x:g},{y:g},{z:g}</node>'
        for i, (x, y, z) in enumerate(mesh.points)
    )
    elems = "\n".join(
        f'      <elem id="{e + 1}">{",".join(str(v + 1) for v in c)}</elem>'
        for e, c in enumerate(cells)
    )

    def facets(rows):
        out = []
        for k, f in enumerate(rows, start=1):
            kind, ids = ("tri3", f[:3]) if f[2] == f[3] else ("quad4", f)
            out.append(f'      <{kind} id="{k}">{",".join(str(v + 1) for v in ids)}</{kind}>')
        return "\n".join(out)

    top, end = mesh.facet_sets["zmax"], mesh.facet_sets["xmax"]
    fixed = ",".join(str(v + 1) for v in mesh.point_sets["xmin"])
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>2</time_steps>
    <step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="tissue" type="neo-Hookean">
      <density>1000</density>
      <E>{E:g}</E>
      <v>{NU:g}</v>
    </material>
  </Material>
  <Mesh>
    <Nodes name="beam">
{nodes}
    </Nodes>
    <Elements type="penta6" name="beam">
{elems}
    </Elements>
    <NodeSet name="x0">{fixed}</NodeSet>
    <Surface name="load">
{facets(np.concatenate([end, top]))}
    </Surface>
    <Surface name="top">
{facets(top)}
    </Surface>
  </Mesh>
  <MeshDomains>
    <SolidDomain name="beam" mat="tissue"/>
  </MeshDomains>
  <Boundary>
    <bc name="clamp" node_set="x0" type="zero displacement">
      <x_dof>1</x_dof>
      <y_dof>1</y_dof>
      <z_dof>1</z_dof>
    </bc>
  </Boundary>
  <Loads>
    <surface_load type="traction" surface="load">
      <traction lc="1">{",".join(f"{v:g}" for v in TRACTION)}</traction>
      <linear>1</linear>
    </surface_load>
    <surface_load type="pressure" surface="top">
      <pressure lc="1">{PRESSURE:g}</pressure>
      <linear>1</linear>
    </surface_load>
  </Loads>
  <LoadData>
    <load_controller id="1" name="ramp" type="loadcurve">
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


def test_febio_penta6_model_runs_as_the_same_wedges_scripted(tmp_path):
    """The model read, converted (its mixed surface written as Gmsh triangles and quads under
    one tag) and run agrees with the same problem set up through the Python API to round-off;
    the loads are FEBio's nodal loads: a quarter of a rectangle's force on each of its
    corners, a third of a triangle's, and the clamp takes them all."""
    mesh = beam()
    feb = tmp_path / "wedges.feb"
    feb.write_text(feb_text(mesh))
    data, meshes = febio_scene(read_feb(feb), "wedges")
    ((converted,),) = [list(meshes.values())]
    assert converted.cell_type == "wedge" and data["simulation"]["formulation"] == "displacement"
    np.testing.assert_array_equal(converted.cells, mesh.cells)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = load_febio(feb).simulation
    body = sim.body("body")
    load = sorted(map(tuple, body.mesh.facet_sets["load"]))
    assert load == sorted(
        map(tuple, np.concatenate([mesh.facet_sets["xmax"], mesh.facet_sets["zmax"]]))
    )
    f = body.model.external_force(1.0).reshape(-1, 3)
    # the end: one quad 1 x 1, its force in 4 quarters; the top 2 x 1: 4 triangles of area
    # 0.5, a third of each one's force (the traction's and the pressure's) on each corner
    expected = np.zeros(len(mesh.points))
    np.add.at(expected, mesh.facet_sets["xmax"].ravel(), TRACTION[2] * 1.0 / 4)
    top = mesh.facet_sets["zmax"][:, :3]
    np.add.at(expected, top.ravel(), (TRACTION[2] - PRESSURE) * 0.5 / 3)
    np.testing.assert_allclose(f[:, 2], expected, atol=1e-9)
    assert f[:, :2] == pytest.approx(0.0, abs=1e-12)

    def ramp(value):
        return lambda X, t: np.broadcast_to(np.multiply(value, min(t, 1.0)), X.shape)

    script = ts.Simulation(integrator="quasistatic", time_step=0.5, newton=NewtonOptions())
    mat = ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=NU)
    script.add_body("body", mesh, mat, density=1000)
    script.fix(mesh.point_sets["xmin"], body="body", name="clamp")
    script.add_traction(mesh.facet_sets["xmax"], ramp(TRACTION), body="body")
    pressed = np.add(TRACTION, (0, 0, -PRESSURE))
    script.add_traction(mesh.facet_sets["zmax"], ramp(pressed), body="body")
    for _ in range(2):
        a, b = sim.step(), script.step()
        assert a.converged and b.converged
    u, v = sim.displacement, script.displacement
    assert v[:, 2].min() < -0.15  # the end bends down 0.19 m; the two agree to 3e-15
    assert np.abs(u - v).max() <= 1e-10 * np.abs(v).max()
    reaction = sim.forces()["clamp"]
    assert reaction[2] == pytest.approx(-f[:, 2].sum(), rel=1e-8)


def test_misnumbered_penta6_is_refused_at_its_element(tmp_path):
    """A penta6 in VTK's order (its triangles reversed) has a negative Jacobian, which FEBio
    refuses too: one line naming the element's line."""
    mesh = beam()
    cells = mesh.cells.copy()
    cells[1] = cells[1][[0, 2, 1, 3, 5, 4]]
    feb = tmp_path / "bad.feb"
    feb.write_text(feb_text(mesh, cells))
    line = next(i for i, s in enumerate(feb.read_text().splitlines(), 1) if '<elem id="2">' in s)
    with pytest.raises(FebError) as info:
        read_feb(feb)
    said = str(info.value)
    assert "\n" not in said and f"bad.feb:{line} <elem>" in said
    assert "not in FEBio's order" in said and "1 such elements" in said


def test_an_uncoupled_law_on_penta6_runs_febios_three_field_element_by_default(tmp_path):
    """FEBio runs an uncoupled law on penta6 without a domain type in its three-field form, as
    on hex8 (FEModelBuilder: ET_PENTA6 takes m_b3field_hex)."""
    text = feb_text(beam()).replace('type="neo-Hookean">', 'type="Mooney-Rivlin">')
    text = text.replace(f"<E>{E:g}</E>", "<c1>1000</c1>").replace(f"<v>{NU:g}</v>", "<k>1e5</k>")
    feb = tmp_path / "uncoupled.feb"
    feb.write_text(text)
    data, _ = febio_scene(read_feb(feb), "uncoupled")
    assert data["simulation"]["formulation"] == "mean_dilatation"
