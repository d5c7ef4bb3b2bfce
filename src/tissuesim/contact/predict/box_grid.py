"""Compiled kernels of the predictor's broad phase (``broad_phase.py``): box pairs through a
uniform grid. Imported only where numba is installed (``tissuesim[fast]``)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["overlap_pairs"]

#: an item over this many cells (of the median extent) along an axis is tried against every
#: item instead of entering the grid (a table's long triangles), and the grid's cells per axis
LARGE = 16.0
MAX_CELLS_PER_AXIS = 256
#: the grid's cells per item at most (the cells grow past the median extent to keep to it)
CELLS_PER_ITEM = 16


@njit(cache=True, nogil=True)
def _cell_range(lo, hi, origin, size, shape, k):
    """The cells [first, last] along axis k that the interval [lo, hi] covers (clamped)."""
    first = int(np.floor((lo - origin[k]) / size))
    last = int(np.floor((hi - origin[k]) / size))
    return min(max(first, 0), shape[k] - 1), min(max(last, 0), shape[k] - 1)


@njit(cache=True, nogil=True)
def overlap_pairs(lo_a, hi_a, lo_b, hi_b, same, a_ids, b_ids, group, enabled, out):
    """Pairs (i, j) of items of a and b whose boxes overlap and that may collide: their
    bodies' pair enabled (a primitive's vertices are of one body), no shared vertex (a_ids
    (na, ka), b_ids (nb, kb): their vertices) and some vertex pair of the two whose groups
    are enabled. ``same``: a is b, each unordered pair once as (i < j). b's boxes go into a
    uniform grid of cells the size of the larger of a's and b's median extents (b's items
    over LARGE cells along an axis are tried against every a instead); each a tries the
    items of the cells its box covers, a pair counted in the one cell that holds the lower
    corner of the boxes' intersection.
    Returns the count; writes the pairs to ``out`` while it has room (call again with room
    for the count when it had not)."""
    na, nb, dim = lo_a.shape[0], lo_b.shape[0], lo_a.shape[1]
    count = 0
    if na == 0 or nb == 0:
        return count
    extent = np.zeros(nb)
    for j in range(nb):
        for k in range(dim):
            extent[j] = max(extent[j], hi_b[j, k] - lo_b[j, k])
    # cells of the larger items' size: a query box then covers a few cells (a 7 mm organ
    # edge in a grid of a jaw's 1.5 mm faces covered 125)
    queried = np.zeros(na)
    for i in range(na):
        for k in range(dim):
            queried[i] = max(queried[i], hi_a[i, k] - lo_a[i, k])
    size = max(np.median(extent), np.median(queried), 1e-300)
    large = extent > LARGE * size
    origin = np.empty(dim)
    top = np.empty(dim)
    shape = np.ones(3, dtype=np.int64)
    for k in range(dim):
        origin[k] = np.inf
        top[k] = -np.inf
    for j in range(nb):
        if not large[j]:
            for k in range(dim):
                origin[k] = min(origin[k], lo_b[j, k])
                top[k] = max(top[k], hi_b[j, k])
    n_small = nb - int(np.sum(large))
    if n_small:
        # surfaces fill few of a volume's cells: at most CELLS_PER_ITEM cells an item (else
        # a fine surface spread over a large box would zero up to 256^3 cells a call)
        while True:
            for k in range(dim):
                shape[k] = min(int((top[k] - origin[k]) / size) + 1, MAX_CELLS_PER_AXIS)
            if shape[0] * shape[1] * shape[2] <= CELLS_PER_ITEM * n_small + 64:
                break
            size *= 1.5
        size = max(size, np.max((top[:dim] - origin[:dim]) / shape[:dim]))
    cells = shape[0] * shape[1] * shape[2]
    # the grid as compressed rows: cell -> b items
    start = np.zeros(cells + 1, dtype=np.int64)
    r = np.zeros((3, 2), dtype=np.int64)  # an item's cell range per axis (unused axes 0)
    for pass_ in range(2):
        if pass_ == 1:
            for c in range(cells):
                start[c + 1] += start[c]
            fill = start[:-1].copy()
            items = np.empty(start[cells], dtype=np.int64)
        for j in range(nb):
            if large[j]:
                continue
            for k in range(dim):
                r[k, 0], r[k, 1] = _cell_range(lo_b[j, k], hi_b[j, k], origin, size, shape, k)
            for x in range(r[0, 0], r[0, 1] + 1):
                for y in range(r[1, 0], r[1, 1] + 1):
                    for z in range(r[2, 0], r[2, 1] + 1):
                        c = (x * shape[1] + y) * shape[2] + z
                        if pass_ == 0:
                            start[c + 1] += 1
                        else:
                            items[fill[c]] = j
                            fill[c] += 1
    large_items = np.flatnonzero(large)
    room = out.shape[0]
    for i in range(na):
        ga = group[a_ids[i, 0]]
        outside = False
        for k in range(dim):
            if n_small and (hi_a[i, k] < origin[k] or lo_a[i, k] > top[k]):
                outside = True
            r[k, 0], r[k, 1] = _cell_range(lo_a[i, k], hi_a[i, k], origin, size, shape, k)
        for x in range(r[0, 0], r[0, 1] + 1 if n_small and not outside else r[0, 0]):
            for y in range(r[1, 0], r[1, 1] + 1):
                for z in range(r[2, 0], r[2, 1] + 1):
                    c = (x * shape[1] + y) * shape[2] + z
                    for t in range(start[c], start[c + 1]):
                        j = items[t]
                        if same and j <= i:
                            continue
                        if not enabled[ga, group[b_ids[j, 0]]]:
                            continue
                        if not _boxes_meet(lo_a, hi_a, lo_b, hi_b, i, j, dim):
                            continue
                        # counted in the cell of the intersection's lower corner only
                        home = True
                        for k in range(dim):
                            corner = max(lo_a[i, k], lo_b[j, k])
                            cell = _cell_range(corner, corner, origin, size, shape, k)[0]
                            if cell != (x if k == 0 else (y if k == 1 else z)):
                                home = False
                        if not home or not _may_collide(a_ids, b_ids, i, j, group, enabled):
                            continue
                        if count < room:
                            out[count, 0] = i
                            out[count, 1] = j
                        count += 1
        for j in large_items:
            if same and j <= i and large[i]:
                continue  # two large ones: once
            if not enabled[ga, group[b_ids[j, 0]]] or (same and j == i):
                continue
            if not _boxes_meet(lo_a, hi_a, lo_b, hi_b, i, j, dim):
                continue
            if not _may_collide(a_ids, b_ids, i, j, group, enabled):
                continue
            if count < room:
                out[count, 0] = min(i, j) if same else i
                out[count, 1] = max(i, j) if same else j
            count += 1
    return count


@njit(cache=True, nogil=True)
def _boxes_meet(lo_a, hi_a, lo_b, hi_b, i, j, dim):
    for k in range(dim):
        if lo_a[i, k] > hi_b[j, k] or lo_b[j, k] > hi_a[i, k]:
            return False
    return True


@njit(cache=True, nogil=True)
def _may_collide(a_ids, b_ids, i, j, group, enabled):
    """No shared vertex, and some vertex pair whose groups are enabled."""
    allowed = False
    for p in range(a_ids.shape[1]):
        u = a_ids[i, p]
        for q in range(b_ids.shape[1]):
            w = b_ids[j, q]
            if u == w:
                return False
            if enabled[group[u], group[w]]:
                allowed = True
    return allowed


@njit(cache=True, nogil=True)
def primitive_boxes(lo, hi, ids):
    """(lo, hi) of each primitive (row of vertex ids): the union of its vertices' boxes."""
    n, k, dim = ids.shape[0], ids.shape[1], lo.shape[1]
    out_lo = np.empty((n, dim))
    out_hi = np.empty((n, dim))
    for i in range(n):
        for c in range(dim):
            a = lo[ids[i, 0], c]
            b = hi[ids[i, 0], c]
            for p in range(1, k):
                a = min(a, lo[ids[i, p], c])
                b = max(b, hi[ids[i, p], c])
            out_lo[i, c] = a
            out_hi[i, c] = b
    return out_lo, out_hi
