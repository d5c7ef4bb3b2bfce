"""Convex polygons clipped by linear functions, batched (Sutherland-Hodgman, one corner slot at
a time over all polygons), their corners as weights over the nodes they live on: the cut
body's contact surface (``contact/cut/surface.py``) and the face parts where cuts meet
(``mesh/cutting/node_groups.py``) clip this way."""

from __future__ import annotations

import numpy as np

__all__ = ["clip_polygons", "polygon_measures"]


def clip_polygons(W: np.ndarray, count: np.ndarray, values: np.ndarray):
    """Convex polygons (corners as weights W (p, K, n) over n nodes, ``count`` (p,) corners)
    clipped to where the linear function with node values ``values`` (p, n) is >= 0
    (Sutherland-Hodgman, one corner slot at a time over all polygons)."""
    p, K, n = W.shape
    val = np.einsum("pkn,pn->pk", W, values)
    out = np.zeros_like(W)
    got = np.zeros(p, dtype=np.int64)
    rows = np.arange(p)
    for i in range(K):
        active = i < count
        nxt = np.where(i + 1 < count, i + 1, 0)
        a, b = W[:, i], W[rows, nxt]
        va, vb = val[:, i], val[rows, nxt]
        inside = active & (va >= 0.0)
        put = np.minimum(got, K - 1)
        out[rows[inside], put[inside]] = a[inside]
        got = got + inside
        cross = active & ((va >= 0.0) != (vb >= 0.0))
        t = np.where(cross, va / np.where(cross, va - vb, 1.0), 0.0)
        put = np.minimum(got, K - 1)
        out[rows[cross], put[cross]] = a[cross] + t[cross, None] * (b[cross] - a[cross])
        got = got + cross
    return out, np.minimum(got, K)


def polygon_measures(W: np.ndarray, count: np.ndarray, X: np.ndarray) -> np.ndarray:
    """The area (p,) of convex polygons with corners W (p, K, n) weights over the n points X
    (p, n, 3) (``count`` (p,) corners each); with n = 2 (a mesh edge, in 2D) the length of
    what is left of the edge."""
    P = np.einsum("pkn,pnd->pkd", W, X)
    p, K, _ = W.shape
    valid = np.arange(K)[None, :] < count[:, None]
    if X.shape[1] == 2:  # an edge: the extent of its clipped points
        lo = np.where(valid[..., None], P, np.inf).min(axis=1)
        hi = np.where(valid[..., None], P, -np.inf).max(axis=1)
        return np.where(count >= 2, np.linalg.norm(hi - lo, axis=1), 0.0)
    rel = P - P[:, :1]
    nxt = np.where(np.arange(K)[None, :] + 1 < count[:, None], np.arange(K) + 1, 0)
    R = np.take_along_axis(rel, nxt[:, :, None], axis=1)
    fan = np.where(valid[..., None], np.cross(rel, R), 0.0).sum(axis=1)
    return np.where(count >= 3, 0.5 * np.linalg.norm(fan, axis=1), 0.0)
