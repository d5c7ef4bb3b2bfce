"""The node level of a sparsity pattern whose stencils list whole nodes (d consecutive DOFs
each, as every FEM body's do): the pattern of node pairs, each a d x d block of the DOF
pattern, and where each block's entries lie in the CSR data array. ``assembly/pattern.py``
merges stencils at this level (d^2 fewer keys to sort), the mass matrix sums its scalar blocks
here (``energies/mass.py``), and a cut renews only the rows it touched
(``assembly/pattern_renewal.py``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["NodeBlocks"]


@dataclass(frozen=True, eq=False)
class NodeBlocks:
    """The node pattern: row r (a node) holds the pairs vptr[r] .. vptr[r+1] (``count`` L_r
    of them), their columns ``cols`` ascending; ``scatters`` one (k, b * b) array per stencil
    of b nodes: each local node pair's index j in the node pattern. DOF row d r + a starts at
    d^2 vptr[r] + a d L_r in the data array; entry (d r + a, d c + e) is d (j - vptr[r]) + e
    further, j the index of the pair (r, c)."""

    d: int
    vptr: np.ndarray
    count: np.ndarray
    cols: np.ndarray
    scatters: tuple[np.ndarray, ...]

    def csr(self) -> tuple[np.ndarray, np.ndarray]:
        """The DOF pattern's (indptr, indices): DOF row d r + a holds row r's neighbours, each
        expanded to its d DOFs; gathered pair by pair (d times fewer indices than entries)."""
        d, count, vptr = self.d, self.count, self.vptr
        row_len = np.repeat(d * count, d)  # d DOF rows per node row, d L_r entries each
        indptr = np.concatenate([[0], np.cumsum(row_len)]).astype(np.int64)
        reps = d * count  # node pairs of node row r's d DOF rows
        offset = np.arange(d * len(self.cols)) - np.repeat(d * vptr[:-1], reps)
        pair = np.repeat(vptr[:-1], reps) + offset % np.repeat(count, reps)
        indices = np.repeat((self.cols[pair] * d).astype(np.int32), d)  # flat: see row_positions
        indices += np.tile(np.arange(d, dtype=np.int32), len(pair))
        return indptr, indices

    def positions(self, j: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Data positions (k, (b d) (b' d)) of the d x d blocks of node pairs j (k, b, b'),
        r (k, b) their row nodes (a stencil's scatter map, local DOFs node-major)."""
        k, b, b2 = j.shape
        return self.row_positions(j.reshape(k * b, b2), r.reshape(-1)).reshape(k, -1)

    def row_positions(self, j: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Data positions (s, d b' d) of the blocks of node pairs j (s, b') in node rows r
        (s,): d^2 vptr[r] + a d L_r + d (j - vptr[r]) + e for DOF a of the row node and e of
        the column node. Built from flat repeats: broadcasting the d x d offsets runs numpy's
        inner loops d elements at a time, several times slower on million-entry maps."""
        d = self.d
        s, b2 = j.shape
        pair = np.repeat(d * j.reshape(-1), d)  # (s b' d): d j + e
        pair += np.tile(np.arange(d), j.size)
        out = np.repeat(pair.reshape(s, b2 * d), d, axis=0)  # (s d, b' d)
        row = ((d * d - d) * self.vptr[r])[:, None] + np.arange(d) * (d * self.count[r])[:, None]
        out += row.reshape(-1, 1)  # (s d,): d^2 vptr[r] - d vptr[r] + a d L_r
        return out.reshape(s, d * b2 * d)  # s may be 0 (no row changed)

    def diagonal_positions(self, j: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Data positions (p, d) of the diagonal entries (a, a) of the blocks of node pairs
        j (p,) in node rows r (p,)."""
        base, step = self._diagonal(j, r)
        return np.stack([base + a * step for a in range(self.d)], axis=1)

    def _diagonal(self, j: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(position of entry (0, 0), the step to (a + 1, a + 1)) of the blocks of pairs j."""
        d = self.d
        return d * j + (d * d - d) * self.vptr[r], d * self.count[r] + 1

    def scalar_blocks(self, which: int, blocks: np.ndarray, nnz: int) -> np.ndarray:
        """The data (nnz,) of local scalar blocks (k, b, b) of stencil ``which`` on every
        component (each block times the d x d identity, as a mass matrix): summed node pair
        by node pair, d^2 times fewer entries than scattering the d-DOF blocks, in the same
        order (the same sums)."""
        pairs = int(self.vptr[-1])
        nodal = np.bincount(self.scatters[which].ravel(), weights=blocks.ravel(), minlength=pairs)
        row = np.repeat(np.arange(len(self.count)), self.count)
        base, step = self._diagonal(np.arange(pairs), row)
        data = np.zeros(nnz)
        for a in range(self.d):  # one diagonal of every block at a time: long loops
            data[base + a * step] = nodal
        return data
