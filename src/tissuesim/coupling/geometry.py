"""Batched geometry for cutting tools: swept blade surfaces, distances and segment crossings.

A blade is a polyline of k >= 2 points. Over one time step it sweeps a ruled surface, here two
triangles per blade segment; a tissue fibre (a segment between two points) is cut when it
crosses one of them. All functions take and return arrays and work on all pairs at once, in
chunks that bound memory. Lengths are in the caller's units.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from tissuesim.errors import InputError
from tissuesim.mesh.queries.locate import TriangleSoup

__all__ = ["swept_blade_triangles", "point_triangle_distance", "segments_hit_triangles"]

# Segment-triangle pairs tested at once (about 30 float arrays of this size).
_PAIRS_PER_CHUNK = 1 << 15
# Closed tests: barycentric coordinates and the segment parameter may overshoot [0, 1] by this.
_HIT_TOLERANCE = 1e-9
# Triangles with |e1 x e2| <= this * (longest edge)^2 are degenerate; segments with
# |d . n| <= this * |d| |n| are parallel to the triangle.
_DEGENERATE = 1e-12


def _array(func: str, name: str, value, shape: str, trailing: tuple[int, ...]) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{func}: {name} must be an array {shape} of numbers: {exc}") from exc
    if a.ndim != 1 + len(trailing) or a.shape[1:] != trailing:
        raise InputError(f"{func}: {name} must have shape {shape}, got {a.shape}")
    if not np.isfinite(a).all():
        raise InputError(f"{func}: {name} has non-finite values; check the positions")
    return a


def swept_blade_triangles(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """Triangles (2 (k - 1), 3, 3) of the surface a blade sweeps in one time step.

    before, after: (k, 3) blade polyline (k >= 2 points) at the start and the end of the step.
    Segment i sweeps the quad before[i], before[i+1], after[i+1], after[i], split along its
    diagonal before[i]-after[i+1] into triangles 2i and 2i+1 (consistently oriented). A blade
    that moves along itself or stands still gives zero-area triangles, which the other
    functions here handle (they never count as hit; their distance is that of their edges).
    """
    func = "swept_blade_triangles"
    b = _array(func, "before", before, "(k, 3)", (3,))
    a = _array(func, "after", after, "(k, 3)", (3,))
    if len(b) < 2:
        raise InputError(f"{func}: a blade needs k >= 2 points, got before with shape {b.shape}")
    if a.shape != b.shape:
        raise InputError(
            f"{func}: before {b.shape} and after {a.shape} must have the same shape: the same "
            f"blade points at the start and the end of the step"
        )
    first = np.stack([b[:-1], b[1:], a[1:]], axis=1)
    second = np.stack([b[:-1], a[1:], a[:-1]], axis=1)
    return np.stack([first, second], axis=1).reshape(-1, 3, 3)


def point_triangle_distance(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Distance (q,) from each of ``points`` (q, 3) to the nearest of ``triangles`` (m, 3, 3).

    Exact point-triangle distances (Voronoi regions, the kernel of
    ``tissuesim.mesh.queries.locate``) over candidate triangles from a KD-tree of centroids, chunked
    over point-triangle pairs; degenerate triangles count as their edges.
    """
    func = "point_triangle_distance"
    p = _array(func, "points", points, "(q, 3)", (3,))
    t = _array(func, "triangles", triangles, "(m, 3, 3)", (3, 3))
    if len(t) == 0:
        raise InputError(f"{func}: triangles is empty (shape {t.shape}); give at least one")
    if len(p) == 0:
        return np.zeros(0)
    return TriangleSoup(t).closest(p, with_points=False)[3]


def segments_hit_triangles(a: np.ndarray, b: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(q,) bool: whether segment a[i]-b[i] meets any of ``triangles`` (m, 3, 3).

    Moller-Trumbore with the segment parameter t in [0, 1], closed: touching counts (an
    endpoint on a triangle, the segment through a triangle's edge or vertex), with a relative
    tolerance of 1e-9 on t and the barycentric coordinates. Not hits: degenerate (zero-area)
    triangles, segments parallel to a triangle's plane (also when lying in it) and zero-length
    segments. Only triangles whose centroid lies within half the segment length plus the largest
    triangle radius of the segment's midpoint are tested (KD-tree), in chunks of pairs.
    """
    func = "segments_hit_triangles"
    a = _array(func, "a", a, "(q, 3)", (3,))
    b = _array(func, "b", b, "(q, 3)", (3,))
    tri = _array(func, "triangles", triangles, "(m, 3, 3)", (3, 3))
    if a.shape != b.shape:
        raise InputError(
            f"{func}: a {a.shape} and b {b.shape} must have the same shape: segment i runs "
            f"from a[i] to b[i]"
        )
    hit = np.zeros(len(a), dtype=bool)
    if len(a) == 0 or len(tri) == 0:
        return hit
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    n = np.cross(e1, e2)
    longest = np.max(((tri - np.roll(tri, 1, axis=1)) ** 2).sum(axis=2), axis=1)
    usable = np.flatnonzero((n**2).sum(axis=1) > (_DEGENERATE * longest) ** 2)
    if len(usable) == 0:
        return hit
    tri, e1, e2 = tri[usable], e1[usable], e2[usable]
    m = len(tri)
    centroids = tri.mean(axis=1)
    radius = float(np.sqrt(((tri - centroids[:, None]) ** 2).sum(axis=2).max()))
    d = b - a
    half = 0.5 * np.sqrt((d**2).sum(axis=1))
    # a triangle meeting the segment has its centroid within half + radius of the midpoint
    reach = (half + radius) * (1.0 + 1e-9) + 1e-300
    mid = 0.5 * (a + b)
    tree = cKDTree(centroids)
    pending = np.flatnonzero(half > 0)
    k = min(16, m)
    while len(pending):
        last = k >= m
        kk = k if last else k + 1
        dd, ii = tree.query(mid[pending], k=kk, workers=-1)
        dd, ii = dd.reshape(len(pending), kk), ii.reshape(len(pending), kk)
        cand = np.where(dd[:, :k] <= reach[pending, None], ii[:, :k], m)
        rows = max(1, _PAIRS_PER_CHUNK // k)
        for s in range(0, len(pending), rows):
            c = cand[s : s + rows]
            r, j = np.nonzero(c < m)
            t = c[r, j]
            i = pending[s + r]
            hit[i[_moller_trumbore(a[i], d[i], tri[t, 0], e1[t], e2[t])]] = True
        settled = hit[pending] | last
        if not last:
            settled |= dd[:, k] > reach[pending]
        pending = pending[~settled]
        k = min(k * 4, m)
    return hit


def _moller_trumbore(
    origin: np.ndarray, direction: np.ndarray, v0: np.ndarray, e1: np.ndarray, e2: np.ndarray
) -> np.ndarray:
    """(n,) bool: segments origin + t direction, t in [0, 1], meet triangles (v0, e1, e2)."""
    tol = _HIT_TOLERANCE
    pvec = np.cross(direction, e2)
    det = np.einsum("ni,ni->n", e1, pvec)
    # |det| = |d . (e1 x e2)| = |d| |n| |cos angle|
    scale = np.sqrt((direction**2).sum(axis=1) * (np.cross(e1, e2) ** 2).sum(axis=1))
    ok = np.abs(det) > _DEGENERATE * scale
    inv = np.divide(1.0, det, out=np.zeros_like(det), where=ok)
    tvec = origin - v0
    u = np.einsum("ni,ni->n", tvec, pvec) * inv
    qvec = np.cross(tvec, e1)
    v = np.einsum("ni,ni->n", direction, qvec) * inv
    t = np.einsum("ni,ni->n", e2, qvec) * inv
    return ok & (u >= -tol) & (v >= -tol) & (u + v <= 1.0 + tol) & (t >= -tol) & (t <= 1.0 + tol)
