"""FEBio's parameter optimisation run by tissuesim: the objective of the <febio_optimize> file
(FEBio's ``FEObjectiveFunction``: the sum of squared differences between the model's values
and the data) minimised by FEBio's Levenberg-Marquardt loop (``FELMOptimizeMethod``: Numerical
Recipes' ``mrqmin``, its stopping rule on the objective's relative decrease ``obj_tol``), with
the Jacobian from the run's sensitivities (``identification/sensitivity.py``: one run and one
back-solve per step for all parameters) where FEBio takes one more run per parameter for
forward differences.

What the objective compares: a data-fit the model's curve (its quantity after every step,
the model's start included, against the time or an ``ordinate`` quantity) interpolated
linearly at the data's abscissae and held constant past its ends (FEBio's load curve); a
target, node-data or element-data objective the quantities at the run's end. Parameters are
held within their bounds as FEBio holds them (clamped before each run). ``constrained
levmar`` runs levmar's own box-constrained loop, as FEBio calls ``dlevmar_bc_dif``
(``levmar_bc.py``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from tissuesim.errors import InputError
from tissuesim.febio.optimize.model import ModelBuilder
from tissuesim.febio.optimize.task import OptimizeTask

__all__ = ["OptimizeResult", "run_optimize"]


@dataclass
class OptimizeResult:
    """The optimisation's outcome: the parameters found, the final objective (FEBio's "Final
    objective value"), the major iterations and the runs it took, the data and the model's
    values at the parameters found."""

    parameters: dict[str, float]
    objective: float
    iterations: int
    runs: int
    converged: bool
    x: np.ndarray
    measured: np.ndarray
    simulated: np.ndarray
    labels: list[str]
    std: dict[str, float] = field(default_factory=dict)
    history: list[dict] = field(default_factory=list)
    wall_s: float = 0.0
    gradients: str = "sensitivities"  # the Jacobian's source used (FEBio's differences where
    # the model's sensitivities are not taken)


class _Objective:
    """a -> (residuals r = model - data, dr/da), each call one differentiated run."""

    def __init__(self, task: OptimizeTask, builder: ModelBuilder, gradients: str) -> None:
        if gradients not in ("sensitivities", "differences"):
            raise InputError(f"gradients must be 'sensitivities' or 'differences', not "
                             f"{gradients!r}")  # fmt: skip
        self.task, self.builder, self.gradients = task, builder, gradients
        self.names = [p.name for p in task.parameters]
        self.scales = {p.name: p.scale for p in task.parameters}
        sim, scene = builder.simulation({})
        self.max_steps = int(scene.run["steps"])
        self.note = None  # why the sensitivities gave way to FEBio's differences
        if gradients == "sensitivities":
            from tissuesim.identification.refusals import refusal

            why = refusal(sim, "sensitivities")
            if why is not None:
                self.gradients = "differences"
                self.note = f"{why.rstrip('.')}; FEBio's forward differences are used"

        self.runs = 0
        self.last = None  # (residuals, labels) of the last evaluation
        self.last_a = None  # the parameters of the last evaluation (clamped)

    def __call__(self, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The residuals at a and their Jacobian: by the run's sensitivities, or (gradients
        "differences") by FEBio's forward differences, one more run per parameter with the
        parameter moved by f_diff_scale (|scale| + |a|), backwards at its upper bound."""
        if self.gradients == "sensitivities":
            return self._residuals(a, True)
        r = self._residuals(a, False)[0]
        at_a = self.last
        J = np.zeros((len(r), len(a)))
        for i, p in enumerate(self.task.parameters):
            b = a.copy()
            sign = -1.0 if a[i] >= p.high else 1.0
            b[i] += sign * self.task.f_diff_scale * (abs(p.scale) + abs(a[i]))
            J[:, i] = (self._residuals(b, False)[0] - r) / (b[i] - a[i])
        self.last = at_a
        return r, J

    def _residuals(self, a: np.ndarray, derivatives: bool):
        from tissuesim.identification.sensitivity import sensitivities

        values = dict(zip(self.names, map(float, a), strict=True))
        build = lambda v: self.builder.simulation(v)[0]  # noqa: E731
        obs = self.builder.observations
        if derivatives:
            s = sensitivities(build, values, obs, self.max_steps, scales=self.scales)
            times, series, jac = s.times, s.values, s.jacobian
        else:
            times, series = _plain_run(build(values), obs, self.max_steps)
            jac = np.zeros((len(times), series.shape[1], len(a)))
        self.runs += 1
        start = build(values)
        y0 = np.concatenate([np.atleast_1d(ob.values(start, start.state.x)) for ob in obs])
        task = self.task
        if task.objective == "data-fit":
            abscissa = np.concatenate([[start.time], times])
            q = np.concatenate([[y0[0]], series[:, 0]])
            dq = np.vstack([np.zeros((1, len(a))), jac[:, 0, :]])
            dx = np.zeros_like(dq)
            if task.series[1] is not None:  # the curve against a quantity, not the time
                abscissa = np.concatenate([[y0[1]], series[:, 1]])
                dx = np.vstack([np.zeros((1, len(a))), jac[:, 1, :]])
            f, J = _interpolate(abscissa, q, dq, dx, task.data[:, 0])
            r = f - task.data[:, 1]
            labels = [f"{task.series[0].text} at {x:g}" for x in task.data[:, 0]]
        else:
            r = series[-1] - np.array([v for _, v in task.targets])
            J = jac[-1]
            labels = [q.text if q.kind != "node" else f"{q.text} {q.variable}"
                      for q, _ in task.targets]  # fmt: skip
        self.last = (r, labels)
        return r, J


def _plain_run(sim, observations, max_steps: int):
    """(times, values (steps, m)) of a run without derivatives."""
    times, rows = [], []
    for _ in range(max_steps):
        if sim.finished:
            break
        sim.step()
        times.append(sim.time)
        rows.append(np.concatenate([np.atleast_1d(ob.values(sim, sim.state.x))
                                    for ob in observations]))  # fmt: skip
    return np.asarray(times), np.asarray(rows)


def _interpolate(X, Y, dY, dX, at):
    """FEBio's load curve through (X, Y) at ``at`` (linear; constant past the ends) and its
    derivative from the points' derivatives dY, dX (k, p)."""
    order = np.argsort(X, kind="stable")
    X, Y, dY, dX = X[order], Y[order], dY[order], dX[order]
    f = np.empty(len(at))
    J = np.zeros((len(at), dY.shape[1]))
    for i, x in enumerate(at):
        if x <= X[0]:
            f[i], J[i] = Y[0], dY[0]
            continue
        if x >= X[-1]:
            f[i], J[i] = Y[-1], dY[-1]
            continue
        k = min(int(np.searchsorted(X, x, side="right")) - 1, len(X) - 2)
        span = X[k + 1] - X[k]
        w = (x - X[k]) / span
        f[i] = (1 - w) * Y[k] + w * Y[k + 1]
        dw = (-dX[k] * span - (x - X[k]) * (dX[k + 1] - dX[k])) / span**2
        J[i] = (1 - w) * dY[k] + w * dY[k + 1] + (Y[k + 1] - Y[k]) * dw
    return f, J


def run_optimize(task: OptimizeTask, model_path, log=None, gradients: str = "sensitivities",
                 febio_solver: bool = False) -> OptimizeResult:  # fmt: skip
    """Run the optimisation ``task`` on the FEBio model ``model_path``; ``log(line)`` gets a
    line per run and per major iteration (FEBio's log). ``gradients``: "sensitivities" (the
    run's own derivatives, one run per evaluation) or "differences" (FEBio's forward
    differences). ``febio_solver``: the model's steps solved by FEBio's quasi-Newton, as
    ``tissuesim run --febio-solver`` (its stopping points, so its adaptive steps: the curve a
    data-fit interpolates is then FEBio's)."""
    start = time.perf_counter()
    builder = ModelBuilder(model_path, task, febio_solver=febio_solver)
    try:
        objective = _Objective(task, builder, gradients)
        if objective.note and log is not None:
            log(objective.note)
        lo = np.array([p.low for p in task.parameters])
        hi = np.array([p.high for p in task.parameters])
        a0 = np.array([p.initial for p in task.parameters])
        loop = _constrained_levmar if task.method == "constrained levmar" else _levmar
        a, chisq, iterations, converged, history, covar = loop(
            objective, a0, lo, hi, task, log or (lambda line: None)
        )
        if not np.array_equal(objective.last_a, a):  # the last run was a rejected trial
            objective._residuals(a, False)
        r, labels = objective.last
    finally:
        builder.close()
    names = objective.names
    data = task.data if task.objective == "data-fit" else None
    measured = data[:, 1] if data is not None else np.array([v for _, v in task.targets])
    x = data[:, 0] if data is not None else np.arange(1, len(measured) + 1, dtype=float)
    dof = max(len(r) - len(a), 1)
    sigma2 = float(chisq) / dof
    std = {n: float(np.sqrt(max(covar[i, i] * sigma2, 0.0))) for i, n in enumerate(names)}
    return OptimizeResult(dict(zip(names, map(float, a), strict=True)), float(chisq), iterations,
                          objective.runs, converged, x, measured, measured + r, labels, std,
                          history, time.perf_counter() - start,
                          objective.gradients)  # fmt: skip


def _levmar(objective, a0, lo, hi, task: OptimizeTask, log):
    """FEBio's loop (FELMOptimizeMethod::Solve around mrqmin) on the exact Jacobian: a first
    trial step, then trial steps until an accepted one (not the first of the loop) lowers the
    objective by less than obj_tol relatively, (f_prev - f) / (f_prev + f + 1)."""
    state = {}

    def evaluate(a):
        a = np.clip(a, lo, hi)  # FEBio's ObjFun holds the parameters in their bounds
        tick = time.perf_counter()
        r, J = objective(a)
        objective.last_a = a
        log(f"run {objective.runs}: objective {float(r @ r):.6g} at {_show(task, a)} "
            f"({time.perf_counter() - tick:.1f} s)")  # fmt: skip
        return a, r, J, float(r @ r)

    def accept(a, r, J, chisq):
        state.update(a=a, r=r, J=J, chisq=chisq, alpha=J.T @ J, beta=-J.T @ r)

    def trial(iteration: int) -> bool:
        """One mrqmin step: whether it was accepted (and lambda lowered)."""
        covar = state["alpha"].copy()
        covar[np.diag_indices_from(covar)] *= 1.0 + state["lam"]
        try:
            da = np.linalg.solve(covar, state["beta"])
        except np.linalg.LinAlgError:
            raise InputError(f"{task.source}: the objective does not depend on the parameters "
                             "(a singular Levenberg-Marquardt system)") from None  # fmt: skip
        a, r, J, chisq = evaluate(state["a"] + da)
        ok = chisq < state["chisq"]
        if ok:
            state["lam"] *= 0.1
            accept(a, r, J, chisq)
        else:
            state["lam"] *= 10.0
        history.append({"iteration": iteration, "objective": state["chisq"],
                        "parameters": state["a"].tolist(), "accepted": ok})  # fmt: skip
        log(f"major iteration {iteration}: objective {state['chisq']:.6g} at "
            f"{_show(task, state['a'])}" + ("" if ok else " (trial rejected)"))  # fmt: skip
        return ok

    history: list[dict] = []
    accept(*evaluate(np.asarray(a0, dtype=float)))
    state["lam"] = 0.001
    trial(0)
    fprev, lam_prev = state["chisq"], state["lam"]
    niter, converged = 1, False
    while True:
        trial(niter)
        if state["lam"] < lam_prev and niter != 1:
            converged = (fprev - state["chisq"]) / (fprev + state["chisq"] + 1) < task.obj_tol
        fprev, lam_prev = state["chisq"], state["lam"]
        niter += 1
        if converged or niter >= task.max_iter:
            break
    covar = np.linalg.pinv(state["alpha"])
    return state["a"], state["chisq"], niter, converged, history, covar


def _constrained_levmar(objective, a0, lo, hi, task: OptimizeTask, log):
    """FEBio's ``constrained levmar`` (levmar's dlevmar_bc_dif: ``levmar_bc.py``) on the run's
    sensitivities, or on levmar's forward differences (``gradients="differences"``)."""
    from tissuesim.febio.optimize.levmar_bc import REASONS, boxed_levenberg_marquardt

    evaluated: dict[tuple, tuple] = {}

    def residuals(a: np.ndarray) -> np.ndarray:
        clamped = np.clip(a, lo, hi)  # FEBio's ObjFun holds the parameters in their bounds
        tick = time.perf_counter()
        if objective.gradients == "sensitivities":
            r, J = objective(clamped)
        else:
            r, J = objective._residuals(clamped, False)[0], None
        objective.last_a = clamped
        evaluated[tuple(a)] = (r, J)
        log(f"run {objective.runs}: objective {float(r @ r):.6g} at {_show(task, clamped)} "
            f"({time.perf_counter() - tick:.1f} s)")  # fmt: skip
        return r

    def jacobian(a: np.ndarray) -> np.ndarray:
        r, J = evaluated[tuple(a)]
        if J is None:  # levmar's forward differences: max(1e-4 |a_j|, delta)
            J = np.empty((len(r), len(a)))
            for j in range(len(a)):
                step = max(1e-4 * abs(a[j]), task.f_diff_scale)
                moved = a.copy()
                moved[j] += step
                J[:, j] = (residuals(moved) - r) / step
        return J

    tol = task.obj_tol
    out = boxed_levenberg_marquardt(residuals, jacobian, a0, lo, hi, tau=task.tau,
                                    eps=(tol, tol, tol), itmax=task.max_iter, log=log)  # fmt: skip
    log(f"levmar stopped by {REASONS.get(out.reason, out.reason)} after {out.iterations} "
        "iterations")  # fmt: skip
    if out.reason in (4, 7):
        raise InputError(f"{task.source}: the constrained Levenberg-Marquardt stopped by "
                         f"{REASONS[out.reason]} at {_show(task, out.p)}")  # fmt: skip
    history = [{"iteration": h["iteration"], "objective": h["objective"],
                "parameters": h["parameters"], "accepted": True, "step": h["step"]}
               for h in out.history]  # fmt: skip
    return out.p, out.objective, out.iterations, out.converged, history, np.linalg.pinv(out.jtj)


def _show(task: OptimizeTask, a: np.ndarray) -> str:
    return ", ".join(f"{p.name} = {v:.6g}" for p, v in zip(task.parameters, a, strict=True))
