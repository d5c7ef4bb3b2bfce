"""The contact boundary of a cut 2D body where cuts meet (``contact/cut/surface_2d.py`` for the
rules): a copy of a triangle several cuts cross is bounded by all its levels, so its region is
cell ∩ {level_i >= gap for every i}. Per copy edge the exposed part is that region on the edge
less what its partners (the copies holding the same two nodes) cover; a partner two cuts bound
covers an interval of the edge, and what it leaves can be two intervals. Inside each copy the
section of each level is clipped by its other levels, so a section can end inside the
triangle, where two cuts' sections meet (a point of three node weights). Segment ends are
merged by their nodes and weights, then the polylines are tidied and their short segments
merged as for one cut.

Edges far from every cut are whole boundary edges or inside; the edges and sections next to
a cut are taken one by one (a 2D cut crosses few cells)."""

from __future__ import annotations

import numpy as np

from tissuesim.contact.cut.polygon_surface import merge_weighted_points
from tissuesim.contact.cut.surface import _MERGE, _ZERO

__all__ = ["assemble", "several_boundary"]

#: the edges of a positively oriented triangle, outward, and the node opposite each (also
#: ``cut_surface_2d``'s)
_TRI_EDGES = np.array([[0, 1], [1, 2], [2, 0]])
_OPPOSITE = np.array([2, 0, 1])


def several_boundary(points: np.ndarray, cells: np.ndarray, levels: np.ndarray, gap: float):
    """Segments (s, 2 ends) of the boundary of the region, each end as (nodes (3,), weights
    (3,)) over a cell's nodes: arrays nodes (s, 2, 3), weights (s, 2, 3). ``levels`` (m, C, 3)
    each copy's levels (+inf: none), already snapped."""
    m, C, _ = levels.shape
    ends_n, ends_w = [], []
    for n, w in _edges(cells, levels, gap):
        ends_n.append(n)
        ends_w.append(w)
    for n, w in _sections(points, cells, levels, gap):
        ends_n.append(n)
        ends_w.append(w)
    if not ends_n:
        return np.zeros((0, 2, 3), dtype=np.int64), np.zeros((0, 2, 3))
    return np.array(ends_n), np.array(ends_w)


def _edges(cells, levels, gap):
    """The exposed intervals of every copy edge, as segment ends over the edge's two nodes."""
    m, C, _ = levels.shape
    enodes = cells[:, _TRI_EDGES].reshape(-1, 2)  # (3m, 2), outward
    elev = levels[:, :, _TRI_EDGES].transpose(0, 2, 1, 3).reshape(3 * m, C, 2)
    opposite = levels[:, :, _OPPOSITE].transpose(0, 2, 1).reshape(3 * m, C)
    finite = np.all(np.isfinite(elev), axis=2)
    hollow = np.any(finite & np.all(elev == gap, axis=2) & (opposite < gap), axis=1)
    key = np.sort(enodes, axis=1)
    _, group, size = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    group = group.ravel()
    near = np.bincount(group, weights=finite.any(axis=1), minlength=len(size)) > 0
    for e in np.flatnonzero(~near[group] & (size[group] == 1)):  # far from cuts: whole
        a, b = enodes[e]
        yield np.array([[a, b, b], [a, b, b]]), np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    members: dict = {}
    for e in np.flatnonzero(near[group]):
        members.setdefault(int(group[e]), []).append(int(e))
    for e in np.flatnonzero(near[group]):
        if hollow[e]:
            continue
        mine = [i for i in range(C) if finite[e, i]]
        a, b = enodes[e]
        spans = [(0.0, 1.0)]
        for i in mine:  # own levels: where each is >= gap
            spans = _keep(spans, elev[e, i] - gap)
        for p in members[int(group[e])]:
            if p == e or hollow[p]:
                continue
            # the partner's levels along this edge (its nodes may be the other way round)
            flip = enodes[p, 0] != a
            lev = [elev[p, i][::-1] if flip else elev[p, i] for i in range(C) if finite[p, i]]
            left = [
                v
                for v in lev
                if not np.all(v >= gap)
                and not any(np.allclose(v, elev[e, i], rtol=1e-9, atol=1e-12 * gap) for i in mine)
            ]
            if not lev:
                spans = []  # a whole partner covers the edge
            elif len(lev) == 1 and len(left) == 1:
                spans = _keep(spans, gap - left[0])  # as for one cut
            elif not left:
                spans = []
            else:  # less the interval where all its other levels are >= gap
                cover = [(0.0, 1.0)]
                for v in left:
                    cover = _keep(cover, v - gap)
                spans = _less(spans, cover)
        for s0, s1 in spans:
            if s1 - s0 > _MERGE:
                yield (
                    np.array([[a, b, b], [a, b, b]]),
                    np.array([[1.0 - s0, s0, 0.0], [1.0 - s1, s1, 0.0]]),
                )


def _keep(spans: list, v: np.ndarray) -> list:
    """The parts of the intervals (of t along an edge) where v0 (1 - t) + v1 t >= 0."""
    v0, v1 = float(v[0]), float(v[1])
    if v0 >= 0.0 and v1 >= 0.0:
        return spans
    if v0 < 0.0 and v1 < 0.0:
        return []
    root = v0 / (v0 - v1)
    lo, hi = (root, 1.0) if v0 < 0.0 else (0.0, root)
    return [(max(a, lo), min(b, hi)) for a, b in spans if min(b, hi) > max(a, lo)]


def _less(spans: list, cover: list) -> list:
    """The intervals less the (at most one) interval ``cover``."""
    if not cover:
        return spans
    c0, c1 = cover[0]
    out = []
    for a, b in spans:
        if c0 > a:
            out.append((a, min(b, c0)))
        if c1 < b:
            out.append((max(a, c1), b))
    return [(a, b) for a, b in out if b > a]


def _sections(points, cells, levels, gap):
    """Inside each copy, the section of each of its levels, clipped by its other levels, with
    the region on its left (outward normal (dy, -dx) along -grad level)."""
    m, C, _ = levels.shape
    for c in np.flatnonzero(np.isfinite(levels[:, :, 0]).any(axis=1)):
        X = points[cells[c]]
        for i in range(C):
            v = levels[c, i] - gap
            if not np.all(np.isfinite(v)) or not (v.max() > 0.0 and v.min() < 0.0):
                continue
            ends = []
            for a, b in _TRI_EDGES:
                if v[a] * v[b] < 0.0:
                    t = v[a] / (v[a] - v[b])
                    w = np.zeros(3)
                    w[a], w[b] = 1.0 - t, t
                    ends.append(w)
            for k in range(3):
                if v[k] == 0.0:
                    w = np.zeros(3)
                    w[k] = 1.0
                    ends.append(w)
            if len(ends) != 2:
                continue
            p, q = ends
            grad = np.linalg.solve(X[1:] - X[:1], v[1:] - v[:1])
            d = (q - p) @ X
            if d[1] * grad[0] - d[0] * grad[1] > 0.0:
                p, q = q, p
            for j in range(C):  # clipped by the copy's other levels
                if j == i or not np.all(np.isfinite(levels[c, j])):
                    continue
                u = levels[c, j] - gap
                up, uq = p @ u, q @ u
                if up < 0.0 and uq < 0.0:
                    p = None
                    break
                if up < 0.0 or uq < 0.0:
                    t = up / (up - uq)
                    cut = (1.0 - t) * p + t * q
                    p, q = (cut, q) if up < 0.0 else (p, cut)
            if p is not None and np.abs(q - p).max() > _MERGE:
                nodes = np.broadcast_to(cells[c], (2, 3))
                yield nodes.copy(), np.array([p, q])


def assemble(n_points: int, nodes: np.ndarray, weights: np.ndarray):
    """Segment ends (s, 2, 3) nodes and weights -> (W (k, n_points), segments (s, 2)): ends
    with the same nodes and weights (to _MERGE) are one point."""
    w = np.where(weights.reshape(-1, 3) > _ZERO, weights.reshape(-1, 3), 0.0)
    w /= w.sum(axis=1, keepdims=True)
    point, W = merge_weighted_points(nodes.reshape(-1, 3), w, 0, n_points)
    return W, point.reshape(-1, 2)
