"""Quadratic meshes: generators, checks of midside nodes, files, output, subdivision."""

import meshio
import numpy as np
import pytest

from tissuesim.errors import MeshError
from tissuesim.mesh import box, ellipsoid, read_mesh, rectangle, write_mesh
from tissuesim.mesh.cells.elevate import elevate_mesh
from tissuesim.mesh.checks import validate_mesh


def test_generators_put_midside_nodes_in_the_side_sets():
    m = box(divisions=(2, 2, 2), order=2)
    assert m.order == 2 and m.cells.shape == (48, 10) and m.n_points == 125
    on = m.points[m.point_sets["xmin"]]
    assert np.all(on[:, 0] == 0.0) and len(on) == 25  # 5 x 5 nodes on the face
    r = rectangle(divisions=(2, 3), order=2)
    assert len(r.point_sets["top"]) == 5
    e = ellipsoid(divisions=4, order=2)
    surface = e.points[e.point_sets["surface"]]
    np.testing.assert_allclose(np.linalg.norm(surface, axis=1), 1.0, atol=1e-12)


def test_elevate_keeps_vertex_ids_and_sets():
    m = box(divisions=(2, 1, 1))
    q = elevate_mesh(m)
    np.testing.assert_array_equal(q.points[: m.n_points], m.points)
    np.testing.assert_array_equal(q.corners, m.cells)
    assert set(m.point_sets["zmax"]) < set(q.point_sets["zmax"])
    assert np.all(q.points[q.point_sets["zmax"], 2] == 1.0)


def test_subdivision_covers_the_cells_positively():
    for m in (rectangle(divisions=(2, 2), order=2), box(divisions=(1, 2, 1), order=2)):
        from tissuesim.mesh.checks import signed_volumes

        vol = signed_volumes(m.points, m.simplices)
        assert vol.min() > 0
        assert vol.sum() == pytest.approx(1.0)
        assert m.simplices.shape[0] == m.n_cells * (4 if m.dim == 2 else 8)


def test_a_displaced_midside_node_is_refused():
    m = rectangle(divisions=(1, 1), order=2)
    p = m.points.copy()
    mid = m.cells[0, 3]
    a, b = m.cells[0, 0], m.cells[0, 1]
    p[mid] = p[a] + 0.9 * (p[b] - p[a])  # 0.4 of the edge off its midpoint
    with pytest.raises(MeshError, match=r"midside node .* lies .* from the midpoint"):
        validate_mesh(p, m.cells, source="moved.msh")


def test_a_node_order_mistake_is_refused():
    m = rectangle(divisions=(1, 1), order=2)
    cells = m.cells.copy()
    cells[0, [0, 3]] = cells[0, [3, 0]]  # a corner and a midside node swapped
    with pytest.raises(MeshError, match="corner of one element and a midside node"):
        validate_mesh(m.points, cells, source="swapped.msh")


def test_nonconforming_midside_nodes_are_refused():
    m = rectangle(divisions=(2, 1), order=2)
    p = np.concatenate([m.points, m.points[:1] * 0 + 99.0])
    cells = m.cells.copy()
    # give one element its own copy of a shared edge's midside node
    shared = np.intersect1d(cells[0, 3:], cells[1, 3:])
    assert shared.size == 1
    p[-1] = p[shared[0]]
    cells[1][cells[1] == shared[0]] = len(p) - 1
    with pytest.raises(MeshError, match="coincide|not conforming"):
        validate_mesh(p, cells, source="split.msh")


def test_a_folded_curved_element_is_refused():
    m = rectangle(divisions=(1, 1), order=2)
    p = m.points.copy()
    mid = m.cells[0, 4]  # the midpoint of edge (1, 2), pushed across the element
    centre = p[m.cells[0, :3]].mean(axis=0)
    p[mid] = p[mid] + 0.24 * np.linalg.norm(p[m.cells[0, 1]] - p[m.cells[0, 2]]) * (
        (centre - p[mid]) / np.linalg.norm(centre - p[mid])
    )
    # within the midside tolerance, yet the element's Jacobian changes sign near the corner
    try:
        validate_mesh(p, m.cells, source="folded.msh")
    except MeshError as exc:
        assert "folded" in str(exc)
    else:  # 0.24 may still be valid: push until folded
        p[mid] = centre
        with pytest.raises(MeshError, match="folded|midpoint"):
            validate_mesh(p, m.cells, source="folded.msh")


def test_negatively_oriented_quadratic_cells_are_reoriented_with_their_midside_nodes():
    for m, perm in (
        (rectangle(divisions=(1, 1), order=2), [0, 2, 1, 5, 4, 3]),
        (box(divisions=(1, 1, 1), order=2), [0, 1, 3, 2, 4, 8, 7, 6, 5, 9]),
    ):
        cells = m.cells.copy()
        cells[0] = cells[0][perm]
        with pytest.warns(UserWarning, match="reoriented 1"):
            fixed = validate_mesh(m.points, cells, source="flipped")
        np.testing.assert_array_equal(fixed.cells[0], m.cells[0])


@pytest.mark.parametrize("suffix", [".msh", ".vtu"])
def test_tetra10_files_round_trip(tmp_path, suffix):
    m = box(divisions=(2, 1, 1), order=2)
    write_mesh(m, tmp_path / f"b{suffix}")
    back = read_mesh(tmp_path / f"b{suffix}")
    assert back.order == 2
    np.testing.assert_allclose(back.points, m.points)
    np.testing.assert_array_equal(back.cells, m.cells)
    if suffix == ".msh":
        assert set(back.facet_sets) >= {"xmin", "zmax"}
        np.testing.assert_array_equal(np.sort(back.facet_sets["xmin"], axis=1),
                                      np.sort(m.facet_sets["xmin"], axis=1))  # fmt: skip


def test_gmsh_second_order_node_order_is_converted(tmp_path):
    # Gmsh numbers a tetra10's last two edges (2,3) then (1,3); meshio converts to VTK's order
    m = box(divisions=(1, 1, 1), order=2)
    gm = m.cells[:, [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]]
    path = tmp_path / "g.msh"
    path.write_text(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n"
        + f"{m.n_points}\n"
        + "".join(f"{i + 1} {x} {y} {z}\n" for i, (x, y, z) in enumerate(m.points))
        + "$EndNodes\n$Elements\n"
        + f"{m.n_cells}\n"
        + "".join(
            f"{e + 1} 11 2 1 1 " + " ".join(str(v + 1) for v in c) + "\n" for e, c in enumerate(gm)
        )
        + "$EndElements\n"
    )
    back = read_mesh(path)
    np.testing.assert_array_equal(back.cells, m.cells)


def test_vtu_output_writes_quadratic_cells(tmp_path):
    from tissuesim.io.series.vtu import VTUSeriesWriter

    m = box(divisions=(1, 1, 1), order=2)
    w = VTUSeriesWriter(tmp_path, m, "body")
    w.write(0.0, m.points, point_data={"displacement": np.zeros((m.n_points, 3))})
    files = sorted(tmp_path.glob("*.vtu"))
    back = meshio.read(files[0])
    assert back.cells[0].type == "tetra10" and back.cells[0].data.shape == (6, 10)
