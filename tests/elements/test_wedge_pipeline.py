"""Wedges through the whole pipeline: the generator and its sets, the tetrahedra geometry sees,
node orders (Gmsh / meshio / FEBio against VTK's), checks that refuse a bad cell in one line,
mixed facet sets, files, output series and pictures, scenes, contact, and what is refused."""

import json
import warnings

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.pairs import contact_facets
from tissuesim.errors import InputError, MeshError
from tissuesim.mesh import describe_mesh, read_mesh, write_mesh
from tissuesim.mesh.cells import wedge
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.queries.boundary import boundary_facets

#: a right wedge over the triangle (0, 0), (1, 0), (0, 1), height 2: volume 1
ONE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 2], [1, 0, 2], [0, 1, 2]], dtype=float)


def sorted_rows(a):
    return set(map(tuple, np.sort(a, axis=1)))


@pytest.mark.parametrize("pattern", ["mirrored", "uniform"])
def test_generator_sets_and_split_boundary(pattern):
    m = ts.box((0, 0, 0), (2, 1, 1), (4, 2, 3), element="wedge", pattern=pattern)
    assert (m.cell_type, m.n_cells, m.n_points, m.order, m.facet_nodes) == ("wedge", 48, 60, 1, 4)
    assert "wedges" in repr(m)
    facets = ts.select.all_boundary_facets(m)
    tri = wedge.is_triangle(facets)
    assert (tri.sum(), (~tri).sum()) == (2 * 16, 2 * (6 + 12))  # top / bottom; sides
    assert wedge.is_triangle(m.facet_sets["zmax"]).all() and m.facet_sets["zmax"].shape == (16, 4)
    assert not wedge.is_triangle(m.facet_sets["xmin"]).any()
    # the tetrahedra: 3 per wedge, positive, filling the box; their boundary is the facets'
    # triangles (a shared quad face split alike on both sides: no glue needed)
    assert m.simplices.shape == (3 * 48, 4)
    x = m.points[m.simplices]
    vol = np.linalg.det(x[:, 1:] - x[:, :1]) / 6
    assert vol.min() > 0 and vol.sum() == pytest.approx(2.0)
    assert sorted_rows(boundary_facets(m.simplices)) == sorted_rows(wedge.facet_triangles(facets))
    # every facet outward
    t = m.points[wedge.facet_triangles(facets)]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    assert (np.einsum("ij,ij->i", n, t.mean(axis=1) - [1.0, 0.5, 0.5]) > 0).all()
    with pytest.raises(MeshError, match="'wedge'"):
        ts.box(element="prism")
    with pytest.raises(MeshError, match="order 1"):
        ts.box(element="wedge", order=2)


def test_node_orders_and_the_volume_of_one_wedge():
    """Gmsh's / meshio's / FEBio's order is positive (volume 1 by the Jacobian); VTK's order
    (the bottom triangle reversed) is a mirrored wedge: reoriented with a warning."""
    m = validate_mesh(ONE, [np.arange(6)], source="gmsh order")
    assert describe_mesh(m)["total_volume"] == pytest.approx(1.0, rel=1e-15)
    vtk_order = [[0, 2, 1, 3, 5, 4]]
    with pytest.warns(UserWarning, match="reoriented 1"):
        r = validate_mesh(ONE, vtk_order, source="vtk order")
    assert describe_mesh(r)["total_volume"] == pytest.approx(1.0, rel=1e-15)
    assert sorted_rows(r.cells) == sorted_rows(m.cells)


#: what Gmsh 4.15 writes for a right triangle (legs 1) extruded by 2 in 2 layers of prisms
#: (``Extrude {0, 0, 2} { Surface{1}; Layers{2}; Recombine; }``) with tagged faces
GMSH_PRISMS = """$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
4
2 2 "bottom"
2 3 "top"
2 4 "sides"
3 1 "body"
$EndPhysicalNames
$Nodes
9
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 2
5 1 0 2
6 0 1 2
7 0 0 1
8 1 0 1
9 0 1 1
$EndNodes
$Elements
10
1 2 2 2 1 1 2 3
2 2 2 3 20 4 5 6
3 3 2 4 11 1 2 8 7
4 3 2 4 11 7 8 5 4
5 3 2 4 15 2 3 9 8
6 3 2 4 15 8 9 6 5
7 3 2 4 19 3 1 7 9
8 3 2 4 19 9 7 4 6
9 6 2 1 1 1 2 3 7 8 9
10 6 2 1 1 7 8 9 4 5 6
$EndElements
"""


def test_a_mesh_gmsh_wrote_reads_as_it_is(tmp_path):
    """Gmsh's prisms are positive as they are (no reorientation), volume 1; its tagged
    triangles and quadrilaterals become facet sets, turned outward (Gmsh's bottom triangle
    faces up, into the body)."""
    path = tmp_path / "prisms.msh"
    path.write_text(GMSH_PRISMS)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = read_mesh(path)
    assert m.cell_type == "wedge" and m.n_cells == 2
    assert describe_mesh(m)["total_volume"] == pytest.approx(1.0, rel=1e-14)
    sizes = {k: (len(v), int(wedge.is_triangle(v).sum())) for k, v in m.facet_sets.items()}
    assert sizes == {"bottom": (1, 1), "top": (1, 1), "sides": (6, 0)}
    facets = np.concatenate(list(m.facet_sets.values()))
    t = m.points[wedge.facet_triangles(facets)]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    assert (np.einsum("ij,ij->i", n, t.mean(axis=1) - m.points.mean(axis=0)) > 0).all()


def test_inverted_and_degenerate_wedges_are_refused_in_one_line():
    m = ts.box(divisions=(1, 1, 2), element="wedge")
    twisted = m.cells.copy()
    twisted[1] = twisted[1][[3, 1, 2, 0, 4, 5]]  # one vertical edge upside down
    with pytest.raises(MeshError) as info:
        validate_mesh(m.points, twisted, source="twisted")
    said = str(info.value)
    assert "\n" not in said and "wedge 1 " in said and "inverted or degenerate" in said
    assert "counter-clockwise seen from the top" in said
    p = m.points.copy()
    top = np.flatnonzero(np.isclose(p[:, 2], 0.5) & np.isclose(p[:, 0], 1) & np.isclose(p[:, 1], 1))
    p[top, 2] = 1.2  # pushed through the layer above
    with pytest.raises(MeshError, match="inverted or degenerate"):
        validate_mesh(p, m.cells, source="folded")
    with pytest.raises(MeshError, match="degenerate|coincide"):
        validate_mesh(ONE * [1, 1, 1e-12], [np.arange(6)], source="flat")


def test_facet_sets_take_triangles_in_any_form_and_refuse_others():
    m = ts.box(divisions=(2, 2, 1), element="wedge")
    top = m.facet_sets["zmax"]
    given = {
        "triangles": top[:, :3],
        "rotated": np.roll(top[:, :3], 1, axis=1),  # (c, a, b): the same triangle
        "doubled first": top[:, [0, 0, 1, 2]],
        "mixed": np.concatenate([top, m.facet_sets["xmax"]]),
    }
    r = validate_mesh(m.points, m.cells, source="sets", facet_sets=given)
    for name in ("triangles", "rotated", "doubled first"):
        np.testing.assert_array_equal(r.facet_sets[name], top)
    assert len(r.facet_sets["mixed"]) == len(top) + len(m.facet_sets["xmax"])
    half = m.cells[:1, [0, 1, 4]]  # half of a side face: no facet
    with pytest.raises(MeshError, match="quad faces and triangles"):
        validate_mesh(m.points, m.cells, source="bad", facet_sets={"x": half})


def test_files_round_trip_with_mixed_facet_sets(tmp_path):
    m = ts.box((0, 0, 0), (1, 2, 1), (2, 3, 2), element="wedge")
    for name in ("wedge.vtu", "wedge.msh"):
        write_mesh(m, tmp_path / name)
        r = read_mesh(tmp_path / name)
        np.testing.assert_array_equal(r.cells, m.cells)
        np.testing.assert_allclose(r.points, m.points)
    assert set(r.facet_sets) == set(m.facet_sets)
    for k, v in m.facet_sets.items():
        np.testing.assert_array_equal(r.facet_sets[k], v)
    raw = meshio.read(tmp_path / "wedge.msh")  # Gmsh holds the triangles as triangles
    assert {b.type for b in raw.cells} >= {"wedge", "triangle", "quad"}
    info = describe_mesh(m)
    assert info["total_volume"] == pytest.approx(2.0) and info["n_boundary_facets"] == 44


def test_vtu_holds_vtks_order(tmp_path):
    """meshio writes VTK_WEDGE cells in VTK's documented order (the bottom triangle's normal
    pointing away from the top: nodes 1 <-> 2, 4 <-> 5 swapped) and swaps them back on
    reading; VTK draws their outside faces outward."""
    pv = pytest.importorskip("pyvista")
    m = validate_mesh(ONE, [np.arange(6)], source="one")
    write_mesh(m, tmp_path / "one.vtu")
    grid = pv.read(tmp_path / "one.vtu")
    assert grid.celltypes.tolist() == [13]
    assert grid.cell_connectivity.tolist() == [0, 2, 1, 3, 5, 4]
    surface = grid.extract_surface(algorithm="dataset_surface").compute_normals(
        cell_normals=True, point_normals=False, auto_orient_normals=False, consistent_normals=False
    )
    centres = surface.cell_centers().points - ONE.mean(axis=0)
    assert (np.einsum("ij,ij->i", surface.cell_data["Normals"], centres) > 0).all()


def test_simulation_writes_wedge_series_and_pictures(tmp_path):
    mesh = ts.box((0, 0, 0), (1, 0.2, 0.2), (5, 1, 1), element="wedge")
    mat = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(
        mesh, mat, density=1000, integrator="backward_euler", time_step=0.01, gravity=(0, 0, -9.81)
    )
    sim.fix(ts.select.vertices_on_plane(mesh, 0, 0.0))
    sim.run(2, tmp_path / "out")
    out = tmp_path / "out"
    m = meshio.read(sorted(out.glob("body_*.vtu"))[-1])
    assert m.cells[0].type == "wedge" and len(m.cells[0].data) == 10
    np.testing.assert_array_equal(m.cells[0].data, mesh.cells)
    np.testing.assert_allclose(m.point_data["displacement"], sim.displacement, atol=1e-12)
    assert sim.displacement[:, 2].min() < 0
    assert (out / "final.png").is_file()
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"


def test_scene_box_element_wedge_with_a_traction_on_the_end():
    from tissuesim.scene.loader import build_scene

    scene = {
        "simulation": {"integrator": "quasistatic", "time_step": 1.0},
        "mesh": {"generator": "box", "upper": [1.0, 0.2, 0.2], "divisions": [5, 1, 1]},
        "material": {"model": "neo_hookean", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
        "dirichlet": [{"vertices": {"on_plane": {"axis": 0, "value": 0.0}}}],
        "traction": [
            {"facets": {"on_plane": {"axis": 0, "value": 1.0}}, "traction": [0.0, 0.0, -100.0]}
        ],
    }
    scene["mesh"]["element"] = "wedge"
    sim = build_scene(scene, name="wedge_scene").simulation
    assert sim.mesh.cell_type == "wedge"
    sim.step()
    assert sim.displacement[np.isclose(sim.mesh.points[:, 0], 1.0), 2].mean() < 0
    f = sim.body("body").model.external_force(1.0).reshape(-1, 3)
    assert f[:, 2].sum() == pytest.approx(-100.0 * 0.04, rel=1e-12)


def test_contact_surfaces_and_a_wedge_block_resting_on_a_plane():
    from tissuesim.contact.obstacles import plane

    mesh = ts.box((0, 0, 0.002), (0.1, 0.1, 0.052), (2, 2, 1), element="wedge")
    top = contact_facets("b", mesh, "zmax")
    np.testing.assert_array_equal(top, mesh.facet_sets["zmax"][:, :3])
    sides = contact_facets("b", mesh, "xmin")
    assert sides.shape == (2 * len(mesh.facet_sets["xmin"]), 3)
    assert sorted_rows(contact_facets("b", mesh, None)) == sorted_rows(
        wedge.facet_triangles(ts.select.all_boundary_facets(mesh))
    )
    mat = ts.make_material("neo_hookean", youngs_modulus=2e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, mat, density=1000, time_step=0.02, gravity=(0, 0, -9.81))
    sim.add_obstacle("floor", plane((0.05, 0.05, 0.0), (0, 0, 1), 1.0))
    sim.set_contact(dhat=0.001)
    for _ in range(10):
        sim.step()
    z = mesh.points[:, 2] + sim.displacement[:, 2]
    assert 0.0 < z.min() < 0.001  # on the floor, never through it
    weight = 1000 * 0.1 * 0.1 * 0.05 * 9.81
    assert sim.forces()["floor"][2] == pytest.approx(weight, rel=0.3)


def test_refused_with_reasons():
    mesh = ts.box(divisions=(2, 1, 1), element="wedge")
    mat = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    sim = ts.Simulation()
    with pytest.raises(InputError, match="order 2 of wedge"):
        sim.add_body("a", mesh, mat, order=2)
    sim.add_body("b", mesh, mat)
    from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

    square = [[0.5, -1, -1], [0.5, 2, -1], [0.5, 2, 2], [0.5, -1, 2]]
    cut = PlanarCut(np.array([0.5, 0, 0.0]), np.array([1.0, 0, 0]), np.array(square, float))
    with pytest.raises(InputError, match="wedge cells"):
        sim.cut_body(cut, body="b")


def test_a_traction_on_a_wedges_triangles_given_as_triangles():
    """add_traction takes a wedge body's triangle faces as (k, 3) too: the same load as their
    (k, 4) rows."""
    mesh = ts.box((0, 0, 0), (1, 1, 1), (2, 2, 2), element="wedge")
    top = ts.select.facets_on_plane(mesh, 2, 1.0)
    assert wedge.is_triangle(top).all()
    forces = []
    for facets in (top, top[:, :3]):
        sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3))
        sim.add_traction(facets, [0.0, 0.0, -3.0])
        forces.append(sim.body().model.external_force(0.0))
    np.testing.assert_array_equal(forces[0], forces[1])
    assert forces[1].reshape(-1, 3)[:, 2].sum() == pytest.approx(-3.0, rel=1e-12)
