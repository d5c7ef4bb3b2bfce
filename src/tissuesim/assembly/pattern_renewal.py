"""A model's sparsity pattern renewed after a few of its cells changed (a cut: the cells it
crossed become copies, the nodes it parted are duplicated), from the pattern it replaces.

A node row that only unchanged cells touch, in the old mesh and in the new one, keeps its
neighbours: its pairs and its DOF entries move by the rows before it, so an unchanged cell's
scatter map is its old one shifted row by row. The rows the changed cells touch are merged
anew from the cells around them (a cut's few thousand, not the body's 1e4-1e5). The result
is the pattern ``SparsityPattern.from_stencils`` gives the new cells (tested equal, entry for
entry), at a fraction of its cost: no sort of every cell's node pairs, no scatter map computed
afresh for cells the cut did not touch."""

from __future__ import annotations

import numpy as np

from tissuesim.assembly.node_blocks import NodeBlocks
from tissuesim.assembly.pattern import SparsityPattern

__all__ = ["renew_pattern"]


def renew_pattern(
    old: SparsityPattern, old_cells: np.ndarray, same: np.ndarray, cells: np.ndarray, n: int
) -> SparsityPattern | None:
    """The pattern of the DOF stencil of ``cells`` (m, b) over ``n`` nodes of d DOFs, as
    ``old`` has (built on ``old_cells``, one node-blocked stencil): ``same`` (m,) the old cell
    with the same nodes in the same order as each cell, -1 for none. None when ``old`` is not
    node-blocked or the mesh lost nodes (build it afresh then)."""
    blocks = old.blocks
    if blocks is None or len(blocks.scatters) != 1 or n < len(blocks.count):
        return None
    d = blocks.d
    m, b = cells.shape
    n_old = len(blocks.count)
    kept = same >= 0
    used = np.zeros(len(old_cells), dtype=bool)
    used[same[kept]] = True
    affected = np.zeros(n, dtype=bool)  # rows a changed cell touches, in either mesh
    affected[cells[~kept]] = True
    affected[old_cells[~used]] = True
    # the affected rows merged from the (cell, slot) pairs in them, and their diagonals
    e, p = np.nonzero(affected[cells])
    r = cells[e, p]
    rows = np.flatnonzero(affected)
    wanted = (r[:, None] * n + cells[e]).ravel()
    key, inverse = np.unique(np.concatenate([wanted, rows * n + rows]), return_inverse=True)
    new_row, new_col = key // n, key % n
    count = np.zeros(n, dtype=np.int64)
    count[:n_old] = blocks.count
    count[rows] = np.bincount(new_row, minlength=n)[rows]
    vptr = np.concatenate([[0], np.cumsum(count)]).astype(np.int64)
    shift = np.zeros(n, dtype=np.int64)  # how far an unaffected row's pairs move
    shift[:n_old] = vptr[:n_old] - blocks.vptr[:-1]
    cols = np.empty(vptr[-1], dtype=blocks.cols.dtype)
    old_row = np.repeat(np.arange(n_old), blocks.count)
    moved = np.flatnonzero(~affected[old_row])
    cols[moved + shift[old_row[moved]]] = blocks.cols[moved]
    rank = np.arange(len(key)) - np.searchsorted(new_row, new_row)  # within its row
    cols[vptr[new_row] + rank] = new_col
    # node pairs: an unchanged cell's old ones moved with their rows, the affected rows' new
    src = np.maximum(same, 0)
    j = blocks.scatters[0][src].reshape(-1)  # (m b b,), flat: b-long rows would run slowly
    j += np.repeat(shift[cells].reshape(-1), b)
    j = j.reshape(m, b, b)
    j[e, p] = (vptr[new_row] + rank)[inverse[: len(wanted)]].reshape(-1, b)
    renewed = NodeBlocks(d, vptr, count, cols, (j.reshape(m, -1),))
    # DOF entries: likewise, an unaffected row's block row moves by d^2 times its shift
    scatter = _fresh(old.scatters[0].dtype, m, b * b * d * d)
    np.take(old.scatters[0], src, axis=0, out=scatter, mode="clip")  # in range: unbuffered
    rows_of = scatter.reshape(m, b, -1)
    rows_of += (d * d * shift[cells])[:, :, None]
    rows_of[e, p] = renewed.row_positions(j[e, p], r)
    indptr, indices = renewed.csr()
    diag = np.arange(n, dtype=np.int64)
    keys = np.repeat(diag, count) * n + cols  # every pair's, ascending
    jd = np.searchsorted(keys, diag * n + diag)
    diagonal = renewed.diagonal_positions(jd, diag).reshape(-1)
    return SparsityPattern(n * d, indptr, indices, diagonal, (scatter,), renewed)


def _fresh(dtype, *shape: int) -> np.ndarray:
    """An empty array of ``shape`` in ordinary pages. numpy asks the kernel for transparent
    huge pages (madvise) for arrays of 4 MB and more; on a virtual machine their first touch
    costs about 5 ms per 2 MB page (measured here: 2-50 ms, median 30 ms, for the 13 MB scatter
    map of a 1e4-cell organ) against 8-10 ms in 4 KiB pages. A private numpy switch, restored
    at once (the default where numpy lacks it)."""
    core = getattr(np, "_core", None) or np.core
    switch = getattr(getattr(core, "multiarray", None), "_set_madvise_hugepage", None)
    if switch is None:
        return np.empty(shape, dtype=dtype)
    previous = switch(False)
    try:
        return np.empty(shape, dtype=dtype)
    finally:
        switch(previous)
