"""Clipped face polygons -> one watertight triangle surface (the cut body's contact surface,
``contact/cut/surface.py``): every surface point a fixed weighting of mesh nodes.

1. Corners are points on mesh edges (or nodes): corners on one edge with the same weight are
   one point.
2. A polygon side along a mesh edge that holds other polygons' points between its ends gets
   them inserted (no T-junction: IPC would see a point at zero distance from a triangle it is
   not a vertex of).
3. Points joined by a polygon side shorter than ``merge`` at rest are made one, at their mean
   (weights averaged): the level set passes within dhat of nodes near the cut's plane in a
   star of points dhat apart, which IPC's barrier would push apart at rest. Where the body
   was cut the level is an affine function of the node positions, so the mean keeps the
   level exactly.
4. Only then are the polygons triangulated, over their merged corners: a polygon left with
   three corners is one triangle; one with inserted points is fanned from the centroid of its
   corners, the others from their first corner.

Merging before triangulating matters: a sliver polygon (a level set passing along a mesh edge)
fanned first and merged after could have its fan's apex left on the wrong side of corners that
merged, and the folded triangles crossed their neighbours (measured on an arc cut through a
sagging block: one edge through one face, all within 0.1 mm).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from tissuesim.mesh.rows import row_keys, unique_rows

__all__ = ["merge_weighted_points", "polygon_surface"]

#: weights below this are round-off (a point on an edge has two, a node one)
_ZERO = 1e-12
#: points on one mesh edge closer than this (in weight) are one point
_MERGE = 1e-9


def polygon_surface(
    n_points: int,
    nodes: np.ndarray,
    weights: np.ndarray,
    count: np.ndarray,
    rest: np.ndarray,
    merge: float,
) -> tuple[sp.csr_matrix, np.ndarray]:
    """(W (k, n_points), triangles (t, 3)) of the polygons whose corners are weights
    ``weights`` (p, K, 4) over ``nodes`` (p, K, 4) (a node, a point on a mesh edge, or, where
    two cuts meet, a point inside a face of a cell), ``count`` (p,) corners each, in outward
    order; ``rest`` the node positions at rest (n_points, 3), ``merge`` the distance (m) under
    which points are made one."""
    p_lo, p_hi, p_w, corner, count, lo, hi, W_face = _points(nodes, weights, count, n_points)
    edge = np.flatnonzero(p_lo >= 0)  # nodes and points on mesh edges; then points in faces
    W = sp.csr_matrix(
        (
            np.column_stack([1.0 - p_w[edge], p_w[edge]]).ravel(),  # a node: lo == hi, 1 in all
            (np.repeat(edge, 2), np.column_stack([p_lo[edge], p_hi[edge]]).ravel()),
        ),
        shape=(len(p_lo), n_points),
    )
    if W_face is not None:
        W = (W + W_face).tocsr()
    inserts = _face_junctions(W, corner, count, len(edge))
    ring, size, mended = _rings(n_points, corner, count, lo, hi, p_lo, p_hi, p_w, inserts)
    label, W = _merge(W, ring, size, rest, merge)
    ring = np.where(ring >= 0, label[np.maximum(ring, 0)], -1)
    ring, size, mended = _distinct(ring, size, mended)
    W, tri = _triangulate(W, ring, size, mended)
    tri = tri[(tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])]
    # a face and its reverse cancel (two sides of a collapsed sliver)
    _, inverse, times = unique_rows(np.sort(tri, axis=1), return_inverse=True, return_counts=True)
    tri = tri[times[inverse] == 1]
    used = np.unique(tri)
    local = np.full(W.shape[0], -1)
    local[used] = np.arange(used.size)
    return W[used], local[tri]


def _points(nodes: np.ndarray, weights: np.ndarray, count: np.ndarray, n_points: int):
    """The polygons' points: corners on one mesh edge with the same weight (to _MERGE) are one
    point, and so are corners inside one face with the same weights (where two cuts meet).
    Returns each point's edge (p_lo, p_hi; a node: both the same; -1 for a point inside a
    face) and weight of p_hi, then the polygons' corners as points (P, K) (-1 padding, a
    corner repeated by its neighbour dropped), their counts, each corner's edge (lo, hi; -1
    inside a face), and the weights of the points inside faces (rows of a (points,
    n_points) matrix, None when there are none)."""
    P, K, _ = weights.shape
    weights = np.where(weights > _ZERO, weights, 0.0)
    weights /= np.maximum(weights.sum(axis=2, keepdims=True), 1e-300)
    valid = np.arange(K)[None, :] < count[:, None]
    in_face = valid & (np.count_nonzero(weights, axis=2) > 2)
    # each corner: its (up to two) nodes and the weight of the larger-numbered one
    big = np.argsort(-weights, axis=2)[:, :, :2]  # the two largest weights
    w2 = np.take_along_axis(weights, big, axis=2)
    n2 = np.take_along_axis(nodes, big, axis=2)
    single = w2[:, :, 1] <= 0.0
    n2[:, :, 1] = np.where(single, n2[:, :, 0], n2[:, :, 1])
    lo, hi = n2.min(axis=2), n2.max(axis=2)
    w_hi = np.where(single, 0.0, np.where(n2[:, :, 0] == hi, w2[:, :, 0], w2[:, :, 1]))
    lo[in_face], hi[in_face], w_hi[in_face] = -1, -1, 0.0
    on_edge = valid & ~in_face
    vlo, vhi, vw = lo[on_edge], hi[on_edge], w_hi[on_edge]
    # merge: sort by (edge, weight); a new point where the edge changes or the weight jumps
    order = np.lexsort((vw, vhi, vlo))
    new = np.ones(order.size, dtype=bool)
    new[1:] = (
        (vlo[order][1:] != vlo[order][:-1])
        | (vhi[order][1:] != vhi[order][:-1])
        | (np.diff(vw[order]) > _MERGE)
    )
    label = np.cumsum(new) - 1
    point = np.empty(order.size, dtype=np.int64)
    point[order] = label
    corner = np.full((P, K), -1)
    corner[on_edge] = point
    first = order[new]
    p_lo, p_hi, p_w = vlo[first], vhi[first], vw[first]
    W_face = None
    if in_face.any():  # few: where two cuts meet
        face_point, W_face = merge_weighted_points(
            nodes[in_face], weights[in_face], len(p_lo), n_points
        )
        corner[in_face] = face_point
        extra = W_face.shape[0] - len(p_lo)
        p_lo = np.concatenate([p_lo, np.full(extra, -1)])
        p_hi = np.concatenate([p_hi, np.full(extra, -1)])
        p_w = np.concatenate([p_w, np.zeros(extra)])
    # corners that merged with their neighbour are one corner; a polygon left with fewer than
    # three is empty (a face between copies whose regions only touch along a line)
    prev = np.where(np.arange(K)[None, :] == 0, np.maximum(count[:, None] - 1, 0), np.arange(K) - 1)
    repeat = valid & (corner == np.take_along_axis(corner, prev, axis=1))
    keep_corner = valid & ~repeat
    slot = np.cumsum(keep_corner, axis=1) - 1
    packed = np.full((P, K), -1)
    r, c = np.nonzero(keep_corner)
    packed[r, slot[r, c]] = corner[r, c]
    packed_lo, packed_hi = np.full((P, K), -1, np.int64), np.full((P, K), -1, np.int64)
    packed_lo[r, slot[r, c]] = lo[r, c]
    packed_hi[r, slot[r, c]] = hi[r, c]
    return p_lo, p_hi, p_w, packed, keep_corner.sum(axis=1), packed_lo, packed_hi, W_face


def merge_weighted_points(nodes: np.ndarray, weights: np.ndarray, start: int, n_points: int):
    """Points given as weights (c, k) over ``nodes`` (c, k) merged by (nodes, weights to
    _MERGE): each one's point index from ``start`` on, and the merged points' weights as rows
    (start + new points, n_points) of a matrix, the first ``start`` rows empty."""
    k = nodes.shape[1]
    order = np.argsort(np.where(weights > 0.0, nodes, n_points), axis=1)  # support first
    n = np.take_along_axis(nodes, order, axis=1)
    w = np.take_along_axis(weights, order, axis=1)
    n = np.where(w > 0.0, n, -1)
    keys = np.column_stack([n, w])
    by = np.lexsort(keys.T[::-1])
    ks = keys[by]
    new = np.ones(len(ks), dtype=bool)
    new[1:] = np.any(ks[1:, :k] != ks[:-1, :k], axis=1) | np.any(
        np.abs(ks[1:, k:] - ks[:-1, k:]) > _MERGE, axis=1
    )
    label = np.cumsum(new) - 1
    point = np.empty(len(ks), dtype=np.int64)
    point[by] = start + label
    first = by[new]
    rows = np.repeat(start + np.arange(len(first)), k)
    cols, vals = n[first].ravel(), w[first].ravel()
    keep = cols >= 0
    W = sp.csr_matrix((vals[keep], (rows[keep], cols[keep])), shape=(start + len(first), n_points))
    return point, W


def _face_junctions(W: sp.csr_matrix, corner: np.ndarray, count: np.ndarray, n_edge: int):
    """{(polygon, side i): points to insert between its corners i and i+1, in order}: a
    polygon side across a face of a cell (its ends' nodes three) that passes through points
    inside that face (where two cuts meet, the sections and faces of the parts on either
    side of one cut end there), so that no T-junction is left. In array passes: where cuts
    nearly coincide there are thousands of such points."""
    if W.shape[0] == n_edge:
        return {}
    P, K = corner.shape
    support = (W != 0).astype(np.int8).tocsr()
    support.sort_indices()
    # the points inside faces, by the face's three nodes (sorted)
    q = np.arange(n_edge, W.shape[0])
    q = q[np.diff(support.indptr)[q] == 3]
    if not len(q):
        return {}
    q_nodes = support.indices[support.indptr[q][:, None] + np.arange(3)]
    # polygon sides whose two ends span three nodes: across a face
    valid = np.arange(K)[None, :] < count[:, None]
    nxt = np.where(np.arange(K)[None, :] + 1 < count[:, None], np.arange(K) + 1, 0)
    pr, pc = np.nonzero(valid)
    a, b = corner[pr, pc], corner[pr, nxt[pr, pc]]
    union = ((support[a] + support[b]) != 0).tocsr()
    union.sort_indices()
    three = np.flatnonzero(np.diff(union.indptr) == 3)
    s_nodes = union.indices[union.indptr[three][:, None] + np.arange(3)]
    # each side against the points inside its face: joined on the face's key
    keys = row_keys(np.concatenate([q_nodes, s_nodes]))
    if keys is None:  # node numbers too wide for one key: rank the rows instead
        keys = unique_rows(np.concatenate([q_nodes, s_nodes]), return_inverse=True)[1]
    q_key, s_key = keys[: len(q)], keys[len(q) :]
    by = np.argsort(q_key, kind="stable")
    first = np.searchsorted(q_key[by], s_key)
    last = np.searchsorted(q_key[by], s_key, "right")
    n = last - first
    side = np.repeat(np.arange(len(three)), n)
    point = by[np.repeat(first, n) + np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)]
    s_id = three[side]
    qq = q[point]
    keep = (qq != a[s_id]) & (qq != b[s_id])
    side, s_id, qq = side[keep], s_id[keep], qq[keep]
    if not len(side):
        return {}
    cols = s_nodes[side]  # (c, 3)

    def weights(rows: np.ndarray) -> np.ndarray:
        return np.asarray(W[np.repeat(rows, 3), cols.ravel()]).reshape(-1, 3)

    wa, wb, wq = weights(a[s_id]), weights(b[s_id]), weights(qq)
    d = wb - wa
    dd = np.einsum("ij,ij->i", d, d)
    t = np.einsum("ij,ij->i", wq - wa, d) / np.where(dd > 0.0, dd, 1.0)
    off = np.abs(wa + t[:, None] * d - wq).max(axis=1)
    hit = (dd > 0.0) & (t > _MERGE) & (t < 1.0 - _MERGE) & (off <= 1e-9)
    s_id, t, qq = s_id[hit], t[hit], qq[hit]
    order = np.lexsort((t, s_id))
    out: dict = {}
    for s_, q_ in zip(s_id[order].tolist(), qq[order].tolist(), strict=True):
        out.setdefault((int(pr[s_]), int(pc[s_])), []).append(q_)
    return out


def _rings(n_points, corner, count, lo, hi, p_lo, p_hi, p_w, inserts: dict):
    """Each polygon's ring of points (R, L) (-1 padding), its size (R,), and whether it got
    points inserted along a side (``mended``: it is fanned from its centroid, since inserted
    points lie on a line with its corners); polygons with fewer than three corners dropped.
    ``inserts``: points to insert along sides across faces (``_face_junctions``)."""
    P, K = corner.shape
    valid = np.arange(K)[None, :] < count[:, None]
    alive = count >= 3
    # points strictly inside mesh edges, sorted by (edge key, weight): an edge's run of them
    inner = np.flatnonzero(p_lo != p_hi)
    inner_key = p_lo[inner] * n_points + p_hi[inner]
    by_edge = inner[np.lexsort((p_w[inner], inner_key))]
    sorted_key = p_lo[by_edge] * n_points + p_hi[by_edge]
    split = np.zeros((P, K), dtype=bool)  # polygon side i -> i+1 lies along a split mesh edge
    if len(inner):
        nxt = np.where(np.arange(K)[None, :] + 1 < count[:, None], np.arange(K) + 1, 0)
        b_lo = np.take_along_axis(lo, nxt, axis=1)
        b_hi = np.take_along_axis(hi, nxt, axis=1)
        ends = np.stack([lo, hi, b_lo, b_hi], axis=2)
        e_lo, e_hi = ends.min(axis=2), ends.max(axis=2)
        # along one mesh edge: both corners' nodes within {e_lo, e_hi}, and two nodes in all
        along = np.all((ends == e_lo[..., None]) | (ends == e_hi[..., None]), axis=2)
        along &= (e_lo != e_hi) & valid
        maybe = along & (e_lo >= 0)
        key = e_lo[maybe] * n_points + e_hi[maybe]
        at = np.minimum(np.searchsorted(sorted_key, key), len(sorted_key) - 1)
        split[maybe] = sorted_key[at] == key
    plain = alive & ~split.any(axis=1)
    if inserts:
        plain[[poly for poly, _ in inserts]] = False
    # polygons with a T-junction to mend: each corner, then the points inserted after it
    # (across a face, ``inserts``; along a split mesh edge, in order from it to the next)
    fix = np.flatnonzero(alive & ~plain)
    n_fix = count[fix]
    poly = np.repeat(fix, n_fix)
    side = np.arange(int(n_fix.sum())) - np.repeat(np.cumsum(n_fix) - n_fix, n_fix)
    a = corner[poly, side]
    parts = [(poly, side, np.zeros(len(poly), dtype=np.int64), a)]
    for (q, i), points in inserts.items():  # few: where two cuts meet
        if not alive[q]:
            continue
        k = len(points)
        parts.append((np.full(k, q), np.full(k, i), 1 + np.arange(k), np.asarray(points)))
    on = split[poly, side]
    if on.any():
        q, i, a = poly[on], side[on], a[on]
        b = corner[q, (i + 1) % count[q]]
        e0, e1 = np.minimum(p_lo[a], p_lo[b]), np.maximum(p_hi[a], p_hi[b])
        wa, wb = _along(a, e0, p_lo, p_w), _along(b, e0, p_lo, p_w)
        key = e0 * n_points + e1
        first = np.searchsorted(sorted_key, key)
        run = np.searchsorted(sorted_key, key, "right") - first
        owner = np.repeat(np.arange(len(q)), run)
        point = by_edge[
            np.repeat(first, run) + np.arange(int(run.sum())) - np.repeat(np.cumsum(run) - run, run)
        ]
        w = p_w[point]  # ascending within each run
        lo_w, hi_w = np.minimum(wa, wb)[owner], np.maximum(wa, wb)[owner]
        inside = (w > lo_w + _MERGE) & (w < hi_w - _MERGE)
        owner, point, w = owner[inside], point[inside], w[inside]
        # after the inserts across faces; from a towards b (descending where wa > wb)
        rank = np.where(wa[owner] > wb[owner], -w, w)
        parts.append((q[owner], i[owner], 1 + len(p_lo) + rank, point))
    q_all, i_all, sub_all, pt_all = (np.concatenate(x) for x in zip(*parts, strict=True))
    by = np.lexsort((sub_all, i_all, q_all))
    q_all, pt_all = q_all[by], pt_all[by]
    row = np.searchsorted(fix, q_all)  # the mended polygon's row among them
    sizes = np.bincount(row, minlength=len(fix))
    slot = np.arange(len(row)) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    n_plain = int(plain.sum())
    L = max(K, int(sizes.max(initial=0)))
    rings = np.full((n_plain + len(fix), L), -1)
    rings[:n_plain, :K] = corner[plain]
    rings[n_plain + row, slot] = pt_all
    size = np.concatenate([count[plain], sizes]).astype(np.int64)
    mended = np.arange(len(rings)) >= n_plain
    return rings, size, mended


def _along(j: np.ndarray, e0: np.ndarray, p_lo: np.ndarray, p_w: np.ndarray) -> np.ndarray:
    """Where points j lie along their mesh edges (e0, e1): 0 at node e0, 1 at node e1, else
    their weights (points inside that edge)."""
    node = p_w[j] == 0.0
    return np.where(node, np.where(p_lo[j] == e0, 0.0, 1.0), p_w[j])


def _merge(W: sp.csr_matrix, ring: np.ndarray, size: np.ndarray, rest: np.ndarray, merge: float):
    """(label (k,), merged W): points joined by a ring side shorter than ``merge`` at rest
    made one, at their mean."""
    k = W.shape[0]
    if merge <= 0.0 or len(ring) == 0:
        return np.arange(k), W
    L = ring.shape[1]
    nxt = np.where(np.arange(L)[None, :] + 1 < size[:, None], np.arange(L) + 1, 0)
    valid = np.arange(L)[None, :] < size[:, None]
    a, b = ring[valid], np.take_along_axis(ring, nxt, axis=1)[valid]
    V = W @ rest
    short = np.linalg.norm(V[a] - V[b], axis=1) < merge
    if not short.any():
        return np.arange(k), W
    graph = sp.coo_matrix((np.ones(int(short.sum())), (a[short], b[short])), shape=(k, k))
    n, label = connected_components(graph, directed=False)
    members = np.bincount(label, minlength=n)
    average = sp.csr_matrix((1.0 / members[label], (label, np.arange(k))), shape=(n, k))
    return label, (average @ W).tocsr()


def _distinct(ring: np.ndarray, size: np.ndarray, mended: np.ndarray):
    """The rings with each run of one point kept once (also around the end), and a ring that
    now meets itself (a point twice, apart: merged across a pinch) split there into loops;
    rings left with fewer than three points dropped."""
    R, L = ring.shape
    valid = np.arange(L)[None, :] < size[:, None]
    prev = np.where(np.arange(L)[None, :] == 0, np.maximum(size[:, None] - 1, 0), np.arange(L) - 1)
    keep = valid & (ring != np.take_along_axis(ring, prev, axis=1))
    all_same = valid.any(axis=1) & ~keep.any(axis=1)  # one point: nothing left
    keep[all_same] = False
    slot = np.cumsum(keep, axis=1) - 1
    packed = np.full((R, L), -1)
    r, c = np.nonzero(keep)
    packed[r, slot[r, c]] = ring[r, c]
    size = keep.sum(axis=1)
    # a point twice in one ring (rare): the ring splits into its loops
    s = np.sort(np.where(packed >= 0, packed, -1 - np.arange(L)[None, :]), axis=1)
    pinched = np.flatnonzero((s[:, 1:] == s[:, :-1]).any(axis=1) & (size >= 3))
    extra, extra_mended = [], []
    for i in pinched:
        for loop in _loops([int(v) for v in packed[i, : size[i]]]):
            extra.append(loop)
            extra_mended.append(bool(mended[i]))
        size[i] = 0
    if extra:
        more = np.full((len(extra), L), -1)
        for i, loop in enumerate(extra):
            more[i, : len(loop)] = loop
        packed = np.concatenate([packed, more])
        size = np.concatenate([size, [len(loop) for loop in extra]])
        mended = np.concatenate([mended, extra_mended])
    ok = size >= 3
    return packed[ok], size[ok], mended[ok]


def _loops(ring: list[int]) -> list[list[int]]:
    """A closed ring that passes a point more than once, cut into simple loops there."""
    out, stack, seen = [], [], {}
    for v in ring + ring[:1]:
        if v in seen:
            start = seen[v]
            loop = stack[start:]
            for u in loop:
                seen.pop(u, None)
            del stack[start:]
            if len(loop) >= 3:
                out.append(loop)
        seen[v] = len(stack)
        stack.append(v)
    return out


def _triangulate(W: sp.csr_matrix, ring: np.ndarray, size: np.ndarray, mended: np.ndarray):
    """(W with the mended rings' centroids appended, triangles): fans from the first point,
    and from a new centroid point for mended rings with more than three points. Rings over
    the same points (the two sides of a collapsed sliver, opposite ways round) are fanned
    alike, from their smallest point or from one shared centroid, so that their triangles are
    each other's reverse and cancel."""
    L = ring.shape[1]
    twin_of, twins = _twins(ring, size)
    ring = _start_at_smallest(ring, size, twins)
    tris = []
    corner_fan = ~mended | (size == 3)
    for i in range(1, L - 1):
        ok = corner_fan & (i + 1 < size)
        tris.append(np.column_stack([ring[ok, 0], ring[ok, i], ring[ok, i + 1]]))
    fan = np.flatnonzero(~corner_fan)
    if len(fan):
        k = W.shape[0]
        # one centroid per point set, in the order the sets first appear
        _, first, centre_of = np.unique(twin_of[fan], return_index=True, return_inverse=True)
        rank = np.empty(len(first), dtype=np.int64)
        rank[np.argsort(first)] = np.arange(len(first))
        centre_of = rank[centre_of.ravel()]
        rep = fan[np.sort(first)]
        vr, vc = np.nonzero(np.arange(L)[None, :] < size[rep, None])
        # each centroid: its ring's point weights, averaged
        average = sp.csr_matrix((1.0 / size[rep][vr], (vr, ring[rep][vr, vc])), shape=(len(rep), k))
        W = sp.vstack([W, average @ W]).tocsr()
        r, c = np.nonzero(np.arange(L)[None, :] < size[fan, None])
        nxt = np.where(c + 1 < size[fan][r], c + 1, 0)
        tris.append(np.column_stack([k + centre_of[r], ring[fan][r, c], ring[fan][r, nxt]]))
    tri = np.concatenate(tris).astype(np.int64) if tris else np.zeros((0, 3), dtype=np.int64)
    return W, tri


def _twins(ring: np.ndarray, size: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(each ring's label, the same for rings over the same points; whether another ring has
    its points). Rings are first told apart by size, sum, least and largest point (cheap),
    and only those alike in all four are compared point by point."""
    R, L = ring.shape
    valid = np.arange(L)[None, :] < size[:, None]
    big = np.iinfo(np.int64).max
    rough = np.column_stack([
        size,
        np.where(valid, ring, 0).sum(axis=1),
        np.where(valid, ring, big).min(axis=1),
        np.where(valid, ring, -1).max(axis=1),
    ])  # fmt: skip
    _, rough_of, rough_count = unique_rows(rough, return_inverse=True, return_counts=True)
    rough_of = rough_of.ravel()
    label = np.arange(R)
    alike = np.flatnonzero(rough_count[rough_of] > 1)
    if not len(alike):
        return label, np.zeros(R, dtype=bool)
    key = np.sort(np.where(valid[alike], ring[alike], -1), axis=1)
    _, exact_of, exact_count = unique_rows(key, return_inverse=True, return_counts=True)
    exact_of = exact_of.ravel()
    twins = np.zeros(R, dtype=bool)
    twins[alike] = exact_count[exact_of] > 1
    label[alike] = R + exact_of  # past every lone ring's own label
    return label, twins


def _start_at_smallest(ring: np.ndarray, size: np.ndarray, which: np.ndarray) -> np.ndarray:
    """The rings ``which`` turned round (order kept) to start at their smallest point."""
    rows = np.flatnonzero(which)
    if not len(rows):
        return ring
    L = ring.shape[1]
    ring = ring.copy()
    sub, n = ring[rows], size[rows]
    shift = np.argmin(
        np.where(np.arange(L)[None, :] < n[:, None], sub, np.iinfo(np.int64).max), axis=1
    )
    cols = np.arange(L)[None, :]
    src = np.where(cols < n[:, None], (cols + shift[:, None]) % np.maximum(n[:, None], 1), cols)
    ring[rows] = np.take_along_axis(sub, src, axis=1)
    return ring
