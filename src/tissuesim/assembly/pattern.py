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

__all__ = ["SparsityPattern"]


@dataclass(frozen=True, eq=False)
class SparsityPattern:
    """CSR structure (indptr, indices) of an (n, n) matrix plus one scatter map per stencil.

    diagonal: (n,) position of each diagonal entry in the data array (always present).
    scatters: list of (k, nloc*nloc) int64 arrays, one per stencil, in the order given.
    """

    n: int
    indptr: np.ndarray
    indices: np.ndarray
    diagonal: np.ndarray
    scatters: tuple[np.ndarray, ...]

    @property
    def nnz(self) -> int:
        return int(self.indices.shape[0])

    @classmethod
    def from_stencils(cls, n: int, stencils: list[np.ndarray]) -> SparsityPattern:
        rows = [np.repeat(s, s.shape[1], axis=1).ravel() for s in stencils]
        cols = [np.tile(s, (1, s.shape[1])).ravel() for s in stencils]
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
        diagonal = inverse[start : start + n]
        return cls(n, indptr, indices.astype(np.int32), diagonal, tuple(scatters))

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """A CSR matrix over this pattern sharing ``data`` (no copy)."""
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def accumulate(self, data: np.ndarray, which: int, blocks: np.ndarray) -> None:
        """Add local blocks (k, nloc, nloc) of stencil ``which`` into ``data`` in place."""
        data += np.bincount(
            self.scatters[which].ravel(), weights=blocks.ravel(), minlength=self.nnz
        )
