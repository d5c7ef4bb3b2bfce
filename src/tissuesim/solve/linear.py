"""Sparse linear solvers for the Newton system H dx = -g, with reusable analysis.

The matrix pattern never changes within a model (see ``assembly.pattern``), so a solver analyses
it once and then only refactorises numbers:

- ``cholmod``: CHOLMOD via scikit-sparse (optional extra ``tissuesim[cholmod]``, which needs
  Debian's ``libsuitesparse-dev``). Symbolic analysis once, ``cholesky_inplace`` per iteration.
  Raises ``NotPositiveDefiniteError`` on an indefinite matrix, which the Newton solver uses to
  switch to a projected Hessian.
- ``splu``: SciPy's SuperLU, always available. SciPy exposes no reusable symbolic factorisation,
  so we reuse its fill-reducing column ordering (computed on the first matrix) instead.
- ``cg``: conjugate gradients preconditioned by Jacobi, or by smoothed-aggregation AMG
  (``preconditioner="amg"``, optional extra ``tissuesim[amg]``).
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = [
    "LinearSolver",
    "NotPositiveDefiniteError",
    "CholmodSolver",
    "SuperLUSolver",
    "CGSolver",
    "make_linear_solver",
    "LINEAR_SOLVERS",
]

LINEAR_SOLVERS = ("auto", "cholmod", "splu", "cg", "amg")


class NotPositiveDefiniteError(RuntimeError):
    """The matrix is not positive definite (Cholesky failed or CG met negative curvature)."""


class LinearSolver:
    name = "base"

    def factorize(self, A: sp.csr_matrix) -> None:
        raise NotImplementedError

    def solve(self, b: np.ndarray) -> np.ndarray:
        raise NotImplementedError


def has_cholmod() -> bool:
    return importlib.util.find_spec("sksparse") is not None


def has_pyamg() -> bool:
    return importlib.util.find_spec("pyamg") is not None


class CholmodSolver(LinearSolver):
    name = "cholmod"

    def __init__(self) -> None:
        from sksparse import cholmod

        self._cholmod = cholmod
        self._factor = None

    def factorize(self, A: sp.csr_matrix) -> None:
        # A symmetric CSR matrix read as CSC is itself: no conversion needed.
        csc = sp.csc_matrix((A.data, A.indices, A.indptr), shape=A.shape)
        try:
            if self._factor is None:
                self._factor = self._cholmod.analyze(csc, mode="supernodal")
            self._factor.cholesky_inplace(csc)
        except self._cholmod.CholmodNotPositiveDefiniteError as exc:
            raise NotPositiveDefiniteError(str(exc)) from exc

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._factor(b)


class SuperLUSolver(LinearSolver):
    name = "splu"

    def __init__(self) -> None:
        self._perm: np.ndarray | None = None
        self._lu = None

    def factorize(self, A: sp.csr_matrix) -> None:
        options = {"SymmetricMode": True}
        if self._perm is None:
            self._lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", options=options)
            self._perm = self._lu.perm_c.copy()
            self._permuted = False
            return
        p = self._perm
        self._lu = spla.splu(A[p][:, p].tocsc(), permc_spec="NATURAL", options=options)
        self._permuted = True

    def solve(self, b: np.ndarray) -> np.ndarray:
        if not self._permuted:
            return self._lu.solve(b)
        p = self._perm
        x = np.empty_like(b)
        x[p] = self._lu.solve(b[p])
        return x


@dataclass
class CGStats:
    iterations: int = 0


class CGSolver(LinearSolver):
    """Preconditioned CG to a relative residual ``rtol``; Jacobi or AMG preconditioner."""

    def __init__(self, preconditioner: str = "jacobi", rtol: float = 1e-8, maxiter: int = 5000):
        self.preconditioner = preconditioner
        self.name = f"cg+{preconditioner}"
        self.rtol = rtol
        self.maxiter = maxiter
        self.stats = CGStats()

    def factorize(self, A: sp.csr_matrix) -> None:
        self._A = A
        if self.preconditioner == "amg":
            import pyamg

            ml = pyamg.smoothed_aggregation_solver(A, symmetry="symmetric", coarse_solver="splu")
            self._M = ml.aspreconditioner(cycle="V")
        else:
            diag = A.diagonal()
            if np.any(diag <= 0):
                raise NotPositiveDefiniteError("non-positive diagonal entry")
            inv = 1.0 / diag
            self._M = spla.LinearOperator(A.shape, matvec=lambda v: inv * v, dtype=float)

    def solve(self, b: np.ndarray) -> np.ndarray:
        count = [0]

        def callback(_):
            count[0] += 1

        x, info = spla.cg(
            self._A, b, rtol=self.rtol, maxiter=self.maxiter, M=self._M, callback=callback
        )
        self.stats.iterations += count[0]
        if info != 0 or not np.all(np.isfinite(x)):
            raise NotPositiveDefiniteError(f"CG did not converge (info={info})")
        return x


def make_linear_solver(name: str, n_dofs: int, dim: int) -> tuple[LinearSolver, str]:
    """Build the solver called ``name`` (see ``LINEAR_SOLVERS``); returns (solver, reason)."""
    if name not in LINEAR_SOLVERS:
        raise ValueError(f"linear_solver must be one of {LINEAR_SOLVERS}, not {name!r}")
    if name == "cholmod":
        if not has_cholmod():
            raise ValueError(
                "linear_solver 'cholmod' needs scikit-sparse: apt-get install libsuitesparse-dev, "
                "then pip install 'tissuesim[cholmod]'"
            )
        return CholmodSolver(), "requested"
    if name == "splu":
        return SuperLUSolver(), "requested"
    if name == "cg":
        return CGSolver("jacobi"), "requested"
    if name == "amg":
        if not has_pyamg():
            raise ValueError("linear_solver 'amg' needs pyamg: pip install 'tissuesim[amg]'")
        return CGSolver("amg"), "requested"
    # auto: direct solvers win in 2D and for small 3D; AMG-CG for large 3D (FIELD-NOTES).
    large_3d = dim == 3 and n_dofs > 60_000
    if large_3d and has_pyamg():
        return CGSolver("amg"), f"auto: 3D with {n_dofs} DOFs > 60000, pyamg available"
    if has_cholmod():
        return CholmodSolver(), f"auto: scikit-sparse (CHOLMOD) available, {n_dofs} DOFs"
    if large_3d:
        return CGSolver("jacobi"), f"auto: 3D with {n_dofs} DOFs > 60000, no pyamg"
    return SuperLUSolver(), f"auto: no scikit-sparse, SciPy SuperLU for {n_dofs} DOFs"
