"""The compliance W = J H^-1 J^T of a step's contact rows, from the kept factorisation.

J reaches few DOFs (the D coordinates of the vertices in contact), so W needs only the block
G = H^-1[D, D]: W = J_D G J_D^T. The block is kept while the factor is, over every DOF a step
has reached: a DOF new to the block costs one column H^-1 e_j, solved through the kept factor
(``solve/reuse.py``: the factor Newton's CG is preconditioned with, of a recent Hessian), all
new ones in one multi-right-hand-side call (PARDISO: about 0.4 ms a column against 0.8 ms for
a single solve at 6,591 DOFs), and by symmetry that column's entries at the DOFs already held
give the block's new row as well. A probe pressing an organ adds a few vertices a step, so a
step solves a few columns, not 3 per vertex in contact. A new factor (or a new system) starts
the block afresh. Only the block is kept, not the columns (1,400 columns of 6,600 DOFs are
74 MB, and copying them out per step cost more than the solves): the correction H^-1 J^T
lambda is one back-solve (``predictor.py``).

H is the step's matrix without contact (inertia, elasticity, prescribed DOFs eliminated: their
rows of H^-1 are zero), so W is the compliance SOFA's constraint correction uses; from a factor
of an earlier matrix it is that matrix's, which the accurate mode's Newton corrects.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["Compliance", "MAX_COLUMNS", "compliance_matrix"]

#: DOFs held in the block at most (then it starts afresh): 3,000 are 72 MB
MAX_COLUMNS = 3000


class Compliance:
    """The block of H^-1 over the DOFs reached since the factor was made; ``solve(B)`` solves
    H X = B through that factor, ``token`` identifies it (None: no kept factor, every call
    solves afresh)."""

    def __init__(self) -> None:
        self._token: object = None
        self._n = 0
        self._slot: dict[int, int] = {}  # DOF -> row and column of _G
        self._dofs = np.zeros(0, dtype=np.int64)  # the DOF of each slot
        self._G = np.zeros((0, 0))  # capacity x capacity; the first len(_slot) are filled
        self.solved_columns = 0  # columns solved in the last ``block`` call

    @property
    def held(self) -> int:
        """The DOFs (columns) the block holds."""
        return len(self._slot)

    def _reset(self, token, n: int) -> None:
        self._token, self._n, self._slot = token, n, {}
        self._dofs = np.zeros(0, dtype=np.int64)

    def block(self, solve, token, n: int, dofs: np.ndarray) -> np.ndarray:
        """H^-1[dofs, dofs] (dense), the columns of DOFs not held yet solved in one call."""
        dofs = np.asarray(dofs, dtype=np.int64)
        if token is None or token != self._token or self._n != n:
            self._reset(token, n)
        missing = np.array([j for j in dict.fromkeys(dofs.tolist()) if j not in self._slot])
        missing = missing.astype(np.int64)
        if len(self._slot) + len(missing) > MAX_COLUMNS:
            self._reset(token, n)
            missing = np.unique(dofs)
        self.solved_columns = len(missing)
        if len(missing):
            self._add(solve, n, missing)
        take = np.fromiter((self._slot[j] for j in dofs.tolist()), dtype=np.int64, count=len(dofs))
        return self._G[np.ix_(take, take)]

    def _add(self, solve, n: int, new: np.ndarray) -> None:
        k, m = len(self._slot), len(new)
        E = np.zeros((n, m))
        E[new, np.arange(m)] = 1.0
        X = np.asarray(solve(E)).reshape(n, m)
        if k + m > self._G.shape[0]:  # grow by doubling: a step adds a few DOFs
            G = np.zeros((max(2 * self._G.shape[0], k + m, 64),) * 2)
            G[:k, :k] = self._G[:k, :k]
            self._G = G
        across = X[self._dofs]  # H^-1[held, new]; its transpose is H^-1[new, held]
        self._G[:k, k : k + m] = across
        self._G[k : k + m, :k] = across.T
        inner = X[new]
        self._G[k : k + m, k : k + m] = 0.5 * (inner + inner.T)
        self._dofs = np.concatenate([self._dofs, new])
        self._slot.update({int(j): k + i for i, j in enumerate(new.tolist())})


def compliance_matrix(J: sp.csr_matrix, G: np.ndarray, dofs: np.ndarray) -> np.ndarray:
    """W = J_D G J_D^T (dense, rows x rows) for J over all DOFs, D = ``dofs`` (J's nonzero
    columns), G = H^-1[D, D] (``Compliance.block``)."""
    J_D = sp.csr_matrix(J[:, dofs])
    B = np.ascontiguousarray((J_D @ G).T)  # (|D|, rows)
    # symmetric to rounding (G is kept exactly symmetric): no symmetrising pass (2-3 ms at
    # 1,400 rows, a tenth of a step's compliance)
    return np.asarray(J_D @ B)
