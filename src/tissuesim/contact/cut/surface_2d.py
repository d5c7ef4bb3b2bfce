"""The contact boundary of a cut 2D body (P1 triangles): the 2D counterpart of
``contact/cut/surface.py``, with the same rules (read its docstring): each side's cut edge follows
the level set ``level = gap`` (gap = GAP dhat) of its copy's material level
(``Mesh.cell_levels``), node levels within SNAP_IN dhat above or SNAP_OUT dhat below it are put
on it, and points closer than MERGE dhat at rest are one point. So the two sides of a fresh cut
start 2 gap apart (at least 2 (GAP - SNAP_OUT) dhat) and their barrier keeps them apart.

The contact region is the union over copies of cell ∩ {level >= gap}. Its boundary, per edge F
of a copy c whose *partners* are the other copies holding the same two nodes:

    exposed(c, F) = F ∩ {level_c >= gap} ∩ (for each partner p) {level_p <= gap},

an interval of the edge (every constraint is linear along it), plus, inside each copy its level
set crosses, the section {level_c = gap}: a segment between two points on its edges. Segment
ends are nodes or points on mesh edges, merged by (edge, weight), so the polylines are closed.
An edge whose both node levels are exactly gap bounds its copy's region only where the copy's
third node is at gap or above (else that region is the edge alone, and the copy leaves it out),
and an edge two copies both give, in opposite directions, is inside the region (dropped).
Segments run with the region on their left (outward normal (dy, -dx), the 2D convention of
``mesh/queries/boundary.py`` that the contact model passes to ipctk as (k, 2) edges).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from tissuesim.contact.cut.boundary_several import _OPPOSITE, _TRI_EDGES, assemble, several_boundary
from tissuesim.contact.cut.surface import (
    _MERGE,
    _ZERO,
    GAP,
    MERGE,
    SNAP_IN,
    SNAP_OUT,
    level_stack,
)
from tissuesim.errors import InputError
from tissuesim.mesh.rows import unique_rows

__all__ = ["cut_boundary"]


def cut_boundary(mesh, dhat: float) -> tuple[sp.csr_matrix, np.ndarray]:
    """(W, edges): the boundary points as rows of node weights W (k, n_points), V = W @ X for
    node positions X (n_points, 2), and the boundary segments (s, 2) over them, each with the
    region on its left, of a cut 2D P1 mesh (``mesh.cell_levels`` set), for a barrier of
    activation distance ``dhat`` (m): the cut edges GAP dhat inside each side, the same snapping
    (SNAP_IN, SNAP_OUT) and merging (MERGE) as the 3D surface (``cut_surface``)."""
    if mesh.dim != 2 or mesh.cells.shape[1] != 3:
        raise InputError("cut_boundary: a 2D mesh of P1 triangles is needed; use cut_surface in 3D")
    gap = GAP * dhat
    cells, levels = mesh.cells, level_stack(mesh)
    snap = (levels >= gap - SNAP_OUT * dhat) & (levels <= gap + SNAP_IN * dhat)
    levels = np.where(snap, gap, levels)
    if levels.shape[1] > 1:  # where cuts meet: every copy bounded by all its levels
        nodes, weights = several_boundary(mesh.points, cells, levels, gap)
        W, seg = assemble(mesh.n_points, nodes, weights)
        W, seg = _tidy(W, seg)
        return _cluster(W, seg, mesh.points, MERGE * dhat)
    levels = levels[:, 0]
    ends = [_exposed_edges(cells, levels, gap), _sections(mesh.points, cells, levels, gap)]
    lo, hi, w = (np.concatenate([e[i] for e in ends]) for i in range(3))  # (s, 2) each
    W, seg = _assemble(mesh.n_points, lo, hi, w)
    return _cluster(W, seg, mesh.points, MERGE * dhat)


def _exposed_edges(cells: np.ndarray, levels: np.ndarray, gap: float):
    """Every copy edge's exposed interval, as its two ends (from, to) in outward order, each end
    (lo node, hi node, weight of hi) on the edge's sorted nodes: three (s, 2) arrays."""
    m = len(cells)
    enodes = cells[:, _TRI_EDGES].reshape(-1, 2)  # (3m, 2), outward order
    elev = levels[:, _TRI_EDGES].reshape(-1, 2)
    opposite = levels[:, _OPPOSITE].ravel()
    swap = enodes[:, 0] > enodes[:, 1]
    snodes = np.where(swap[:, None], enodes[:, ::-1], enodes)  # sorted: lo, hi
    slev = np.where(swap[:, None], elev[:, ::-1], elev)
    _, group, size = unique_rows(snodes, return_inverse=True, return_counts=True)
    by_group = np.argsort(group, kind="stable")
    start = np.concatenate([[0], np.cumsum(size)])
    # the interval [s0, s1] of the sorted edge (s = weight of hi) where every constraint >= 0
    s0, s1 = np.zeros(3 * m), np.ones(3 * m)
    empty = np.zeros(3 * m, dtype=bool)

    def constrain(u: np.ndarray) -> None:
        nonlocal s0, s1, empty
        u = np.where(np.isposinf(u), 1.0, np.where(np.isneginf(u), -1.0, u))
        u0, u1 = u[:, 0], u[:, 1]
        root = u0 / np.where(u0 != u1, u0 - u1, 1.0)
        empty |= (u0 < 0.0) & (u1 < 0.0)
        s1 = np.where((u0 >= 0.0) & (u1 < 0.0), np.minimum(s1, root), s1)
        s0 = np.where((u0 < 0.0) & (u1 >= 0.0), np.maximum(s0, root), s0)

    constrain(slev - gap)
    for j in range(int(size.max(initial=1))):  # the j-th member of each edge's group
        has = j < size[group]
        member = np.where(has, by_group[np.minimum(start[group] + j, len(by_group) - 1)], 0)
        other = has & (member != np.arange(3 * m))
        constrain(np.where(other[:, None], gap - slev[member], np.inf))  # inf: no constraint
    # an edge at gap all along bounds an area of its copy only if the third node is not below
    flat = np.all(slev == gap, axis=1) & (opposite < gap)
    keep = ~empty & ~flat & (s1 - s0 > _MERGE)
    lo, hi = snodes[keep, 0], snodes[keep, 1]
    w = np.column_stack([s0[keep], s1[keep]])
    w = np.where(swap[keep, None], w[:, ::-1], w)  # outward: from the edge's first node
    return np.column_stack([lo, lo]), np.column_stack([hi, hi]), w


def _sections(points: np.ndarray, cells: np.ndarray, levels: np.ndarray, gap: float):
    """The level set {level = gap} in each copy it crosses, as segments with the region
    (level >= gap) on their left: their ends (lo, hi, weight of hi), three (c, 2) arrays."""
    v = levels - gap
    crossed = np.all(np.isfinite(v), axis=1) & (v.max(axis=1) > 0.0) & (v.min(axis=1) < 0.0)
    idx = np.flatnonzero(crossed)
    c, v = cells[idx], v[idx]
    a, b = _TRI_EDGES[:, 0], _TRI_EDGES[:, 1]
    va, vb = v[:, a], v[:, b]
    hit = va * vb < 0.0  # (c, 3)
    t = np.where(hit, va / np.where(hit, va - vb, 1.0), 0.0)  # weight of b
    na, nb = c[:, a], c[:, b]
    # candidates: the three edges' crossings, then the three nodes on the level set
    lo = np.concatenate([np.minimum(na, nb), c], axis=1)
    hi = np.concatenate([np.maximum(na, nb), c], axis=1)
    w = np.concatenate([np.where(nb > na, t, 1.0 - t), np.zeros_like(v)], axis=1)
    hit = np.concatenate([hit, v == 0.0], axis=1)
    pick = np.argsort(~hit, axis=1, kind="stable")[:, :2]  # exactly two hits in a crossed copy
    lo, hi, w = (np.take_along_axis(x, pick, axis=1) for x in (lo, hi, w))
    # orientation: the outward normal (dy, -dx) along -grad level (out of level >= gap)
    X = points[c]  # (c, 3, 2)
    grad = np.linalg.solve(X[:, 1:] - X[:, :1], (v[:, 1:] - v[:, :1])[:, :, None])[:, :, 0]
    P = (1.0 - w)[:, :, None] * points[lo] + w[:, :, None] * points[hi]  # (c, 2, 2)
    d = P[:, 1] - P[:, 0]
    flip = d[:, 1] * grad[:, 0] - d[:, 0] * grad[:, 1] > 0.0
    lo, hi, w = (np.where(flip[:, None], x[:, ::-1], x) for x in (lo, hi, w))
    return lo, hi, w


def _assemble(n_points: int, lo: np.ndarray, hi: np.ndarray, w: np.ndarray):
    """Segments given by their ends (lo, hi, weight of hi) (s, 2) -> points W (k, n_points)
    and segments (s', 2) over them: ends on one mesh edge with the same weight (to _MERGE) are
    one point (a node: weight 0 on itself), degenerate segments and pairs of opposite ones
    (the edge between two copies whose regions both reach it) dropped."""
    lo, hi, w = lo.ravel(), hi.ravel(), w.ravel()
    at_lo, at_hi = w <= _ZERO, w >= 1.0 - _ZERO
    lo = np.where(at_hi, hi, lo)
    hi = np.where(at_lo, lo, hi)
    w = np.where(at_lo | at_hi, 0.0, w)
    order = np.lexsort((w, hi, lo))
    new = np.ones(order.size, dtype=bool)
    new[1:] = (
        (lo[order][1:] != lo[order][:-1])
        | (hi[order][1:] != hi[order][:-1])
        | (np.diff(w[order]) > _MERGE)
    )
    label = np.empty(order.size, dtype=np.int64)
    label[order] = np.cumsum(new) - 1
    first = order[new]
    k = first.size
    W = sp.csr_matrix(
        (
            np.column_stack([1.0 - w[first], w[first]]).ravel(),
            (np.repeat(np.arange(k), 2), np.column_stack([lo[first], hi[first]]).ravel()),
        ),
        shape=(k, n_points),
    )
    W.eliminate_zeros()
    return _tidy(W, label.reshape(-1, 2))


def _tidy(W: sp.csr_matrix, seg: np.ndarray):
    """Degenerate segments and opposite pairs dropped, unused points left out."""
    seg = seg[seg[:, 0] != seg[:, 1]]
    k = W.shape[0]
    forward, backward = seg[:, 0] * k + seg[:, 1], seg[:, 1] * k + seg[:, 0]
    seg = seg[~np.isin(backward, forward)]
    used = np.unique(seg)
    local = np.full(k, -1)
    local[used] = np.arange(used.size)
    return W[used], local[seg]


def _cluster(W: sp.csr_matrix, seg: np.ndarray, rest: np.ndarray, merge: float):
    """Points joined by a segment shorter than ``merge`` at rest made one, at their mean (as in
    3D: where the body was cut the level is affine in the node positions, so the mean keeps it)."""
    from scipy.sparse.csgraph import connected_components

    if merge <= 0.0 or len(seg) == 0:
        return W, seg
    V = W @ rest
    pairs = seg[np.linalg.norm(V[seg[:, 0]] - V[seg[:, 1]], axis=1) < merge]
    if len(pairs) == 0:
        return W, seg
    k = len(V)
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(k, k))
    n, label = connected_components(graph, directed=False)
    size = np.bincount(label, minlength=n)
    average = sp.csr_matrix((1.0 / size[label], (label, np.arange(k))), shape=(n, k))
    return _tidy((average @ W).tocsr(), label[seg])
