"""A CSR sparsity pattern built once per model, with scatter maps from local blocks.

Every energy with a Hessian declares a stencil: (k, nloc) global DOFs of each of its local
blocks. The pattern is the union of all stencils' couplings. For each stencil we precompute
``scatter[k, nloc*nloc]``, the position in the CSR data array of every local entry, so that
assembling a Hessian is one ``np.bincount`` into a fixed array: no COO sort, no pattern rebuild,
and the linear solver's symbolic analysis stays valid across Newton iterations and time steps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from tissuesim.assembly.node_blocks import NodeBlocks
from tissuesim.errors import InputError

__all__ = ["SparsityPattern"]


def _node_block(n: int, stencils: list[np.ndarray]) -> int:
    """The d (2 or 3) such that every stencil lists whole nodes (d consecutive DOFs starting at
    a multiple of d), or 0."""
    for d in (3, 2):
        if n % d or not stencils:
            continue
        ok = True
        for s in stencils:
            if s.shape[1] % d or s.size == 0:
                ok = False
                break
            first = s[:, ::d]
            if np.any(first % d) or np.any(
                s.reshape(s.shape[0], -1, d) != first[:, :, None] + np.arange(d)
            ):
                ok = False
                break
        if ok:
            return d
    return 0


@dataclass(frozen=True, eq=False)
class SparsityPattern:
    """CSR structure (indptr, indices) of an (n, n) matrix plus one scatter map per stencil.

    diagonal: (n,) position of each diagonal entry in the data array (always present).
    scatters: list of (k, nloc*nloc) int64 arrays, one per stencil, in the order given.
    blocks: for stencils of whole d-DOF nodes, the node pattern they were merged on.
    """

    n: int
    indptr: np.ndarray
    indices: np.ndarray
    diagonal: np.ndarray
    scatters: tuple[np.ndarray, ...]
    #: the node-level structure of a node-blocked pattern (None for others)
    blocks: NodeBlocks | None = None

    @property
    def nnz(self) -> int:
        return int(self.indices.shape[0])

    @classmethod
    def from_stencils(
        cls, n: int, stencils: list[np.ndarray], extra: tuple[np.ndarray, np.ndarray] | None = None
    ) -> SparsityPattern:
        """The union of the stencils' blocks, the diagonal and ``extra`` (rows, cols) entries
        (for energies whose blocks are not rectangular stencils, found with ``positions``).

        Node-blocked stencils (a node's d DOFs consecutive, as FEM bodies have) are merged at
        the node level, d^2 times fewer keys to sort (``_from_node_blocks``): the pattern is
        rebuilt after every cut, and that sort was most of a cut's cost."""
        block = _node_block(n, stencils) if extra is None else 0
        if block > 1:
            return cls._from_node_blocks(n, stencils, block)
        rows = [np.repeat(s, s.shape[1], axis=1).ravel() for s in stencils]
        cols = [np.tile(s, (1, s.shape[1])).ravel() for s in stencils]
        n_extra = 0
        if extra is not None:
            rows.append(np.asarray(extra[0], dtype=np.int64))
            cols.append(np.asarray(extra[1], dtype=np.int64))
            n_extra = rows[-1].size
        diag = np.arange(n, dtype=np.int64)
        rows.append(diag)
        cols.append(diag)
        key = np.concatenate(rows).astype(np.int64) * n + np.concatenate(cols)
        unique, inverse = np.unique(key, return_inverse=True)
        indices = unique % n
        counts = np.bincount(unique // n, minlength=n)
        indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        scatters, start = [], 0
        for s in stencils:
            size = s.shape[0] * s.shape[1] ** 2
            scatters.append(inverse[start : start + size].reshape(s.shape[0], -1))
            start += size
        start += n_extra
        diagonal = inverse[start : start + n]
        return cls(n, indptr, indices.astype(np.int32), diagonal, tuple(scatters))

    @classmethod
    def _from_node_blocks(cls, n: int, stencils: list[np.ndarray], d: int) -> SparsityPattern:
        """``from_stencils`` for stencils of whole d-DOF nodes: the node pattern (rows of
        nodes, sorted neighbour lists), then each node pair's d x d block in place. DOF row
        d r + a of node row r (neighbours vptr[r] .. vptr[r+1]) starts at d^2 vptr[r] + a d L_r
        (L_r neighbours); entry (d r + a, d c + b) is d (j - vptr[r]) + b further, j the node
        pair's position in the node pattern."""
        nv = n // d
        nodes = [s[:, ::d] // d for s in stencils]
        rows = [np.repeat(v, v.shape[1], axis=1).ravel() for v in nodes]
        cols = [np.tile(v, (1, v.shape[1])).ravel() for v in nodes]
        diag_v = np.arange(nv, dtype=np.int64)
        key = np.concatenate([*rows, diag_v]).astype(np.int64) * nv + np.concatenate(
            [*cols, diag_v]
        )
        unique, inverse = np.unique(key, return_inverse=True)
        v_row, v_col = unique // nv, unique % nv
        count = np.bincount(v_row, minlength=nv)  # L_r
        vptr = np.concatenate([[0], np.cumsum(count)]).astype(np.int64)
        pairs, start = [], 0  # each stencil's (k, b * b) node pair indices
        for v in nodes:
            size = v.shape[0] * v.shape[1] ** 2
            pairs.append(inverse[start : start + size].reshape(v.shape[0], -1))
            start += size
        blocks = NodeBlocks(d, vptr, count, v_col, tuple(pairs))
        indptr, indices = blocks.csr()
        scatters = [
            blocks.positions(j.reshape(len(v), v.shape[1], -1), v)
            for j, v in zip(blocks.scatters, nodes, strict=True)
        ]
        diagonal = blocks.diagonal_positions(inverse[-nv:], diag_v).reshape(-1)
        return cls(n, indptr, indices, diagonal, tuple(scatters), blocks)

    @classmethod
    def from_entries(cls, n: int, rows: np.ndarray, cols: np.ndarray) -> SparsityPattern:
        """The pattern of the given entries (plus the diagonal), with no stencil scatters:
        for systems assembled from other patterns through ``positions``."""
        diag = np.arange(n, dtype=np.int64)
        key = np.concatenate([np.asarray(rows, np.int64) * n + cols, diag * n + diag])
        unique = np.unique(key)
        counts = np.bincount(unique // n, minlength=n)
        indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        indices = (unique % n).astype(np.int32)
        diagonal = np.searchsorted(unique, diag * n + diag)
        return cls(n, indptr, indices, diagonal, ())

    def keys(self) -> np.ndarray:
        """row * n + col of every stored entry, ascending (CSR order, sorted columns)."""
        rows = np.repeat(np.arange(self.n, dtype=np.int64), np.diff(self.indptr))
        return rows * self.n + self.indices

    def positions(self, rows, cols, keys: np.ndarray | None = None) -> np.ndarray:
        """Positions in the data array of entries (rows, cols), any shape; ValueError if one
        is not stored. ``keys``: a cached ``self.keys()``."""
        keys = self.keys() if keys is None else keys
        wanted = np.asarray(rows, dtype=np.int64) * self.n + cols
        pos = np.minimum(np.searchsorted(keys, wanted), keys.size - 1)
        if not np.array_equal(keys[pos], wanted):
            raise InputError("internal: an entry lies outside the sparsity pattern")
        return pos

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """A CSR matrix over this pattern sharing ``data`` (no copy)."""
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def accumulate(self, data: np.ndarray, which: int, blocks: np.ndarray) -> None:
        """Add local blocks (k, nloc, nloc) of stencil ``which`` into ``data`` in place."""
        data += np.bincount(
            self.scatters[which].ravel(), weights=blocks.ravel(), minlength=self.nnz
        )
