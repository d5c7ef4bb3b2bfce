"""Issue 41: points embedded in a mesh by barycentric coordinates (mesh/queries/embedding.py), the
map that carries a fine visual surface with a coarse body. A barycentric map is exact for affine
motion, points outside the mesh included (their coordinates are extrapolated)."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.mesh.cells.elevate import elevate_mesh
from tissuesim.mesh.queries.embedding import embed_points

A3 = np.array([[1.1, 0.2, -0.1], [0.05, 0.9, 0.1], [0.02, -0.03, 1.2]])
B3 = np.array([0.01, 0.02, -0.03])


def _affine(x: np.ndarray, A: np.ndarray, b: np.ndarray) -> np.ndarray:
    return x @ A.T + b


@pytest.mark.parametrize(
    "mesh",
    [
        ts.ellipsoid((0, 0, 0), (0.06, 0.04, 0.02), 4),
        ts.box((0, 0, 0), (0.1, 0.05, 0.04), (3, 2, 2), element="hex"),  # flat fillers inside
        elevate_mesh(ts.box((0, 0, 0), (0.1, 0.05, 0.04), (3, 2, 2))),  # P2: its subdivision
    ],
    ids=["ellipsoid", "hex", "p2"],
)
def test_affine_motion_is_reproduced_exactly_inside_and_outside(mesh):
    rng = np.random.default_rng(1)
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    pad = 0.1 * (hi - lo)  # some points outside, by less than an element
    points = rng.uniform(lo - pad, hi + pad, (2000, 3))
    e = embed_points(mesh, points)
    assert e.outside.any() and not e.outside.all()
    np.testing.assert_allclose(e.weights.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(e.positions(mesh.points), points, atol=1e-14)  # at rest
    moved = e.positions(_affine(mesh.points, A3, B3))
    np.testing.assert_allclose(moved, _affine(points, A3, B3), atol=1e-14)


def test_inside_points_have_nonnegative_coordinates_outside_ones_a_distance():
    mesh = ts.box((0, 0, 0), (0.1, 0.05, 0.04), (4, 2, 2))
    points = np.array(
        [
            [0.05, 0.025, 0.02],  # inside
            [0.0, 0.0, 0.0],  # a corner: inside (closed)
            [0.05, 0.025, 0.043],  # 3 mm above the top face
            [0.104, 0.025, 0.02],  # 4 mm beyond the end face
            [0.103, 0.054, 0.02],  # beyond an edge: sqrt(3^2 + 4^2) = 5 mm
        ]
    )
    e = embed_points(mesh, points)
    np.testing.assert_array_equal(e.outside, [False, False, True, True, True])
    np.testing.assert_allclose(e.distance, [0, 0, 0.003, 0.004, 0.005], atol=1e-12)
    assert (e.weights[:2] >= -1e-10).all()
    assert (e.weights[2:].min(axis=1) < 0).all()  # extrapolated from the closest element
    # the carrying element owns the closest boundary facet: its vertices are near the point
    near = np.linalg.norm(mesh.points[e.vertices] - points[:, None], axis=2).min(axis=1)
    assert (near <= e.size + e.distance).all()


def test_2d_points_follow_an_affine_motion_of_triangles():
    mesh = ts.rectangle((0, 0), (0.1, 0.02), (10, 2))
    rng = np.random.default_rng(2)
    points = rng.uniform([-0.005, -0.002], [0.105, 0.022], (500, 2))
    e = embed_points(mesh, points)
    assert e.outside.any() and not e.outside.all()
    A, b = np.array([[0.9, 0.3], [-0.1, 1.1]]), np.array([0.002, -0.01])
    moved = e.positions(_affine(mesh.points, A, b))
    np.testing.assert_allclose(moved, _affine(points, A, b), atol=1e-14)
    outside = (points < [0, 0]).any(axis=1) | (points > [0.1, 0.02]).any(axis=1)
    np.testing.assert_array_equal(e.outside, outside)
    gap = np.maximum(np.maximum([0, 0] - points, points - [0.1, 0.02]), 0.0)
    np.testing.assert_allclose(e.distance, np.linalg.norm(gap, axis=1), atol=1e-12)


def test_bad_points_are_refused():
    mesh = ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    with pytest.raises(ts.InputError, match=r"\(q, 3\)"):
        embed_points(mesh, np.zeros((4, 2)))
    with pytest.raises(ts.InputError, match="finite"):
        embed_points(mesh, np.array([[np.nan, 0.0, 0.0]]))
