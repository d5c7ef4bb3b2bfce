"""The cut body's contact surface from its clipped face polygons (contact/cut/polygon_surface.py):
points closer than the merge distance are made one before the polygons are triangulated, so a
sliver polygon along a mesh edge never leaves a folded triangle; points inserted along a side
(no T-junction) get a centroid fan; a ring merged across a pinch splits into loops."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from tissuesim.contact.cut.polygon_surface import _face_junctions, _loops, polygon_surface

A, B, C, D, E = range(5)
REST = np.array([[0, 0, 0], [0, 10, 0], [-10, 0, 0], [-2.5, -1, 0], [3, 2, 0]], dtype=float)


def _point(a: int, b: int | None = None, w: float = 0.0) -> tuple[list[int], list[float]]:
    """A corner: node a, or the point at weight w from node a towards node b."""
    return [a, a if b is None else b, 0, 0], [1.0 - w, w, 0.0, 0.0]


def _arrays(polygons: list[list[tuple]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    K = max(len(p) for p in polygons)
    nodes = np.zeros((len(polygons), K, 4), dtype=np.int64)
    weights = np.zeros((len(polygons), K, 4))
    for i, polygon in enumerate(polygons):
        for j, (n, w) in enumerate(polygon):
            nodes[i, j], weights[i, j] = n, w
    return nodes, weights, np.array([len(p) for p in polygons])


def _z_areas(W, tri) -> np.ndarray:
    V = W @ REST
    return 0.5 * np.cross(V[tri[:, 1]] - V[tri[:, 0]], V[tri[:, 2]] - V[tri[:, 0]])[:, 2]


def cross2(a: np.ndarray, b: np.ndarray) -> float:
    """The z component of the cross product of two 2D vectors."""
    return float(a[0] * b[1] - a[1] * b[0])


def test_a_sliver_along_a_mesh_edge_merges_without_a_folded_triangle():
    """Flat polygons facing +z: a sliver P along edge A-B (0.2 wide at A, 4.5 long) whose side
    on A-B holds Q's point at 0.30, and a small triangle R at A whose sides are all shorter
    than the merge distance. R's points merge into one (moving A 0.15 to the left); fanning P
    from its centroid first and merging after left one fan triangle facing -z (measured on the
    arc cut through a sagging block, where it crossed a neighbour). Now every triangle faces
    +z and the area is that of the merged polygons."""
    polygons = [
        [_point(A), _point(A, B, 0.45), _point(A, C, 0.02)],  # P
        [_point(A), _point(E), _point(A, B, 0.30)],  # Q
        [_point(A), _point(A, C, 0.02), _point(A, D, 0.1)],  # R, all sides < 0.3
    ]
    W, tri = polygon_surface(5, *_arrays(polygons), REST, merge=0.3)
    area = _z_areas(W, tri)
    assert len(tri) == 2 and np.all(area > 0.0)  # P and Q, one triangle each; R collapsed
    V = W @ REST
    merged = (REST[A] + np.array([-0.2, 0, 0]) + np.array([-0.25, -0.1, 0])) / 3
    assert np.isclose(np.linalg.norm(V - merged, axis=1), 0.0).sum() == 1  # R's mean, once
    # P: (merged, AB30, AB45); Q: (merged, E, AB30), by the shoelace formula
    p = 0.5 * abs(cross2(np.array([0, 3.0]) - merged[:2], np.array([0, 4.5]) - merged[:2]))
    q = 0.5 * abs(cross2(np.array([3, 2.0]) - merged[:2], np.array([0, 3.0]) - merged[:2]))
    assert np.isclose(area.sum(), p + q)


def test_points_inserted_along_a_side_make_a_centroid_fan_without_a_t_junction():
    """Square P (A, a point on A-B, and two more) with Q's corner in the middle of P's side
    on A-B: P's ring takes it, is fanned from its centroid (inserted points lie on a line with
    the side's ends), and every triangle faces +z; nothing merges (merge distance 0)."""
    polygons = [
        [_point(A), _point(E), _point(A, B, 0.5)],  # Q on the right of A-B, corner at 0.5
        [_point(A), _point(A, B, 0.8), _point(A, C, 0.3)],  # P on the left, side A -> 0.8
    ]
    W, tri = polygon_surface(5, *_arrays(polygons), REST, merge=0.0)
    assert np.all(_z_areas(W, tri) > 0.0)
    V = W @ REST
    mid = int(np.flatnonzero(np.isclose(np.linalg.norm(V - [0, 5, 0], axis=1), 0.0))[0])
    assert (tri == mid).any(axis=1).sum() == 3  # Q's triangle and two of P's fan
    centre = np.mean([[0, 0, 0], [0, 5, 0], [0, 8, 0], [-3, 0, 0]], axis=0)
    assert np.isclose(np.linalg.norm(V - centre, axis=1), 0.0).any()  # P's centroid
    assert np.isclose(_z_areas(W, tri).sum(), 0.5 * 3 * 5 + 0.5 * 8 * 3)


def test_a_ring_that_meets_itself_splits_into_loops():
    assert _loops([1, 2, 3, 1, 4, 5]) == [[1, 2, 3], [1, 4, 5]]
    assert _loops([1, 2, 3]) == [[1, 2, 3]]
    assert _loops([1, 2, 1, 3, 4]) == [[1, 3, 4]]  # a loop of two points is no polygon


def test_points_inside_a_face_on_a_side_across_it_are_inserted_in_order():
    """A side from the middle of edge 0-1 to node 2 crosses the face (0, 1, 2): the points
    inside that face on it (t = 0.5 and 0.25 along it) go in after its first corner, nearest
    first; a point inside the face off the side, and the sides along edges, get none."""
    W = sp.csr_matrix(
        np.array(
            [
                [0.5, 0.5, 0.0],  # 0: a, on edge 0-1
                [0.0, 0.0, 1.0],  # 1: b, node 2
                [1.0, 0.0, 0.0],  # 2: c, node 0
                [0.25, 0.25, 0.5],  # 3: inside the face, halfway from a to b
                [0.375, 0.375, 0.25],  # 4: a quarter of the way
                [0.5, 0.25, 0.25],  # 5: inside the face, off the side
            ]
        )
    )
    corner = np.array([[0, 1, 2]])
    assert _face_junctions(W, corner, np.array([3]), n_edge=3) == {(0, 0): [4, 3]}
