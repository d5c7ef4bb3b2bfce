"""The contact predictor of one implicit step: detect, compliance, Signorini-Coulomb,
correction (``contact/predict/__init__.py`` lists the stages' files).

Given the free motion x_free (the step solved without contact, on the kept factorisation) and
the obstacles' start and target positions, the pairs the step makes get constraint rows J
(``rows.py``, over the collision vertices, then through the surfaces' map dV/dq to the system's
DOFs), their compliance W = J H^-1 J^T (``compliance.py``), forces lambda from the contact
problem on W with each pair's gap held at or above its target (``signorini.py``), and the
corrected positions

    x = x_free + H^-1 J^T lambda,

linear in lambda: exact for the linearised gaps on the kept factor's matrix. The forces each
obstacle exerts on the bodies are the multipliers summed over its pairs (N), the body-to-body
ones likewise; ``time/contact_step.py`` certifies x by CCD and accepts it (interactive mode) or
starts the barrier's Newton solve there (accurate mode).
"""

from __future__ import annotations

import time
from collections import defaultdict
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from tissuesim.contact.predict.compliance import Compliance, compliance_matrix
from tissuesim.contact.predict.rows import ContactRows, detect_rows, sweep_candidates
from tissuesim.contact.predict.signorini import solve_signorini_coulomb

__all__ = ["Prediction", "ContactPredictor"]


@dataclass
class Prediction:
    """One step's prediction: ``x`` the corrected configuration, ``dq`` its correction
    (tangent DOFs) from ``x_free``, ``rows`` the pairs, ``force`` (m, d) their multipliers
    (N), ``J`` (m d, n_dofs) the rows over the free DOFs (``J_all``: prescribed ones too),
    ``W`` the compliance, ``free`` (m, d) the gaps and slips at ``x_free`` before any force,
    ``forces`` per obstacle the force on the bodies (N) and ``normal_forces`` its normal part,
    ``sweeps`` / ``converged`` of the contact solve."""

    x: np.ndarray
    dq: np.ndarray
    x_free: np.ndarray
    rows: ContactRows
    force: np.ndarray
    J: sp.csr_matrix
    J_all: sp.csr_matrix
    W: np.ndarray
    free: np.ndarray
    forces: dict[str, np.ndarray]
    normal_forces: dict[str, np.ndarray]
    rhs: np.ndarray | None = None  # (m, d) the contact problem's b: free values less targets
    soft: np.ndarray | None = None  # (m,) the pairs' own compliances in it
    sweeps: int = 0
    converged: bool = True
    smoothing: float = 0.0  # IPC's static-friction slip over 2, eps_v h / 2 (signorini.py)


def _factor_solve(solver, matrix, own):
    """(solve(B) through the factor a prediction uses, the factor's token); ``matrix()`` the
    step's eliminated Hessian, factorised when there is no factor yet (a free motion that
    needed no Newton iteration). An iterative step solver (CG, AMG: no factor to reuse, one
    vector a solve) gets a direct factor of the predictor's own, ``own`` (a dict kept on the
    predictor: a SuperLU factor of the Hessian when it was first needed, made again when its
    ``stale`` flag is set), since a compliance needs many right-hand sides."""
    from tissuesim.solve.linear import SuperLUSolver
    from tissuesim.solve.reuse import ReusedFactorSolver, is_direct

    if isinstance(solver, ReusedFactorSolver):
        if not solver._factored:
            solver.factorize(matrix())
            solver.refactorize()
        return solver.direct.solve, (id(solver.direct), solver.version)
    if is_direct(solver):
        return solver.solve, None
    if own.get("solver") is None or own.get("stale", False):
        direct = SuperLUSolver()
        direct.factorize(matrix())
        own.update(solver=direct, stale=False, version=own.get("version", 0) + 1)
    return own["solver"].solve, ("own", own["version"])


def _hessian(system, x: np.ndarray, energies) -> sp.csr_matrix:
    """The step's eliminated Hessian without contact at x."""
    acc = system.evaluate(x, 2, False, energies, contact=False)
    system.elimination.apply(acc.hessian, acc.gradient)
    return acc.pattern.matrix(acc.hessian).tocsr()


class ContactPredictor:
    """Kept per contact model across steps: the compliance columns and the last step's
    multipliers (the warm start, matched per pair by its stencil's vertices)."""

    def __init__(self) -> None:
        self.compliance = Compliance()
        self._warm: dict[tuple, np.ndarray] = {}
        self.last: Prediction | None = None
        self._solve_through = None  # solve(B) through the factor of the last prediction
        self._weights: dict[tuple, float] = {}  # the barrier's effective weight per pair
        self._candidates = None  # (the sweep's key, sweep_candidates' answer) of the last
        self.clock: defaultdict[str, float] = defaultdict(float)  # seconds per stage, summed
        self.columns = 0  # compliance columns solved since the caller last set it to 0
        # the next free motion by Newton (its PCG refreshes the kept factor) rather than on
        # the kept factor's matrix (time/contact_step.py)
        self.refresh = False
        # a direct factor of the predictor's own, for step solvers without one (CG, AMG)
        self.own_factor: dict = {}
        # friction smoothed as the barrier's (eps_v h / 2, set per step by the caller): exact
        # Coulomb stuck where IPC's friction slips a little, 2-7 % off its forces in a stroke
        self.smoothing = 0.0
        # the last accepted step's contact forces (time, J^T lambda) and H^-1 of them
        self._carried: tuple[float, np.ndarray] | None = None
        self._shift = None

    def predict(
        self,
        system,
        solver,
        x0: np.ndarray,
        x_free: np.ndarray,
        y0: np.ndarray | None,
        y1: np.ndarray | None,
        target_gap,
        also: np.ndarray | None = None,
        energies=None,
        at: np.ndarray | None = None,
        correct: bool = True,
        carried: np.ndarray | None = None,
    ) -> Prediction:
        """The prediction for the step x0 -> x_free (obstacles y0 -> y1, flat, or None where
        they do not move); ``target_gap`` (m, scalar or (m,) for the pairs of the last
        prediction when ``also`` is given): the gap each pair is held at or above; ``also``: a
        configuration whose sweep from x0 adds pairs (the last prediction's, when it crossed a
        surface the free motion did not reach); ``energies``: the step's body energies (for a
        Hessian when the solver holds no factor); ``at``: a configuration (obstacles at y1)
        where the gaps are linearised (``rows.detect_rows``), default the step's start;
        ``correct`` False: the forces alone (``correct`` later gives x); ``carried``: the
        forces (over the DOFs) the free motion x_free was solved under (the last step's
        contact forces, ``carried_force``): the prediction is then made from x_free - H^-1
        carried (the free motion without them, to first order), its pairs from the sweep to
        x_free (near where the step ends: a resting organ's free motion springs back through
        the table by millimetres, and its sweep met 6x the candidates)."""
        contact = system.contact
        start = time.perf_counter()
        solve, token = _factor_solve(
            solver, lambda: _hessian(system, x_free, energies), self.own_factor
        )
        sweep_to = x_free
        if carried is not None:  # the free motion carried the last forces: take them off
            x_free = system.retract(x_free, -self._carried_shift(solve, token, x_free, carried))
        V0 = contact.vertices(x0, obstacle=y0)
        V1 = contact.vertices(x_free, obstacle=y1)
        keep = float(np.max(target_gap)) if np.ndim(target_gap) else float(target_gap)
        V2 = None if also is None else contact.vertices(also, obstacle=y1)
        V_at = None if at is None else contact.vertices(at, obstacle=y1)
        V_to = V1 if carried is None else contact.vertices(sweep_to, obstacle=y1)
        ends = [np.asfortranarray(V_to)] + ([] if V2 is None else [np.asfortranarray(V2)])
        key = (x0.tobytes(), sweep_to.tobytes(), None if also is None else also.tobytes())
        if self._candidates is None or self._candidates[0] != key:
            parts = sweep_candidates(contact, np.asfortranarray(V0), ends, keep + contact.dhat)
            self._candidates = (key, parts)
        rows = detect_rows(
            contact, V0, V1, keep + contact.dhat, V2, V_at, candidates=self._candidates[1]
        )
        if self._weights and rows.n_pairs:
            known = [self._weights.get(k) for k in rows.keys(contact.group)]
            weights = [w if w is not None else g for w, g in zip(known, rows.weights, strict=True)]
            rows = replace(rows, weights=np.asarray(weights, dtype=float))
        S = contact.selection(x_free)
        J = J_all = sp.csr_matrix(rows.J @ S)
        held = system.elimination.dofs
        if len(held) and J.nnz:
            keep_cols = np.ones(J.shape[1])
            keep_cols[held] = 0.0
            J = sp.csr_matrix(J @ sp.diags(keep_cols))
            J.eliminate_zeros()
        self.clock["detect"] += time.perf_counter() - start
        start = time.perf_counter()
        dofs = np.unique(J.indices)
        G = self.compliance.block(solve, token, system.n_dofs, dofs)
        self.columns += self.compliance.solved_columns
        if hasattr(solver, "held_columns"):  # a fresh factor solves the block again
            solver.held_columns["compliance"] = self.compliance.held
        W = compliance_matrix(J, G, dofs)
        self.clock["compliance"] += time.perf_counter() - start
        self._solve_through = solve
        shell = Prediction(
            x=x_free, dq=np.zeros(system.n_dofs), x_free=x_free, rows=rows,
            force=np.zeros((rows.n_pairs, rows.dim)), J=J, J_all=J_all, W=W,
            free=rows.free_values(), forces={}, normal_forces={},
        )  # fmt: skip
        return self._solve(system, shell, target_gap, correct=correct)

    @property
    def warm_start(self) -> dict:
        """The multipliers the next contact solve starts from, per pair (a copy)."""
        return dict(self._warm)

    @warm_start.setter
    def warm_start(self, warm: dict) -> None:
        self._warm = dict(warm)

    def _carried_shift(self, solve, token, x_free: np.ndarray, carried: np.ndarray):
        """H^-1 carried through the factor (one back-solve, kept for this free motion)."""
        key = (token, id(carried), x_free.tobytes())
        if self._shift is None or self._shift[0] != key or token is None:
            start = time.perf_counter()
            self._shift = (key, np.asarray(solve(carried)).reshape(-1))
            self.clock["correction"] += time.perf_counter() - start
        return self._shift[1]

    def carry(self, time_: float, force: np.ndarray | None) -> None:
        """Keep an accepted step's contact forces (over the DOFs, at its end time) for the
        next step's free motion (``carried_force``); None forgets them."""
        self._carried = None if force is None else (float(time_), force)

    def carried_force(self, time_: float) -> np.ndarray | None:
        """The forces kept by ``carry`` at ``time_`` (the step's start), or None."""
        # the simulation snaps its clock to whole steps (0.7999999999999999 -> 0.8)
        if self._carried is None or abs(self._carried[0] - time_) > 1e-9 * max(1.0, abs(time_)):
            return None
        return self._carried[1]

    def solve_again(self, system, target_gap, soft=None, correct: bool = True) -> Prediction:
        """The last prediction's pairs and compliance with other target gaps ((m,) or a
        scalar) and pair compliances ``soft`` (m,): only the contact problem and (unless
        ``correct`` is False: the forces alone are wanted, x and dq are left as they were) the
        correction again."""
        return self._solve(system, self.last, target_gap, soft, correct)

    def correct(self, system) -> Prediction:
        """The last prediction with its correction for its multipliers (after solves with
        ``correct`` False: one back-solve for the last of several)."""
        p = self.last
        m = p.rows.n_pairs
        dq = np.zeros(system.n_dofs)
        if m:
            start = time.perf_counter()
            dq = np.asarray(self._solve_through(p.J.T @ p.force.reshape(-1))).reshape(-1)
            self.clock["correction"] += time.perf_counter() - start
        self.last = replace(p, x=system.retract(p.x_free, dq), dq=dq)
        return self.last

    def refine(self, system, gradient, target_gap, soft=None) -> tuple[Prediction, float]:
        """One more pass of the last prediction on its pairs and compliance, from a new free
        point: with K the kept factor's matrix and g(x) the step's gradient without contact,
        x_free' = x - K^-1 g(x) (a Newton step on the elasticity's nonlinearity, lagged
        matrix), its gaps J (x_free' - x_free) from the old ones (the rows are linear), then
        the contact problem and the correction again. ``gradient(x)`` -> g, prescribed rows
        zero. Returns (the prediction, the largest move of x_free)."""
        p = self.last
        start = time.perf_counter()
        delta = np.asarray(self._solve_through(gradient(p.x)))
        x_free = system.retract(p.x, -delta)
        self.clock["refine"] += time.perf_counter() - start
        shift = system.difference(x_free, p.x_free)
        moved = float(np.max(np.abs(shift), initial=0.0))
        free = p.free + (p.J @ shift).reshape(p.free.shape) if p.rows.n_pairs else p.free
        shell = replace(p, x_free=x_free, free=free)
        return self._solve(system, shell, target_gap, soft), moved

    def _solve(self, system, p: Prediction, target_gap, soft=None, correct=True) -> Prediction:
        """The contact problem on p's W for its free values less the target gaps, then the
        correction from p.x_free: a new Prediction."""
        contact, rows = system.contact, p.rows
        m, d = rows.n_pairs, rows.dim
        start = time.perf_counter()
        b = p.free.copy()
        b[:, 0] -= np.broadcast_to(np.asarray(target_gap, dtype=float), (m,))
        keys = rows.keys(contact.group)
        warm = np.array([self._warm.get(k, np.zeros(d)) for k in keys]).reshape(m, d)
        result = solve_signorini_coulomb(p.W, b, rows.mu, warm, soft, self.smoothing)
        self.clock["contact_solve"] += time.perf_counter() - start
        start = time.perf_counter()
        lam = result.force.reshape(-1)
        dq = p.dq
        if correct:  # one back-solve through the factor W came from
            dq = np.zeros(system.n_dofs)
            if m:
                dq = np.asarray(self._solve_through(p.J.T @ lam)).reshape(-1)
        normal_only = np.zeros_like(result.force)
        normal_only[:, 0] = result.force[:, 0]
        self._warm = dict(zip(keys, result.force, strict=True))
        self.last = replace(
            p,
            x=system.retract(p.x_free, dq) if correct else p.x,
            dq=dq,
            force=result.force,
            forces=self._forces(contact, rows, result.force),
            normal_forces=self._forces(contact, rows, normal_only),
            sweeps=result.sweeps,
            converged=result.converged,
            rhs=b,
            soft=None if soft is None else np.asarray(soft, dtype=float),
            smoothing=self.smoothing,
        )
        self.clock["correction"] += time.perf_counter() - start
        return self.last

    def calibrate(self, contact, x: np.ndarray, pull) -> int:
        """Learn each pair's effective barrier weight at the accepted state x from the
        barrier itself: the barrier's force on the pair's point along its normal over the
        force per unit weight at its gap, ``pull(d)`` (``time/contact_step.py``). The barrier
        spreads a point's force over all its collisions (faces round it, edges), which a
        pair's own area weight does not see. Returns the pairs calibrated."""
        p = self.last
        if p is None or p.rows.n_pairs == 0:
            return 0
        V = contact.vertices(x)
        col = contact._collisions(V)
        if len(col) == 0:
            return 0
        grad = contact.barrier.gradient(col, contact.mesh, V).reshape(-1, contact.dim)
        rows = p.rows
        point = rows.vertices[:, 0]
        safe = np.where(rows.vertices >= 0, rows.vertices, 0)
        gap = np.einsum(
            "md,md->m", rows.normals, np.einsum("mk,mkd->md", rows.coefficients, V[safe])
        )
        force = -np.einsum("md,md->m", grad[point], rows.normals)
        ok = (force > 0) & (gap > 0) & (gap < contact.dhat)
        unit = pull(np.where(ok, gap, 0.5 * contact.dhat))
        keys = rows.keys(contact.group)
        for i in np.flatnonzero(ok).tolist():
            self._weights[keys[i]] = float(force[i] / unit[i])
        return int(ok.sum())

    @staticmethod
    def _forces(contact, rows: ContactRows, force: np.ndarray) -> dict[str, np.ndarray]:
        """Per obstacle, the force it exerts on the bodies (N): minus the multipliers' force on
        its own vertices, J_V^T lambda summed over them."""
        d = contact.dim
        f_V = (rows.J.T @ force.reshape(-1)).reshape(-1, d) if rows.n_pairs else None
        out = {}
        for ob in contact.obstacles:
            where = contact.slices[ob.name][0]
            out[ob.name] = np.zeros(d) if f_V is None else -f_V[where].sum(axis=0)
        return out
