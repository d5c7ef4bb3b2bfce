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

A matrix may come with a fast-changing local part (``factorize(A, update=C)``: contact's
Hessian, which changes wholesale as pairs appear and vanish, over the few DOFs of the vertices
in contact). The factor is then made of A - C, and C is applied to it exactly by Woodbury's
identity: with X = K^-1 P^T the factor's columns at C's DOFs (kept while the factor is; a
pair's DOFs stay in contact over many iterations and steps), G = P X and C_D = P C P^T,

    (K + P^T C_D P)^-1 r = y - X (I + C_D G)^-1 C_D y_D,   y = K^-1 r,

one back-solve and a small dense solve. The preconditioner then holds the current contact
exactly and only the elasticity's drift is left to CG: a probe pressing an organ at 1e4
tetrahedra refactorised 2.9 times a contact step when the factor held the contact of the
iteration it was made at (38 % of the barrier's step). A C over more than MAX_UPDATE_DOFS
DOFs, or needing more than MAX_NEW_COLUMNS new columns at once, is factorised with A instead
(the factor then holds that C, and Woodbury waits for the next factorisation).

Woodbury is used with the Cholesky solvers (PARDISO, CHOLMOD) only: SuperLU's LU factors the
elasticity of a body held by contact alone (nearly singular) without a word.

When to take a fresh factor: as the matrix drifts from the factor's, CG needs more
iterations per solve. Each back-solve beyond the first of a solve is counted against the
factor; once they add up to what a fresh factor costs (REFACTOR_AFTER back-solves, plus the
kept Woodbury columns solved again), the next matrix is factorised (the ski-rental rule: at
most twice the best schedule's cost). Counts, not timings, so runs stay bit-reproducible. A
sagging organ's free steps at 1e4 tetrahedra used one factor for 30 steps at 5.7 back-solves
a solve (8 was the old limit); with the rule they take 2.6 (``benchmarks/free_step.py``).

With ``background=True`` (Courtecuisse et al.'s asynchronous preconditioner) a fresh factor
is made in a thread (PARDISO and CHOLMOD release the GIL) once the kept one has cost
BACKGROUND_AFTER extra back-solves, and swapped in at the first matrix after it is ready;
solves go on with the old one meanwhile. Runs are then not bit-reproducible (the swap depends
on timing), and it did not pay here: a factor one step old still costs CG 2-3 back-solves a
solve at rtol 1e-6, so the steps save little (the palpation organ sagging, 1e4 tetrahedra, two
cores, ``benchmarks/free_step.py --divisions 12 --background``: 24.3 ms a step against 24.7,
4.85 back-solves against 5.15, 0.50 factorisations in the thread against 0.15, measured while
another process used part of the second core). Off by default.

Counts per step (``take_stats``): factorisations, back-solves, CG iterations.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import scipy.sparse as sp

from tissuesim.solve.linear import LinearSolver, NotPositiveDefiniteError

__all__ = [
    "ReusedFactorSolver",
    "LinearStats",
    "MAX_UPDATE_DOFS",
    "MAX_NEW_COLUMNS",
    "factorize_with_update",
]

#: the largest local part applied by Woodbury (its dense Cholesky factors are of this size),
#: and the most new factor columns one solve may ask for (each about a fifth of a back-solve
#: in one multi-right-hand-side call: 96 are about one factorisation of a 1e4-tetrahedron
#: organ, paid once while the contact stays where it is)
MAX_UPDATE_DOFS = 600
MAX_NEW_COLUMNS = 96
#: columns kept per factor at most (1,000 of a 1e4-tetrahedron organ's 6,600 DOFs: 53 MB)
MAX_KEPT_COLUMNS = 1000
#: back-solves beyond one per solve a stale factor may cost before the next matrix is
#: factorised: a factorisation costs 22-38 back-solves at 2e3-2e4 DOFs in 3D (PARDISO, one
#: thread, measured here), 20 keeps the rule on the side of fresh factors
REFACTOR_AFTER = 20
#: with the factor made in a background thread: a new one is started once the kept factor has
#: cost this many back-solves beyond one per solve
BACKGROUND_AFTER = 2
#: a kept column solved again costs about this share of a back-solve (one multi-column call:
#: 0.47 ms a column at 6,591 DOFs against 0.9-1.8 ms for one back-solve, PARDISO, measured)
COLUMN_COST = 0.3


@dataclass
class LinearStats:
    factorizations: int = 0
    back_solves: int = 0
    cg_iterations: int = 0
    solves: int = 0


class ReusedFactorSolver(LinearSolver):
    """Wraps a direct ``LinearSolver`` (PARDISO, CHOLMOD, SuperLU); see the module docstring."""

    def __init__(
        self,
        direct: LinearSolver,
        max_cg: int = 8,
        rtol: float = 1e-6,
        woodbury: bool | None = None,
        background: bool = False,
    ) -> None:
        self.direct = direct
        # a fresh factor made in a thread while solves go on with the kept one
        # (``_background``): None, or [executor, spare solver, pending job or None]
        self._background: list | None = [None, None, None] if background else None
        # the update apart by Woodbury (default: with the Cholesky solvers, PARDISO and
        # CHOLMOD; SuperLU's LU factors the elasticity of a body only contact holds, nearly
        # singular, without a word, and four contact tests then lost their descent directions)
        if woodbury is None:
            from tissuesim.solve.linear import CholmodSolver, PardisoSolver

            woodbury = isinstance(direct, PardisoSolver | CholmodSolver)
        self.woodbury = bool(woodbury)
        self.name = direct.name
        self.max_cg = int(max_cg)
        self.rtol = float(rtol)
        self._rtol = self.rtol  # the current matrix's (``factorize``)
        self.stats = LinearStats()
        self._A: sp.csr_matrix | None = None
        self._factored = False
        self._fresh = False  # the factor is of the current A
        self.factored_matrix: sp.csr_matrix | None = None  # the factor's matrix (checkpoints)
        self.version = 0  # counts factorisations (what is kept from a factor is valid while
        # the version is the same: contact/predict/compliance.py)
        self._update: sp.csr_matrix | None = None  # the current matrix's local part
        self.factor_holds_update = False  # the factor is of A with its update (no Woodbury)
        self.columns = FactorColumns()  # K^-1 e_j of the factor at the update's DOFs
        self._woodbury: tuple | None | bool = None  # _woodbury_terms; False: not usable
        self.excess = 0  # back-solves beyond one per solve since the factor was made
        self.refactor_after = REFACTOR_AFTER
        # columns of the factor others keep (the contact predictor's compliance), by owner:
        # a fresh factor solves them again, which the refresh rule counts
        self.held_columns: dict[str, int] = {}

    def factorize(
        self, A: sp.csr_matrix, update: sp.csr_matrix | None = None, rtol: float | None = None
    ) -> None:
        """Record A (and its fast-changing local part ``update``, included in A); ``rtol``:
        the relative residual the solves of this matrix need (default the solver's own;
        never tighter)."""
        self._rtol = self.rtol if rtol is None else max(float(rtol), self.rtol)
        self._A = A
        self._update = update if update is not None and update.nnz else None
        self._fresh = False
        self._woodbury = None
        if self._background is not None and self._factored:
            self._take_background()
            if self.excess >= BACKGROUND_AFTER:
                self._start_background()
            return
        if self._factored and self.excess >= self.refresh_cost():
            self._factored = False  # the stale factor has cost a fresh one: refactorise

    def refresh_cost(self) -> float:
        """A fresh factor's cost in back-solves: the factorisation and the kept columns."""
        held = len(self.columns.slot) + sum(self.held_columns.values())
        return self.refactor_after + COLUMN_COST * held

    # -- the factor made in a background thread (Courtecuisse et al.'s asynchronous
    # preconditioner): PARDISO and CHOLMOD release the GIL while they factorise
    def _base(self, hold: bool):
        """(the matrix to factor, whether it holds the update) for the current A."""
        if self.woodbury and self._update is not None and not hold:
            if self._woodbury_dofs() is not None:
                return (self._A - self._update).tocsr(), False
        return self._A, True

    def _start_background(self) -> None:
        executor, spare, job = self._background
        if job is not None:
            return
        if executor is None:
            from concurrent.futures import ThreadPoolExecutor

            executor = ThreadPoolExecutor(1, thread_name_prefix="tissuesim-factor")
            spare = self.direct.__class__()
            self._background[:2] = executor, spare
        base, holds = self._base(False)
        holds = holds and self._update is not None

        def factor():
            spare.factorize(base)
            return base, holds

        self._background[2] = executor.submit(factor)

    def _take_background(self) -> None:
        """Swap in the background factor if it is ready (a failed one is dropped)."""
        executor, spare, job = self._background
        if job is None or not job.done():
            return
        self._background[2] = None
        try:
            base, holds = job.result()
        except Exception:  # noqa: BLE001 (indefinite: the next synchronous factor says so)
            return
        self.direct, self._background[1] = spare, self.direct
        self.factored_matrix = base
        self.factor_holds_update = holds
        self.columns.clear()
        self._woodbury = None
        self.stats.factorizations += 1
        self.excess = 0
        self.version += 1
        self._fresh = base is self._A

    def refactorize(self, hold: bool = False) -> None:
        """Factorise the current matrix now, without its update where Woodbury can apply it
        (``hold``: with it; raises NotPositiveDefiniteError)."""
        self._factored = False
        if self._background is not None and self._background[2] is not None:
            self._background[2].exception()  # wait: its factor is older than this one
            self._background[2] = None
        base, holds = self._A, True
        if (
            self.woodbury
            and self._update is not None
            and not hold
            and self._woodbury_dofs() is not None
        ):
            base, holds = (self._A - self._update).tocsr(), False
        try:
            self.direct.factorize(base)
        except NotPositiveDefiniteError:
            if holds:
                raise
            # the elasticity alone indefinite where the contact holds it: factor all of it
            base, holds = self._A, True
            self.direct.factorize(base)
        self.factored_matrix = base
        self.factor_holds_update = holds and self._update is not None
        self.columns.clear()
        self._woodbury = None
        self.stats.factorizations += 1
        self.excess = 0
        self.version += 1
        self._factored = self._fresh = True

    def solve(self, b: np.ndarray) -> np.ndarray:
        self.stats.solves += 1
        if not self._factored:
            self.refactorize()
        start, version = self.stats.cg_iterations, self.version
        x = self._solve(b)
        if self.version == version:  # CG on this factor: its iterations beyond the first
            self.excess += max(self.stats.cg_iterations - start - 1, 0)
        return x

    def _solve(self, b: np.ndarray) -> np.ndarray:
        exact = self._fresh and (self._update is None or self.factor_holds_update)
        if not exact:
            # CG preconditioned by the factor (with the update by Woodbury: one iteration on a
            # fresh factor, as Woodbury's subtraction loses digits to a stiff update)
            x = self._pcg(b)
            if x is not None:
                return x
            self.refactorize(hold=self._fresh)
            if not self.factor_holds_update and self._update is not None:
                x = self._pcg(b)
                if x is not None:
                    return x
                self.refactorize(hold=True)
        self.stats.back_solves += 1
        return self.direct.solve(b)

    def _woodbury_dofs(self) -> np.ndarray | None:
        """The update's DOFs, or None when it is too large for Woodbury (after a new factor
        all its columns are new)."""
        dofs = np.unique(self._update.indices)
        return dofs if len(dofs) <= min(MAX_UPDATE_DOFS, MAX_NEW_COLUMNS) else None

    def _woodbury_terms(self):
        """(dofs, C_D, X, G's and H's Cholesky factors) of the current update on the kept
        factor, or None (no update, the factor holds it, or it is too large or needs too
        many new columns). Raises NotPositiveDefiniteError when K + update is not positive
        definite (H = G^-1 + C_D is not: an exact barrier Hessian), as its factorisation would."""
        if self._woodbury is None:
            self._woodbury = False
            if self.woodbury and self._update is not None and not self.factor_holds_update:
                dofs = np.unique(self._update.indices)
                if len(dofs) <= MAX_UPDATE_DOFS and self.columns.missing(dofs) <= MAX_NEW_COLUMNS:
                    import scipy.linalg as sla

                    X = self.columns.take(self.direct.solve, self._A.shape[0], dofs)
                    self.stats.back_solves += self.columns.solved
                    C = self._update[dofs][:, dofs].toarray()
                    G = X[dofs]
                    try:
                        G_factor = sla.cho_factor(0.5 * (G + G.T), check_finite=False)
                        H = sla.cho_solve(G_factor, np.eye(len(dofs)), check_finite=False) + C
                        H_factor = sla.cho_factor(0.5 * (H + H.T), check_finite=False)
                    except np.linalg.LinAlgError:
                        self._woodbury = None
                        raise NotPositiveDefiniteError(
                            "the matrix with its update is not positive definite"
                        ) from None
                    self._woodbury = (dofs, C, X, G_factor, H_factor)
        return self._woodbury or None

    def _precondition(self, r: np.ndarray) -> np.ndarray:
        """(K + update)^-1 r by Woodbury, or K^-1 r where it does not apply: with
        H = G^-1 + C_D, (I + C_D G)^-1 C_D = G^-1 H^-1 C_D."""
        y = self.direct.solve(r)
        terms = self._woodbury_terms() if self._update is not None else None
        if terms is None:
            return y
        import scipy.linalg as sla

        dofs, C, X, G_factor, H_factor = terms
        z = sla.cho_solve(H_factor, C @ y[dofs], check_finite=False)
        return y - X @ sla.cho_solve(G_factor, z, check_finite=False)

    def _pcg(self, b: np.ndarray) -> np.ndarray | None:
        """CG on the current A, the kept factor (with the update, by Woodbury) as
        preconditioner; None if it does not reach rtol within max_cg iterations or meets
        negative curvature."""
        A, M = self._A, self._precondition
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
            if float(np.linalg.norm(r)) <= self._rtol * norm_b:
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


class FactorColumns:
    """Columns K^-1 e_j of one factor, per DOF j, solved in batches as they are first asked
    for (one multi-right-hand-side call)."""

    def __init__(self) -> None:
        self.clear()

    def clear(self) -> None:
        self.slot: dict[int, int] = {}
        self.X = np.zeros((0, 0))
        self.solved = 0  # columns solved by the last ``take``

    def missing(self, dofs: np.ndarray) -> int:
        return sum(1 for j in dofs.tolist() if j not in self.slot)

    def take(self, solve, n: int, dofs: np.ndarray) -> np.ndarray:
        """(n, len(dofs)): the columns at ``dofs``, the missing ones solved through ``solve``
        (past MAX_KEPT_COLUMNS kept, the others are let go: a long stroke over a surface)."""
        new = np.array([j for j in dofs.tolist() if j not in self.slot], dtype=np.int64)
        if len(self.slot) + len(new) > MAX_KEPT_COLUMNS:
            self.clear()
            new = np.asarray(dofs, dtype=np.int64)
        self.solved = len(new)
        if len(new):
            E = np.zeros((n, len(new)))
            E[new, np.arange(len(new))] = 1.0
            Y = np.asarray(solve(E)).reshape(n, len(new))
            k = self.X.shape[1]
            self.X = np.hstack([self.X, Y]) if k else np.array(Y, order="F")
            self.slot.update({int(j): k + i for i, j in enumerate(new.tolist())})
        take = [self.slot[j] for j in dofs.tolist()]
        return self.X[:, take]


def factorize_with_update(
    solver: LinearSolver, A: sp.csr_matrix, update: sp.csr_matrix | None, rtol: float | None = None
) -> None:
    """``solver.factorize(A)``, A including ``update`` (contact's eliminated Hessian, or None):
    a reused factor takes the update apart (Woodbury) and, where it does, solves to ``rtol``."""
    if update is not None and isinstance(solver, ReusedFactorSolver):
        solver.factorize(A, update=update, rtol=rtol if solver.woodbury else None)
    else:
        solver.factorize(A)


def is_direct(solver: LinearSolver) -> bool:
    from tissuesim.solve.linear import CholmodSolver, PardisoSolver, SuperLUSolver

    return isinstance(solver, PardisoSolver | CholmodSolver | SuperLUSolver)
