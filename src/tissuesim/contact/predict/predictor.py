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
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from tissuesim.contact.predict.compliance import Compliance, compliance_matrix
from tissuesim.contact.predict.rows import ContactRows, detect_rows
from tissuesim.contact.predict.signorini import solve_signorini_coulomb

__all__ = ["Prediction", "ContactPredictor"]


@dataclass
class Prediction:
    """One step's prediction: ``x`` the corrected configuration, ``dq`` its correction
    (tangent DOFs), ``rows`` the pairs, ``force`` (m, d) their multipliers (N), ``J`` (m d,
    n_dofs) the rows over the free DOFs (``J_all``: prescribed ones too), ``W`` the compliance,
    ``forces`` per obstacle the force on the bodies (N), ``seconds`` per stage,
    ``sweeps`` / ``converged`` of the contact solve, ``columns_solved`` compliance columns
    solved this step."""

    x: np.ndarray
    dq: np.ndarray
    rows: ContactRows
    force: np.ndarray
    J: sp.csr_matrix
    J_all: sp.csr_matrix
    W: np.ndarray
    forces: dict[str, np.ndarray]
    normal_forces: dict[str, np.ndarray]
    sweeps: int = 0
    converged: bool = True
    columns_solved: int = 0
    seconds: dict[str, float] = field(default_factory=dict)


def _factor_solve(solver, matrix):
    """(solve(B) through the factor a prediction uses, the factor's token or None);
    ``matrix()`` the step's eliminated Hessian, factorised when there is no factor yet (a free
    motion that needed no Newton iteration)."""
    from tissuesim.solve.reuse import ReusedFactorSolver, is_direct

    if isinstance(solver, ReusedFactorSolver):
        if not solver._factored:
            solver.factorize(matrix())
            solver.refactorize()
        return solver.direct.solve, (id(solver.direct), solver.version)
    if is_direct(solver):
        return solver.solve, None

    def one_by_one(B: np.ndarray) -> np.ndarray:  # iterative solvers take one vector at a time
        return np.column_stack([solver.solve(B[:, k]) for k in range(B.shape[1])])

    return one_by_one, None


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
    ) -> Prediction:
        """The prediction for the step x0 -> x_free (obstacles y0 -> y1, flat, or None where
        they do not move); ``target_gap`` (m, scalar or (m,) for the pairs of the last
        prediction when ``also`` is given): the gap each pair is held at or above; ``also``: a
        configuration whose sweep from x0 adds pairs (the last prediction's, when it crossed a
        surface the free motion did not reach); ``energies``: the step's body energies (for a
        Hessian when the solver holds no factor)."""
        contact = system.contact
        seconds: dict[str, float] = {}
        start = time.perf_counter()
        V0 = contact.vertices(x0, obstacle=y0)
        V1 = contact.vertices(x_free, obstacle=y1)
        keep = float(np.max(target_gap)) if np.ndim(target_gap) else float(target_gap)
        V2 = None if also is None else contact.vertices(also, obstacle=y1)
        rows = detect_rows(contact, V0, V1, keep + contact.dhat, V2)
        S = contact.selection(x_free)
        J = J_all = sp.csr_matrix(rows.J @ S)
        held = system.elimination.dofs
        if len(held) and J.nnz:
            keep_cols = np.ones(J.shape[1])
            keep_cols[held] = 0.0
            J = sp.csr_matrix(J @ sp.diags(keep_cols))
            J.eliminate_zeros()
        seconds["detect"] = time.perf_counter() - start
        start = time.perf_counter()
        dofs = np.unique(J.indices)
        solve, token = _factor_solve(solver, lambda: _hessian(system, x_free, energies))
        X = self.compliance.columns(solve, token, system.n_dofs, dofs)
        W = compliance_matrix(J, X, dofs)
        seconds["compliance"] = time.perf_counter() - start
        return self._solve(system, contact, rows, J, J_all, W, X, dofs, x_free, target_gap, seconds)

    def solve_again(self, system, target_gap) -> Prediction:
        """The last prediction's pairs and compliance with other target gaps ((m,) or a
        scalar): only the contact problem and the correction again."""
        p = self.last
        seconds = {k: v for k, v in p.seconds.items() if k in ("detect", "compliance")}
        return self._solve(
            system, system.contact, p.rows, p.J, p.J_all, p.W, p._X, p._dofs, p._x_free,
            target_gap, seconds,
        )  # fmt: skip

    def _solve(self, system, contact, rows, J, J_all, W, X, dofs, x_free, target_gap, seconds):
        m, d = rows.n_pairs, rows.dim
        start = time.perf_counter()
        target = np.broadcast_to(np.asarray(target_gap, dtype=float), (m,))
        b = rows.free_values()
        b[:, 0] -= target
        keys = [tuple(v) for v in rows.vertices.tolist()]
        warm = np.array([self._warm.get(k, np.zeros(d)) for k in keys]).reshape(m, d)
        result = solve_signorini_coulomb(W, b, rows.mu, warm)
        seconds["contact_solve"] = time.perf_counter() - start
        start = time.perf_counter()
        lam = result.force.reshape(-1)
        dq = X @ (J[:, dofs].T @ lam) if m else np.zeros(system.n_dofs)
        x = system.retract(x_free, dq)
        forces = self._forces(contact, rows, result.force)
        normal_only = np.zeros_like(result.force)
        normal_only[:, 0] = result.force[:, 0]
        normal_forces = self._forces(contact, rows, normal_only)
        seconds["correction"] = time.perf_counter() - start
        self._warm = dict(zip(keys, result.force, strict=True))
        self.last = Prediction(
            x=x,
            dq=dq,
            rows=rows,
            force=result.force,
            J=J,
            J_all=J_all,
            W=W,
            forces=forces,
            normal_forces=normal_forces,
            sweeps=result.sweeps,
            converged=result.converged,
            columns_solved=self.compliance.solved_columns,
            seconds=seconds,
        )
        self.last._X, self.last._dofs, self.last._x_free = X, dofs, x_free
        return self.last

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
