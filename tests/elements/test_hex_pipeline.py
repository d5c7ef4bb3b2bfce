"""Q1 hexahedra and quadrilaterals through the whole pipeline: files, generators in scenes,
output series, pictures' geometry, contact on the split boundary, and what is refused."""

import json

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError, MeshError
from tissuesim.mesh import describe_mesh, read_mesh, write_mesh
from tissuesim.mesh.cells.tensor import split_faces
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.queries.boundary import boundary_facets


def test_generators_sets_and_split_boundary():
    m = ts.box((0, 0, 0), (2, 1, 1), (4, 2, 3), element="hex")
    assert (m.cell_type, m.n_cells, m.n_points, m.order) == ("hexahedron", 24, 60, 1)
    assert m.facet_sets["zmax"].shape == (8, 4) and m.facet_nodes == 4
    quads = ts.select.all_boundary_facets(m)
    assert quads.shape == (2 * (8 + 12 + 6), 4)
    # the simplices' boundary (contact, pictures) is every boundary quad split in two
    tri = boundary_facets(m.simplices)
    assert len(tri) == 2 * len(quads)
    assert set(map(tuple, np.sort(tri, axis=1))) == set(
        map(tuple, np.sort(split_faces(quads), axis=1))
    )
    vol = np.linalg.det(
        np.swapaxes(m.points[m.simplices][:, 1:] - m.points[m.simplices][:, :1], 1, 2)
    )
    assert vol.min() > 0 and vol.sum() / 6 == pytest.approx(2.0)
    r = ts.rectangle((0, 0), (2, 1), (4, 2), element="quad")
    assert (r.cell_type, r.n_cells, r.facet_sets["top"].shape) == ("quad", 8, (4, 2))
    assert r.linear_view.n_cells == 16
    with pytest.raises(MeshError, match="element must be"):
        ts.box(element="hexa")
    with pytest.raises(MeshError, match="order 1"):
        ts.box(element="hex", order=2)


def test_unstructured_numbering_keeps_the_split_closed():
    """Hexahedra numbered from different corners split a shared face along different
    diagonals; a flat tetrahedron glues the two, so the split's boundary is still the
    boundary faces' halves."""
    m = ts.box(divisions=(2, 2, 2), element="hex")
    rot = np.array([1, 2, 3, 0, 5, 6, 7, 4])  # the same hexahedron, numbered from node 1
    cells = m.cells.copy()
    cells[::3] = cells[::3][:, rot]
    r = validate_mesh(m.points, cells, source="rotated")
    assert len(r.simplices) > 6 * r.n_cells
    assert len(boundary_facets(r.simplices)) == 2 * len(ts.select.all_boundary_facets(r))


def test_inverted_and_mirrored_hexahedra():
    m = ts.box(divisions=(2, 1, 1), element="hex")
    mirrored = m.cells.copy()
    mirrored[0] = mirrored[0][[4, 5, 6, 7, 0, 1, 2, 3]]
    with pytest.warns(UserWarning, match="reoriented 1"):
        r = validate_mesh(m.points, mirrored, source="mirrored")
    np.testing.assert_array_equal(r.cells, m.cells)
    twisted = m.cells.copy()
    twisted[1] = twisted[1][[0, 1, 3, 2, 4, 5, 6, 7]]  # a bow-tie bottom face
    with pytest.raises(MeshError, match="hexahedron 1 .* inverted or degenerate"):
        validate_mesh(m.points, twisted, source="twisted")
    p = m.points.copy()
    node = np.flatnonzero(np.isclose(p[:, 0], 0.5))[0]
    p[node, 0] = 1.2  # one node pushed through its neighbour: a negative Jacobian at a corner
    with pytest.raises(MeshError, match="inverted or degenerate"):
        validate_mesh(p, m.cells, source="folded")
    flat = m.points.copy()
    flat[:, 2] *= 1e-12
    with pytest.raises(MeshError, match="degenerate|coincide"):
        validate_mesh(flat, m.cells, source="flat")


def test_files_round_trip(tmp_path):
    m = ts.box((0, 0, 0), (1, 2, 1), (2, 3, 2), element="hex")
    for name in ("hex.vtu", "hex.msh"):
        write_mesh(m, tmp_path / name)
        r = read_mesh(tmp_path / name)
        np.testing.assert_array_equal(r.cells, m.cells)
        np.testing.assert_allclose(r.points, m.points)
    assert {k: v.shape for k, v in r.facet_sets.items()}["zmin"] == (6, 4)
    q = ts.rectangle(divisions=(3, 2), element="quad")
    write_mesh(q, tmp_path / "quad.msh")
    r = read_mesh(tmp_path / "quad.msh")
    assert r.cell_type == "quad" and set(r.facet_sets) >= {"left", "top"}
    info = describe_mesh(m)
    assert info["total_volume"] == pytest.approx(2.0) and info["quality_min"] == pytest.approx(1.0)


def test_simulation_writes_hexahedron_series_and_pictures(tmp_path):
    mesh = ts.box((0, 0, 0), (1, 0.2, 0.2), (5, 1, 1), element="hex")
    mat = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(
        mesh, mat, density=1000, integrator="backward_euler", time_step=0.01, gravity=(0, 0, -9.81)
    )
    sim.fix(ts.select.vertices_on_plane(mesh, 0, 0.0))
    sim.run(3, tmp_path / "out")
    out = tmp_path / "out"
    vtu = sorted(out.glob("body_*.vtu"))[-1]
    m = meshio.read(vtu)
    assert m.cells[0].type == "hexahedron" and len(m.cells[0].data) == 5
    np.testing.assert_allclose(m.points, mesh.points)
    np.testing.assert_allclose(m.point_data["displacement"], sim.displacement, atol=1e-12)
    assert sim.displacement[:, 2].min() < 0
    assert (out / "final.png").is_file()
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"


def test_scene_box_element_hex():
    from tissuesim.scene.loader import build_scene

    scene = {
        "simulation": {"integrator": "quasistatic", "time_step": 1.0},
        "mesh": {
            "generator": "box",
            "upper": [1.0, 0.2, 0.2],
            "divisions": [5, 1, 1],
            "element": "hex",
        },
        "material": {"model": "neo_hookean", "youngs_modulus": 1e5, "poisson_ratio": 0.3},
        "dirichlet": [{"vertices": {"on_plane": {"axis": 0, "value": 0.0}}}],
        "traction": [
            {"facets": {"on_plane": {"axis": 0, "value": 1.0}}, "traction": [0.0, 0.0, -100.0]}
        ],
    }
    sim = build_scene(scene, name="hex_scene").simulation
    assert sim.mesh.cell_type == "hexahedron"
    sim.step()
    tip = np.isclose(sim.mesh.points[:, 0], 1.0)
    assert sim.displacement[tip, 2].mean() < 0
    f = sim.body("body").model.external_force(1.0).reshape(-1, 3)
    assert f[:, 2].sum() == pytest.approx(-100.0 * 0.04, rel=1e-12)


def test_hex_box_rests_on_a_plane_without_intersecting():
    from tissuesim.contact.obstacles import plane

    mesh = ts.box((0, 0, 0.002), (0.1, 0.1, 0.052), (3, 3, 2), element="hex")
    mat = ts.make_material("neo_hookean", youngs_modulus=2e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, mat, density=1000, time_step=0.02, gravity=(0, 0, -9.81))
    sim.add_obstacle("floor", plane((0.05, 0.05, 0.0), (0, 0, 1), 1.0))
    sim.set_contact(dhat=0.001)
    for _ in range(15):
        sim.step()
    z = mesh.points[:, 2] + sim.displacement[:, 2]
    assert z.min() > 0.0  # above the floor: never through it
    assert z.min() < 0.001  # it fell onto it (within dhat)
    force = sim.forces()["floor"]
    weight = 1000 * 0.1 * 0.1 * 0.05 * 9.81
    assert force[2] == pytest.approx(weight, rel=0.3)


def test_refused_with_reasons():
    mesh = ts.box(divisions=(2, 1, 1), element="hex")
    mat = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    sim = ts.Simulation()
    with pytest.raises(InputError, match="order 2 of hexahedron"):
        sim.add_body("a", mesh, mat, order=2)
    sim.add_body("b", mesh, mat)
    from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

    square = [[0.5, -1, -1], [0.5, 2, -1], [0.5, 2, 2], [0.5, -1, 2]]
    cut = PlanarCut(np.array([0.5, 0, 0.0]), np.array([1.0, 0, 0]), np.array(square, float))
    with pytest.raises(InputError, match="hexahedron cells"):
        sim.cut_body(cut, body="b")
