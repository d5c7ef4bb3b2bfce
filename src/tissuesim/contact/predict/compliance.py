"""The compliance W = J H^-1 J^T of a step's contact rows, from the kept factorisation.

J reaches few DOFs (the D coordinates of the vertices in contact), so W needs only the
columns X = H^-1 E_D (E_D: the unit vectors of D): W = J_D X[D] J_D^T, and the correction of
the positions for multipliers lambda is X (J_D^T lambda). The columns are solved through the
kept factor (``solve/reuse.py``: the factor Newton's CG is preconditioned with, of a recent
Hessian), all new ones in one multi-right-hand-side call (PARDISO: about 0.4 ms a column
against 0.8 ms for a single solve at 6,591 DOFs), and kept while that factor is: a probe
pressing an organ adds a few vertices a step, so a step solves a few columns, not 3 per
vertex in contact. A new factor (or a new system) starts the columns afresh.

H is the step's matrix without contact (inertia, elasticity, prescribed DOFs eliminated: their
rows of X are zero), so W is the compliance SOFA's constraint correction uses; from a factor
of an earlier matrix it is that matrix's, which the accurate mode's Newton corrects.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["Compliance", "MAX_COLUMNS"]

#: columns kept at most (then the cache starts afresh): 3,000 columns of 1e5 DOFs are 2.4 GB
MAX_COLUMNS = 3000


class Compliance:
    """Columns of H^-1 kept per factor; ``solve(B)`` solves H X = B through that factor,
    ``token`` identifies it (None: no kept factor, every call solves afresh)."""

    def __init__(self) -> None:
        self._token: object = None
        self._slot: dict[int, int] = {}  # DOF -> column of _X
        self._X = np.zeros((0, 0))
        self.solved_columns = 0  # columns solved in the last ``columns`` call

    def columns(self, solve, token, n: int, dofs: np.ndarray) -> np.ndarray:
        """X[:, k] = H^-1 e_{dofs[k]} (n, len(dofs)), the missing ones solved in one call."""
        if token is None or token != self._token or self._X.shape[0] != n:
            self._token, self._slot, self._X = token, {}, np.zeros((n, 0))
        missing = np.array([j for j in dofs.tolist() if j not in self._slot], dtype=np.int64)
        self.solved_columns = len(missing)
        if len(missing):
            if self._X.shape[1] + len(missing) > MAX_COLUMNS:
                self._slot, self._X = {}, np.zeros((n, 0))
                missing = np.unique(dofs)
                self.solved_columns = len(missing)
            E = np.zeros((n, len(missing)))
            E[missing, np.arange(len(missing))] = 1.0
            X = np.asarray(solve(E)).reshape(n, len(missing))
            start = self._X.shape[1]
            self._X = np.hstack([self._X, X]) if start else np.array(X, order="F")
            self._slot.update({int(j): start + k for k, j in enumerate(missing.tolist())})
        take = np.fromiter((self._slot[int(j)] for j in dofs), dtype=np.int64, count=len(dofs))
        return self._X[:, take]


def compliance_matrix(J: sp.csr_matrix, X: np.ndarray, dofs: np.ndarray) -> np.ndarray:
    """W = J_D X[D] J_D^T (dense, rows x rows) for J over all DOFs, D = ``dofs`` (J's nonzero
    columns), X = H^-1 E_D (``Compliance.columns``)."""
    J_D = sp.csr_matrix(J[:, dofs])
    B = J_D @ X[dofs]  # (rows, |D|)
    W = np.asarray((J_D @ B.T).T)
    return 0.5 * (W + W.T)
