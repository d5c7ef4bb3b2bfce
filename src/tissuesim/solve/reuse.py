"""A direct solver whose factorisation is reused across Newton iterations and time steps.

Newton's matrix changes little between iterations and between steps (contact changes it only
where pairs appear), so a factor of an earlier matrix is a near-perfect preconditioner of the
current one (Courtecuisse et al. use the same idea for SOFA's asynchronous preconditioner).
``factorize(A)`` only records A; ``solve(b)`` runs conjugate gradients on the current A
preconditioned by the kept factor (one back-solve per CG iteration) and refactorises, then
solves directly, when CG needs more than ``max_cg`` iterations, meets negative curvature (the
current A may be indefinite: the fresh Cholesky then says so exactly) or there is no factor yet.
The direction is exact to ``rtol`` (relative residual): Newton with such directions converges as
with exact ones (an inexact Newton method, forcing term far below the quadratic regime's).

Counts per step (``take_stats``): factorisations, back-solves, CG iterations.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import scipy.sparse as sp

from tissuesim.solve.linear import LinearSolver

__all__ = ["ReusedFactorSolver", "LinearStats"]


@dataclass
class LinearStats:
    factorizations: int = 0
    back_solves: int = 0
    cg_iterations: int = 0
    solves: int = 0


class ReusedFactorSolver(LinearSolver):
    """Wraps a direct ``LinearSolver`` (PARDISO, CHOLMOD, SuperLU); see the module docstring."""

    def __init__(self, direct: LinearSolver, max_cg: int = 8, rtol: float = 1e-6) -> None:
        self.direct = direct
        self.name = direct.name
        self.max_cg = int(max_cg)
        self.rtol = float(rtol)
        self.stats = LinearStats()
        self._A: sp.csr_matrix | None = None
        self._factored = False
        self._fresh = False  # the factor is of the current A
        self.factored_matrix: sp.csr_matrix | None = None  # the factor's matrix (checkpoints)
        self.version = 0  # counts factorisations (what is kept from a factor is valid while
        # the version is the same: contact/predict/compliance.py)

    def factorize(self, A: sp.csr_matrix) -> None:
        self._A = A
        self._fresh = False

    def refactorize(self) -> None:
        """Factorise the current matrix now (raises NotPositiveDefiniteError)."""
        self._factored = False
        self.direct.factorize(self._A)
        self.factored_matrix = self._A
        self.stats.factorizations += 1
        self.version += 1
        self._factored = self._fresh = True

    def solve(self, b: np.ndarray) -> np.ndarray:
        self.stats.solves += 1
        if self._factored and not self._fresh:
            x = self._pcg(b)
            if x is not None:
                return x
        if not self._fresh:
            self.refactorize()
        self.stats.back_solves += 1
        return self.direct.solve(b)

    def _pcg(self, b: np.ndarray) -> np.ndarray | None:
        """CG on the current A, the kept factor as preconditioner; None if it does not reach
        rtol within max_cg iterations or meets negative curvature."""
        A, M = self._A, self.direct.solve
        norm_b = float(np.linalg.norm(b))
        if norm_b == 0.0:
            return np.zeros_like(b)
        x = np.zeros_like(b)
        r = b.copy()
        z = M(r)
        self.stats.back_solves += 1
        p = z.copy()
        rz = float(r @ z)
        for _ in range(self.max_cg):
            Ap = A @ p
            curvature = float(p @ Ap)
            self.stats.cg_iterations += 1
            if not curvature > 0.0 or not np.isfinite(curvature):
                return None
            alpha = rz / curvature
            x += alpha * p
            r -= alpha * Ap
            if float(np.linalg.norm(r)) <= self.rtol * norm_b:
                return x
            z = M(r)
            self.stats.back_solves += 1
            rz_new = float(r @ z)
            p = z + (rz_new / rz) * p
            rz = rz_new
        return None

    def take_stats(self) -> dict:
        """The counts since the last call (one step's), then reset."""
        out = asdict(self.stats)
        self.stats = LinearStats()
        return out


def is_direct(solver: LinearSolver) -> bool:
    from tissuesim.solve.linear import CholmodSolver, PardisoSolver, SuperLUSolver

    return isinstance(solver, PardisoSolver | CholmodSolver | SuperLUSolver)
