"""Simplices split by a plane, in closed form and batched: the fraction of each simplex on one
side (``positive_fraction``), and which simplices a bounded planar cut crosses completely
(``sections_inside``). The virtual node cut (``virtual_nodes.py``) calls these for every cell
and face next to a cut at once, so cutting a 1e4-element organ costs milliseconds, not the
per-cell convex hulls it took before.

The fraction of an n-simplex where the affine function d (values d_i at its vertices) is
positive is the divided difference of t -> t_+^n over the d_i (the B-spline identity):

    f = sum_{i: d_i > 0} d_i^n / prod_{j != i} (d_i - d_j).

With one vertex alone on a side this is a product of edge ratios, t_ij = d_i / (d_i - d_j):
f = prod_j t_ij (or 1 minus it), exact and free of cancellation; a zero value gives t = 1. The
only case with two vertices on each side is a tetrahedron split 2-2; there the formula is the
divided difference (g(d_a) - g(d_b)) / (d_a - d_b) of g(x) = x^3 / ((x - d_c)(x - d_e)) over the
positive pair a, b, and g' at their midpoint when d_a and d_b agree to 1e-5 (its error there is
below 1e-10; the cancellation it avoids would be larger).
"""

from __future__ import annotations

import numpy as np

__all__ = ["positive_fraction", "section_measures", "sections_inside"]

#: relative gap below which the 2-2 divided difference is taken as a derivative
_CONFLUENT = 1e-5


def positive_fraction(d: np.ndarray) -> np.ndarray:
    """Fraction (m,) of each simplex where the linear function with vertex values d (m, n+1),
    n = 1, 2 or 3, is >= 0: 1 with no negative value (a simplex in the plane counts as on
    both sides), 0 with no positive one."""
    d = np.asarray(d, dtype=float)
    m, k = d.shape
    n = k - 1
    pos, neg = d > 0.0, d < 0.0
    n_pos, n_neg = pos.sum(axis=1), neg.sum(axis=1)
    out = np.where(n_neg == 0, 1.0, 0.0)
    split = (n_pos > 0) & (n_neg > 0)
    lone_pos = split & (n_pos == 1)
    lone_neg = split & (n_neg == 1) & ~lone_pos
    if lone_pos.any():
        out[lone_pos] = _corner(d[lone_pos], pos[lone_pos])
    if lone_neg.any():
        out[lone_neg] = 1.0 - _corner(-d[lone_neg], neg[lone_neg])
    both = split & ~lone_pos & ~lone_neg  # only a tetrahedron split 2-2
    if both.any():
        assert n == 3
        out[both] = _two_two(d[both], pos[both])
    return np.clip(out, 0.0, 1.0)


def _corner(d: np.ndarray, alone: np.ndarray) -> np.ndarray:
    """The fraction of the corner at the one vertex with d > 0 (``alone``): prod_j t_ij."""
    i = np.argmax(alone, axis=1)
    di = d[np.arange(len(d)), i][:, None]
    t = di / (di - np.where(alone, -1.0, d))  # the vertex itself: a dummy, replaced by 1
    t[alone] = 1.0
    return np.prod(t, axis=1)


def _two_two(d: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """Fraction on the positive side of tetrahedra with two vertices on each side."""
    order = np.argsort(~pos, axis=1, kind="stable")  # the positive pair first
    v = np.take_along_axis(d, order, axis=1)
    a, b, c, e = v.T
    scale = np.abs(v).max(axis=1)

    def g(x):
        return x**3 / ((x - c) * (x - e))

    def g_prime(x):
        p, q = x - c, x - e
        return (3.0 * x**2 * p * q - x**3 * (p + q)) / (p * q) ** 2

    close = np.abs(a - b) <= _CONFLUENT * scale
    safe = np.where(close, 1.0, a - b)
    return np.where(close, g_prime(0.5 * (a + b)), (g(a) - g(b)) / safe)


def sections_inside(
    x: np.ndarray, d: np.ndarray, polygon: np.ndarray, normal: np.ndarray
) -> np.ndarray:
    """Whether the plane's section of each simplex lies in the convex ``polygon`` (k, 3) of
    that plane: x (m, n+1, 3) the simplices' vertices, d (m, n+1) their distances to the plane
    (vertices on it exactly 0). The section's points are the vertices on the plane and the
    edges' crossings; each must be inside within 1e-9 of its simplex's size. Returns (m,)."""
    m, k = d.shape
    i, j = np.triu_indices(k, 1)
    di, dj = d[:, i], d[:, j]
    crosses = di * dj < 0.0
    t = np.where(crosses, di / np.where(crosses, di - dj, 1.0), 0.0)
    points = np.concatenate([x, x[:, i] + t[..., None] * (x[:, j] - x[:, i])], axis=1)
    valid = np.concatenate([d == 0.0, crosses], axis=1)  # (m, k + pairs)
    centre = polygon.mean(axis=0)
    inside = np.ones(valid.shape, dtype=bool)
    size = np.linalg.norm(x.max(axis=1) - x.min(axis=1), axis=1)  # (m,)
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
        inward = np.cross(normal, b - a)
        if inward @ (centre - a) < 0.0:
            inward = -inward
        inward = inward / np.linalg.norm(inward)
        inside &= (points - a) @ inward >= -1e-9 * size[:, None]
    return np.all(inside | ~valid, axis=1)


def section_measures(points: np.ndarray, cells: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The measure (m,) of the zero set of the linear function with vertex values ``values``
    (m, d+1) in each simplex of ``cells`` (m, d+1) over ``points`` (n, d): the area of the
    section polygon in 3D (fanned about its centroid, corners in angle order about the
    function's gradient), its length in 2D."""
    X = np.asarray(points, dtype=float)[cells]
    m, k, d = X.shape
    i, j = np.triu_indices(k, 1)
    vi, vj = values[:, i], values[:, j]
    crosses = vi * vj < 0.0
    t = np.where(crosses, vi / np.where(crosses, vi - vj, 1.0), 0.0)
    P = np.concatenate([X[:, i] + t[..., None] * (X[:, j] - X[:, i]), X], axis=1)
    valid = np.concatenate([crosses, values == 0.0], axis=1)
    if d == 2:  # a segment: its extent
        lo = np.where(valid[..., None], P, np.inf).min(axis=1)
        hi = np.where(valid[..., None], P, -np.inf).max(axis=1)
        return np.where(valid.sum(axis=1) >= 2, np.linalg.norm(hi - lo, axis=1), 0.0)
    count = valid.sum(axis=1)
    centre = np.einsum("me,med->md", valid, P) / np.maximum(count, 1)[:, None]
    edges = X[:, 1:] - X[:, :1]
    grad = np.linalg.solve(edges, (values[:, 1:] - values[:, :1])[:, :, None])[:, :, 0]
    n = grad / np.linalg.norm(grad, axis=1, keepdims=True)
    helper = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = np.cross(n, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(n, e1)
    rel = P - centre[:, None, :]
    angle = np.arctan2(np.einsum("med,md->me", rel, e2), np.einsum("med,md->me", rel, e1))
    order = np.argsort(np.where(valid, angle, np.inf), axis=1)
    Q = np.take_along_axis(rel, order[:, :, None], axis=1)
    ok = np.take_along_axis(valid, order, axis=1)
    nxt = np.where(np.arange(Q.shape[1])[None, :] + 1 < count[:, None], 1, 0)
    nxt_index = np.where(nxt == 1, np.arange(Q.shape[1])[None, :] + 1, 0)
    R = np.take_along_axis(Q, nxt_index[:, :, None], axis=1)
    tri = 0.5 * np.linalg.norm(np.cross(Q, R), axis=2)
    return np.where(count >= 3, np.where(ok, tri, 0.0).sum(axis=1), 0.0)


def region_fractions(d: np.ndarray) -> np.ndarray:
    """Fraction (r,) of each simplex where several linear functions are all >= 0: d (r, C, n+1)
    their values at the simplex's vertices (C functions; +inf values: no constraint), n = 2
    or 3. The region is a convex polytope: its vertices are enumerated (``region_vertices``)
    and its volume is their convex hull's. A cell crossed by several cuts
    (``virtual_nodes.py``) is rare (where cuts meet), so this is a loop over rows."""
    from math import factorial

    d = np.asarray(d, dtype=float)
    n = d.shape[2] - 1
    points = region_vertices(d)
    out = np.array([_hull_measure(p[:, 1:]) * factorial(n) for p in points])
    return np.clip(out, 0.0, 1.0)


def region_vertices(d: np.ndarray) -> list[np.ndarray]:
    """The vertices of each simplex's region where the linear functions d (r, C, n+1) are all
    >= 0 (+inf values: no constraint), in barycentric coordinates, one (p_i, n+1) array per
    row: every n of the simplex's faces and the functions' zero sets that meet in a point
    inside all of them."""
    from itertools import combinations

    r, C, k = d.shape
    n = k - 1
    # constraints a . y + b >= 0 on y = (l_1 .. l_n), l_0 = 1 - sum(y): the barycentric
    # coordinates themselves, then each function sum_i l_i d_i
    a = np.zeros((r, k + C, n))
    b = np.zeros((r, k + C))
    a[:, 0, :] = -1.0
    b[:, 0] = 1.0
    a[:, 1:k, :] = np.eye(n)
    finite = np.where(np.isfinite(d), d, 0.0)
    scale = np.maximum(np.abs(finite).max(axis=(1, 2)), 1e-300)[:, None]
    a[:, k:, :] = (finite[:, :, 1:] - finite[:, :, :1]) / scale[:, :, None]
    b[:, k:] = finite[:, :, 0] / scale
    points = [[] for _ in range(r)]
    for combo in combinations(range(k + C), n):
        A, B = a[:, combo, :], -b[:, combo]
        ok = np.abs(np.linalg.det(A)) > 1e-12
        y = np.zeros((r, n))
        if ok.any():
            y[ok] = np.linalg.solve(A[ok], B[ok][:, :, None])[:, :, 0]
        slack = np.einsum("rcn,rn->rc", a, y) + b
        ok &= np.all(slack >= -1e-12, axis=1)
        for i in np.flatnonzero(ok):
            points[i].append(y[i])
    out = []
    for p in points:
        y = np.array(p).reshape(-1, n)
        out.append(np.column_stack([1.0 - y.sum(axis=1), y]))
    return out


def _hull_measure(points: np.ndarray) -> float:
    """Volume (area in 2D) of the convex hull of ``points`` (p, n); 0 when flat."""
    from scipy.spatial import ConvexHull, QhullError

    if len(points) <= points.shape[1]:
        return 0.0
    try:
        return float(ConvexHull(points).volume)
    except QhullError:  # flat within round-off
        return 0.0
