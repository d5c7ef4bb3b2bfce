"""The virtual node algorithm's core (mesh/cutting/virtual_nodes.py): which cells a cut crosses, the
copies and their volume fractions, node duplication where the material separates."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.mesh.checks import signed_volumes
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, cut_cells, virtual_node_cut


def plane_x(x0: float, y=(-1.0, 2.0), z=(-1.0, 2.0)) -> PlanarCut:
    """The plane x = x0, bounded by the rectangle y0..y1, z0..z1."""
    (y0, y1), (z0, z1) = y, z
    poly = np.array([[x0, y0, z0], [x0, y1, z0], [x0, y1, z1], [x0, y0, z1]])
    return PlanarCut(np.array([x0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), poly)


def volumes(points, cells) -> np.ndarray:
    return np.abs(signed_volumes(points, cells))


@pytest.fixture
def block():
    return ts.box((0.0, 0.0, 0.0), (1.0, 0.5, 0.5), (6, 3, 3))


def test_a_through_cut_parts_the_block_and_keeps_every_volume(block):
    cut = plane_x(0.47)  # through cells, off the mesh planes (x = k / 6)
    out = virtual_node_cut(block.points, block.cells, [cut])
    v0 = volumes(block.points, block.cells)
    v = volumes(out.points, out.cells) * out.fraction  # copies keep their parents' shape
    assert v.sum() == pytest.approx(v0.sum(), rel=1e-12)
    assert out.n_pieces == 2
    hit = cut_cells(block.points, block.cells, cut)
    assert hit.size > 0 and np.all(out.side[np.isin(out.parent, hit)] != 0)
    for e in hit:  # each cut cell: two copies whose fractions add up to one
        mine = out.fraction[out.parent == e]
        assert len(mine) == 2 and mine.sum() == pytest.approx(1.0, abs=1e-12)
    # the side x < 0.47 holds 0.47 of the block: its copies and the whole cells left of it
    v = volumes(out.points, out.cells) * out.fraction
    centre_x = out.points[out.cells].mean(axis=1)[:, 0]
    left = (out.side == -1) | ((out.side == 0) & (centre_x < 0.47))
    assert v[left].sum() == pytest.approx(0.47 * 0.25, rel=1e-12)
    # duplicated nodes sit where their originals are; the cut cells' nodes were duplicated
    np.testing.assert_array_equal(out.points, block.points[out.origin])
    assert len(out.points) > block.n_points and np.all(
        out.origin[: block.n_points] == np.arange(block.n_points)
    )


def test_a_notch_duplicates_nodes_but_leaves_one_piece(block):
    cut = plane_x(0.47, z=(-1.0, 0.3))  # the blade went down 0.2 of the 0.5 depth
    out = virtual_node_cut(block.points, block.cells, [cut])
    assert out.n_pieces == 1
    assert len(out.points) > block.n_points  # the notch's faces have their own nodes
    v = volumes(out.points, out.cells) * out.fraction
    assert v.sum() == pytest.approx(0.25, rel=1e-12)


def test_cells_the_blade_is_still_inside_stay_whole(block):
    full = cut_cells(block.points, block.cells, plane_x(0.47))
    part = cut_cells(block.points, block.cells, plane_x(0.47, z=(-1.0, 0.3)))
    assert 0 < part.size < full.size and set(part) <= set(full)
    centres = block.points[block.cells[part]].mean(axis=1)
    assert centres[:, 2].max() < 0.3 + 1e-12  # only cells under the blade's reach


def test_a_cut_along_mesh_faces_parts_the_block(block):
    out = virtual_node_cut(block.points, block.cells, [plane_x(0.5)])  # x = 3 / 6: mesh faces
    assert out.n_pieces == 2 and np.all(out.fraction == 1.0)
    assert cut_cells(block.points, block.cells, plane_x(0.5)).size == 0


def test_a_2d_strip_cut_across():
    strip = ts.rectangle((0.0, 0.0), (1.0, 0.2), (10, 2))
    cut = plane_x(0.53)
    out = virtual_node_cut(strip.points, strip.cells, [cut])
    assert out.n_pieces == 2
    area = volumes(out.points, out.cells)  # signed_volumes gives triangle areas in 2D
    assert (area * out.fraction).sum() == pytest.approx(0.2, rel=1e-12)


def plane_y(y0: float, x=(-1.0, 2.0)) -> PlanarCut:
    """The plane y = y0, bounded by x0..x1 (and z over the block)."""
    (x0, x1), (z0, z1) = x, (-1.0, 2.0)
    poly = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]])
    return PlanarCut(np.array([0.0, y0, 0.0]), np.array([0.0, 1.0, 0.0]), poly)


def piece_volumes(out) -> np.ndarray:
    """The material volume of each connected piece of a cut mesh, smallest first."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    k = out.cells.shape[1]
    rows = np.repeat(out.cells[:, 0], k - 1)
    n = len(out.points)
    graph = coo_matrix((np.ones(len(rows)), (rows, out.cells[:, 1:].ravel())), shape=(n, n))
    labels = connected_components(graph, directed=False)[1][out.cells[:, 0]]
    v = volumes(out.points, out.cells) * out.fraction
    return np.sort(np.bincount(labels, weights=v)[np.unique(labels)])


def test_two_cuts_through_the_same_cells_leave_the_slab_between_them(block):
    out = virtual_node_cut(block.points, block.cells, [plane_x(0.47), plane_x(0.48)])
    assert out.n_pieces == 3 and out.extra is not None
    # a cell both cross: three parts holding material (the fourth sign vector is empty)
    both = np.unique(out.parent[out.several])
    assert both.size > 0
    for e in both:
        mine = out.fraction[out.parent == e]
        assert len(mine) == 3 and mine.sum() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(piece_volumes(out), np.array([0.01, 0.47, 0.52]) * 0.25, rtol=1e-11)


def test_crossing_cuts_make_four_pieces_and_keep_every_volume(block):
    out = virtual_node_cut(block.points, block.cells, [plane_x(0.47), plane_y(0.23)])
    assert out.n_pieces == 4
    x, y = np.array([0.47, 0.53]), np.array([0.23, 0.27])
    expected = np.sort(np.outer(x, y).ravel() * 0.5)
    np.testing.assert_allclose(piece_volumes(out), expected, rtol=1e-11)
    assert np.any(np.bincount(out.parent) == 4)  # cells along the crossing: four parts
    # every copy's material at its real nodes: a node is material in some copy using it
    assert out.material_nodes[: block.n_points].all()
    c = out.constraints()
    assert set(np.unique(c.copy)) == set(np.flatnonzero(out.side != 0))


def test_a_cut_ending_at_another_parts_one_side_only(block):
    """A T: a second cut from the first one's left side to x = 0.5 (a mesh plane) splits the
    left part in two and notches the right one 0.03 deep, leaving three pieces."""
    out = virtual_node_cut(block.points, block.cells, [plane_x(0.47), plane_y(0.23, (-1, 0.5))])
    assert out.n_pieces == 3
    expected = np.sort([0.47 * 0.23 * 0.5, 0.47 * 0.27 * 0.5, 0.53 * 0.5 * 0.5])
    np.testing.assert_allclose(piece_volumes(out), expected, rtol=1e-11)


def test_crossing_cuts_in_2d_make_four_pieces():
    square = ts.rectangle((0.0, 0.0), (1.0, 1.0), (8, 8))
    cuts = [plane_x(0.43), plane_y(0.61)]
    out = virtual_node_cut(square.points, square.cells, cuts)
    assert out.n_pieces == 4
    expected = np.sort(np.outer([0.43, 0.57], [0.61, 0.39]).ravel())
    np.testing.assert_allclose(piece_volumes(out), expected, rtol=1e-11)


def test_a_blade_swept_down_through_the_block_is_a_planar_cut(block):
    cut = PlanarCut.swept_segment(
        (0.47, -1, 1.0), (0.47, 2, 1.0), (0.47, -1, -1.0), (0.47, 2, -1.0)
    )
    assert np.allclose(np.abs(cut.normal), [1.0, 0.0, 0.0])
    assert virtual_node_cut(block.points, block.cells, [cut]).n_pieces == 2
    with pytest.raises(InputError, match="not planar"):
        PlanarCut.swept_segment((0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 1))
    with pytest.raises(InputError, match="no area"):
        PlanarCut.swept_segment((0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0))


@pytest.mark.parametrize("crossing", [False, True], ids=["one cut", "crossing cuts"])
def test_a_cut_2d_strip_is_drawn_as_its_material_with_the_cut_open(tmp_path, crossing):
    """The 2D pictures draw each copy as its material part (the triangle clipped by its
    levels; where two cuts cross, by both): every drawn polygon's area is its copy's fraction
    of the triangle, so the pieces do not overlap at the cut, and the picture is written."""
    from tissuesim.render.plot2d import _cell_polygons, render_frame_png

    strip = ts.rectangle((0.0, 0.0), (1.0, 0.2), (10, 2))
    cuts = [plane_x(0.53)] + ([plane_y(0.07)] if crossing else [])
    mesh = virtual_node_cut(strip.points, strip.cells, cuts).to_mesh(strip)
    assert (mesh.cell_more_levels is not None) == crossing
    P = _cell_polygons(mesh, mesh.points)
    x, y = P[..., 0], P[..., 1]
    area = 0.5 * np.abs(np.sum(x * np.roll(y, -1, axis=1) - y * np.roll(x, -1, axis=1), axis=1))
    whole = volumes(mesh.points, mesh.cells)
    np.testing.assert_allclose(area, mesh.cell_fractions * whole, rtol=1e-12, atol=1e-15)
    assert area.sum() == pytest.approx(0.2, rel=1e-12)
    if not crossing:  # the copies of the cut x = 0.53: parts, not whole triangles
        assert np.all(np.ptp(P[mesh.cell_fractions < 1][..., 0], axis=1) < 0.08)
    png = render_frame_png(mesh, mesh.points, mesh.cell_fractions, tmp_path / "cut.png")
    assert png.stat().st_size > 1000
