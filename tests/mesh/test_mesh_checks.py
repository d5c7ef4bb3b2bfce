"""validate_mesh: errors naming source and element, reorientation, sets."""

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import MeshError
from tissuesim.mesh import signed_volumes, validate_mesh

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
TRIS = np.array([[0, 1, 2], [0, 2, 3]])
TET_POINTS = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]])


def test_valid_mesh_types_and_volumes():
    m = validate_mesh(SQUARE.tolist(), TRIS.astype(np.int32), source="square")
    assert m.points.dtype == np.float64 and m.cells.dtype == np.int64
    assert m.cells.flags.c_contiguous and m.source == "square"
    np.testing.assert_allclose(signed_volumes(m.points, m.cells), [0.5, 0.5])
    assert signed_volumes(TET_POINTS, [[0, 1, 2, 3]])[0] == pytest.approx(1 / 6)


def test_nan_point_named():
    p = SQUARE.copy()
    p[2, 1] = np.nan
    with pytest.raises(MeshError, match=r"square: vertex 2 .*non-finite"):
        validate_mesh(p, TRIS, source="square")


def test_bad_shapes():
    with pytest.raises(MeshError, match=r"\(n, 2\) or \(n, 3\)"):
        validate_mesh(np.zeros((4, 4)), TRIS, source="s")
    with pytest.raises(MeshError, match=r"need \(m, 3\) cells"):
        validate_mesh(SQUARE, [[0, 1, 2, 3, 0]], source="s")  # (m, 4): quadrilaterals
    with pytest.raises(MeshError, match="no cells"):
        validate_mesh(SQUARE, np.zeros((0, 3), dtype=int), source="s")


@pytest.mark.parametrize("bad", [4, -1])
def test_index_out_of_range_named(bad):
    cells = np.array([[0, 1, 2], [0, 2, bad]])
    with pytest.raises(MeshError, match=rf"s: element 1 refers to vertex {bad}\b"):
        validate_mesh(SQUARE, cells, source="s")


def test_repeated_vertex():
    with pytest.raises(MeshError, match=r"element 1 repeats a vertex \[0, 2, 2\]"):
        validate_mesh(SQUARE, [[0, 1, 2], [0, 2, 2]], source="s")


def test_collinear_triangle_named():
    p = np.vstack([SQUARE, [[2.0, 0.0]]])
    with pytest.raises(MeshError, match=r"s: element 2 with vertices \[0, 1, 4\] is degenerate"):
        validate_mesh(p, [[0, 1, 2], [0, 2, 3], [0, 1, 4]], source="s")


def test_flat_tet_named():
    p = np.vstack([TET_POINTS, [[0.5, 0.5, 0.0]]])
    with pytest.raises(MeshError, match=r"element 1 with vertices \[0, 1, 2, 5\].*coplanar"):
        validate_mesh(p, [[0, 1, 2, 3], [0, 1, 2, 5]], source="flat.vtu")


def test_reversed_elements_reoriented_with_warning():
    cells = np.array([[0, 2, 1], [0, 2, 3]])
    with pytest.warns(UserWarning, match=r"reoriented 1 .*\[0\]"):
        m = validate_mesh(SQUARE, cells, source="s")
    np.testing.assert_array_equal(m.cells, [[0, 1, 2], [0, 2, 3]])
    np.testing.assert_array_equal(cells, [[0, 2, 1], [0, 2, 3]])  # input untouched
    with pytest.warns(UserWarning, match="reoriented 1"):
        m3 = validate_mesh(TET_POINTS[:4], [[0, 2, 1, 3]], source="t")
    assert signed_volumes(m3.points, m3.cells)[0] > 0


def test_unreferenced_vertices_are_dropped_and_indices_remapped():
    # a stray vertex first: every later index shifts down by one, sets follow
    p = np.vstack([[[5.0, 5.0]], SQUARE])
    cells = np.asarray(TRIS) + 1
    with pytest.warns(UserWarning, match=r"dropped 1 vertices that belong to no element"):
        m = validate_mesh(p, cells, source="s", point_sets={"corner": [1, 3]})
    assert m.n_points == len(SQUARE)
    np.testing.assert_array_equal(m.points, SQUARE)
    np.testing.assert_array_equal(m.cells, validate_mesh(SQUARE, TRIS, source="s").cells)
    np.testing.assert_array_equal(m.point_sets["corner"], [0, 2])


def test_unreferenced_vertices_no_longer_break_the_solver():
    """Before: a stray vertex was a massless free DOF; Newton's line search then failed."""
    p = np.vstack([SQUARE, [[5.0, 5.0]]])
    with pytest.warns(UserWarning, match="dropped 1"):
        mesh = validate_mesh(p, TRIS, source="s")
    sim = ts.Simulation(
        mesh,
        ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3),
        integrator="quasistatic",
        time_step=1.0,
    )
    sim.add_dirichlet([0, 3])
    sim.add_gravity([0.0, -9.81])
    assert sim.step().newton_iterations >= 1


def test_coincident_vertices_are_refused_or_merged():
    # two triangles sharing an edge, exported unwelded: vertices 4 and 5 duplicate 1 and 2
    pts = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [1, 0], [0, 1 + 1e-13]], float)
    cells = [[0, 1, 2], [4, 3, 5]]
    with pytest.raises(
        MeshError, match=r"2 vertices coincide .*vertices 1 and 4.*merge_coincident"
    ):
        validate_mesh(pts, cells, source="seam.vtu")
    with pytest.warns(UserWarning, match="merged 2 coincident vertices"):
        m = validate_mesh(pts, cells, source="seam.vtu", merge_coincident=True)
    assert m.n_points == 4
    assert set(m.cells[1].tolist()) == {1, 2, 3}  # one body now: the shared edge is 1-2


def test_merging_that_collapses_an_element_is_refused():
    # vertex 3 lies 1e-10 from vertex 1: element 1 is thin but valid, merged it collapses
    pts = np.array([[0, 0], [1, 0], [0, 1], [1 + 1e-10, 1e-10]], float)
    with pytest.raises(MeshError, match="collapses element 1"):
        validate_mesh(pts, [[0, 1, 2], [1, 3, 2]], source="s", merge_coincident=True)


def test_duplicate_element_rejected():
    with pytest.raises(MeshError, match="shared by elements"):
        validate_mesh(TET_POINTS, [[0, 1, 2, 3], [0, 1, 2, 3], [1, 2, 3, 4]], source="s")


def test_sets_checked_and_facets_oriented_outward():
    m = validate_mesh(
        SQUARE,
        TRIS,
        source="s",
        point_sets={"p": [3, 0, 0]},
        facet_sets={"bottom": [[1, 0]], "left": [[0, 3], [3, 0]]},
        cell_sets={"c": np.array([1])},
    )
    np.testing.assert_array_equal(m.point_sets["p"], [0, 3])
    np.testing.assert_array_equal(m.facet_sets["bottom"], [[0, 1]])
    np.testing.assert_array_equal(m.facet_sets["left"], [[3, 0]])
    with pytest.raises(MeshError, match="'diag' row 0 .* not a boundary facet"):
        validate_mesh(SQUARE, TRIS, source="s", facet_sets={"diag": [[0, 2]]})
    with pytest.raises(MeshError, match="point set 'p'"):
        validate_mesh(SQUARE, TRIS, source="s", point_sets={"p": [7]})
    with pytest.raises(MeshError, match="cell set 'c'"):
        validate_mesh(SQUARE, TRIS, source="s", cell_sets={"c": [2]})
