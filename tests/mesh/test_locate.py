"""Closest boundary points, inside test and distance against brute force and analytic shapes."""

import numpy as np
import pytest

from tissuesim.mesh import box, ellipsoid, rectangle
from tissuesim.mesh.queries.boundary import boundary_facets
from tissuesim.mesh.queries.locate import (
    ClosestPoints,
    MeshLocator,
    closest_boundary_points,
    closest_on_triangles,
    distance_to_boundary,
    inside_mesh,
)

BOX = box((0.0, -0.5, 0.2), (1.0, 1.5, 0.7), (4, 6, 3))
ELLIPSOID = ellipsoid((0.1, 0.0, -0.2), (1.0, 0.7, 0.5), 6)


def _segment_distance(p, a, b):
    """|p - segment a-b| for p (q, 1, 3) and a, b (1, m, 3): (q, m)."""
    ab = b - a
    t = np.clip(((p - a) * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * ab - p, axis=-1)


def brute_distance(points, triangles):
    """Independent reference: plane projection if it falls inside, else the nearest edge."""
    p = points[:, None, :]
    a, b, c = (triangles[None, :, i] for i in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    h = ((p - a) * n).sum(-1)
    proj = p - h[..., None] * n
    inside = np.ones(h.shape, dtype=bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= (np.cross(v - u, proj - u) * n).sum(-1) >= 0
    edges = np.minimum(
        np.minimum(_segment_distance(p, a, b), _segment_distance(p, b, c)),
        _segment_distance(p, c, a),
    )
    return np.where(inside, np.abs(h), edges).min(axis=1)


def cloud(mesh, n, margin, seed):
    lo, hi = mesh.points.min(axis=0) - margin, mesh.points.max(axis=0) + margin
    return np.random.default_rng(seed).uniform(lo, hi, (n, 3))


@pytest.mark.parametrize("mesh", [BOX, ELLIPSOID], ids=["box", "ellipsoid"])
def test_closest_matches_brute_force(mesh):
    p = cloud(mesh, 1500, 0.5, 1)
    p = np.concatenate([p, mesh.points[:50] + 1e-3, [[30.0, -20.0, 10.0]]])  # near and far
    res = closest_boundary_points(mesh, p)
    assert isinstance(res, ClosestPoints)
    tri = mesh.points[boundary_facets(mesh.cells)]
    np.testing.assert_allclose(res.distance, brute_distance(p, tri), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(
        np.linalg.norm(p - res.positions, axis=1), res.distance, rtol=1e-12, atol=1e-14
    )
    np.testing.assert_allclose(distance_to_boundary(mesh, p), res.distance)


@pytest.mark.parametrize("mesh", [BOX, ELLIPSOID], ids=["box", "ellipsoid"])
def test_barycentric_reproduces_positions_on_a_boundary_face(mesh):
    p = cloud(mesh, 800, 0.3, 2)
    res = closest_boundary_points(mesh, p)
    b = res.barycentric
    assert res.cells.dtype == np.int64 and b.shape == (len(p), 4)
    assert (b >= 0).all()
    np.testing.assert_allclose(b.sum(axis=1), 1.0, atol=1e-14)
    assert ((b == 0).sum(axis=1) >= 1).all()
    x = mesh.points[mesh.cells[res.cells]]  # (q, 4, 3)
    np.testing.assert_allclose(np.einsum("qa,qai->qi", b, x), res.positions, atol=1e-14)
    # the closest points lie on the boundary
    np.testing.assert_allclose(distance_to_boundary(mesh, res.positions), 0.0, atol=1e-14)


def test_box_distance_is_analytic():
    lo, hi = np.array([0.0, -0.5, 0.2]), np.array([1.0, 1.5, 0.7])
    p = cloud(BOX, 2000, 1.0, 3)
    outside = np.linalg.norm(np.maximum(0, np.maximum(lo - p, p - hi)), axis=1)
    inside = np.minimum(p - lo, hi - p).min(axis=1)
    expected = np.where(outside > 0, outside, inside)
    np.testing.assert_allclose(distance_to_boundary(BOX, p), expected, atol=1e-12)


def test_inside_box_and_ellipsoid_against_analytic():
    lo, hi = np.array([0.0, -0.5, 0.2]), np.array([1.0, 1.5, 0.7])
    p = cloud(BOX, 3000, 0.4, 4)
    gap = np.minimum(np.abs(p - lo), np.abs(p - hi)).min(axis=1)
    p = p[gap > 1e-6]
    expected = ((p > lo) & (p < hi)).all(axis=1)
    np.testing.assert_array_equal(inside_mesh(BOX, p), expected)

    c, r = np.array([0.1, 0.0, -0.2]), np.array([1.0, 0.7, 0.5])
    q = cloud(ELLIPSOID, 4000, 0.3, 5)
    rho = np.sqrt((((q - c) / r) ** 2).sum(axis=1))
    got = inside_mesh(ELLIPSOID, q)
    # the mesh is inscribed: outside the ellipsoid is outside the mesh; at divisions 6 the
    # polyhedron comes within rho 0.9 of the centre nowhere
    assert not got[rho > 1.0].any()
    assert got[rho < 0.9].all()
    assert got.sum() > 0.9 * (rho < 1.0).sum()


def test_boundary_points_are_inside_at_distance_zero():
    f = boundary_facets(ELLIPSOID.cells)
    p = ELLIPSOID.points[f].mean(axis=1)
    assert inside_mesh(ELLIPSOID, p).all()
    np.testing.assert_allclose(distance_to_boundary(ELLIPSOID, p), 0.0, atol=1e-15)


def test_locator_reuse_and_single_tetrahedron():
    loc = MeshLocator(ELLIPSOID)
    p = cloud(ELLIPSOID, 200, 0.2, 6)
    np.testing.assert_array_equal(loc.inside(p), inside_mesh(ELLIPSOID, p))
    np.testing.assert_allclose(loc.distance(p), distance_to_boundary(ELLIPSOID, p))
    # max_distance: exact where within, inf beyond
    d = loc.distance(p)
    capped = loc.distance(p, max_distance=0.1)
    np.testing.assert_allclose(capped[d <= 0.1], d[d <= 0.1])
    assert np.isinf(capped[d > 0.1]).all()

    one = box(divisions=(1, 1, 1))
    tet = type(one)(points=one.points, cells=one.cells[:1], source="one tet")
    q = np.array([[0.1, 0.05, 0.01], [2.0, 2.0, 2.0], [0.9, 0.1, 0.1]])
    x = tet.points[tet.cells[0]]
    lam = np.linalg.solve(np.vstack([x.T, np.ones(4)]), np.vstack([q.T, np.ones(3)]))
    np.testing.assert_array_equal(inside_mesh(tet, q), (lam >= 0).all(axis=0))
    res = closest_boundary_points(tet, q)
    assert (res.cells == 0).all()


def test_kernel_handles_degenerate_triangles():
    p = np.array([[0.5, 1.0, 0.0], [-1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    a = np.zeros((3, 3))
    b = np.tile([1.0, 0.0, 0.0], (3, 1))
    c = np.tile([2.0, 0.0, 0.0], (3, 1))  # collinear: the segment 0..2 on the x axis
    bary, pos = closest_on_triangles(p, a, b, c)
    np.testing.assert_allclose(pos, [[0.5, 0.0, 0.0], [0.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    assert np.isfinite(bary).all() and (bary >= 0).all()
    _, pos = closest_on_triangles(p, a, a, a)  # a point
    np.testing.assert_allclose(pos, 0.0)


def test_errors_name_the_argument():
    with pytest.raises(ValueError, match=r"points must have shape \(q, 3\)"):
        inside_mesh(BOX, np.zeros((4, 2)))
    with pytest.raises(ValueError, match="for one point use"):
        distance_to_boundary(BOX, np.zeros(3))
    with pytest.raises(ValueError, match="point 1 is not finite"):
        closest_boundary_points(BOX, [[0, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(ValueError, match="2D mesh; tetrahedra are needed"):
        inside_mesh(rectangle(), np.zeros((1, 3)))
    with pytest.raises(ValueError, match="mesh must be a tissuesim Mesh"):
        distance_to_boundary(np.zeros((4, 3)), np.zeros((1, 3)))
    with pytest.raises(ValueError, match="max_distance must be a number >= 0"):
        MeshLocator(BOX).distance(np.zeros((1, 3)), max_distance=-1.0)


def test_empty_queries():
    e = np.zeros((0, 3))
    res = closest_boundary_points(BOX, e)
    assert res.cells.shape == (0,) and res.barycentric.shape == (0, 4)
    assert inside_mesh(BOX, e).shape == (0,) and distance_to_boundary(BOX, e).shape == (0,)
