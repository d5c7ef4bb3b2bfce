"""FEBio's ``constrained levmar``: Lourakis' levmar ``dlevmar_bc_dif`` as FEBio 4 calls it
(``FEConstrainedLMOptimizeMethod``: opts = tau, obj_tol three times, f_diff_scale; no
parameter scaling), written here after the algorithm levmar implements (Kanzow, Yamashita and
Fukushima, "Levenberg-Marquardt methods with strong local convergence properties for solving
nonlinear equations with convex constraints", J. Comput. Appl. Math. 172, 2004).

Each iteration k, at p (in the bounds) with e = data - model and J = d model / d p:

- stop when |e|^2 <= eps3 (6), or when J^T e on the free parameters is below eps1 and points
  out of the bounds on the active ones (1);
- mu starts at 0.5 tau |e|^2 (Kanzow's start, as there are bounds);
- the LM step: (J^T J + mu I) Dp = J^T e, p + Dp projected on the bounds; stop when
  |Dp|^2 <= eps2^2 |p|^2 (2); taken when |e(p + Dp)|^2 <= 0.99995 |e|^2, mu then scaled by
  max(1/3, 1 - (2 dF / dL - 1)^3) (Nielsen's rule; dF the decrease, dL the model's);
- otherwise a backtracking line search along Dp where it descends (g^T Dp <= -1e-8
  |Dp|^2.1: Schnabel's, levmar's default, quadratic then cubic fits), else, or where it
  fails, a projected gradient search (t from min(1, 100 / (1 + |g|)), or the last one's t,
  by 0.9 down to 1e-18); a failed gradient search leaves p for the next iteration's Jacobian.

The Jacobian is the run's sensitivities, or with ``differences`` levmar's forward
differences: parameter j moved by max(1e-4 |p_j|, f_diff_scale) (FEBio clamps a moved
parameter to its bounds in its objective function, and so does the caller here).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = ["BoxedLM", "boxed_levenberg_marquardt"]

GAMMA, ALPHA, BETA, RHO = 0.99995, 1e-4, 0.9, 1e-8  # levmar's constants
T_MIN_GRADIENT, T_START = 1e-18, 1.0
#: the line search's: its iterations, and the relative step below which it gives up
LINE_SEARCH_ITERATIONS, STEP_TOLERANCE = 150, 1e3 * np.sqrt(np.finfo(float).eps)
EPSILON = np.finfo(float).eps
#: levmar's reasons to stop (its info[6])
REASONS = {
    1: "small gradient J^T e",
    2: "small step Dp",
    3: "the iteration limit",
    4: "a singular matrix",
    5: "no further reduction",
    6: "small objective |e|^2",
    7: "a non-finite objective",
}


@dataclass
class BoxedLM:
    """The outcome: parameters, objective |e|^2, iterations (levmar's k), the reason levmar
    stops (``REASONS``), accepted steps (iteration, objective, parameters, kind)."""

    p: np.ndarray
    objective: float
    iterations: int
    reason: int
    jtj: np.ndarray
    history: list[dict] = field(default_factory=list)

    @property
    def converged(self) -> bool:
        return self.reason in (1, 2, 6)


def _line_search(objective_at, project, p, pe, gradient, step, stepmx):
    """levmar's backtracking line search along ``step`` (Schnabel, Koontz and Weiss' uncmin
    ``lnsrch``, with the trial points projected on the bounds): on f = |e|^2 / 2 with
    ``gradient`` its gradient, lambda from 1, a quadratic then cubic fit of f along the step,
    each new lambda in [0.1, 0.5] of the last, until f(p + lambda step) <= f + 1e-4 lambda
    g^T step. (trial, e, |e|^2) or None where it fails (then a projected gradient search)."""
    f = 0.5 * pe
    length = float(np.linalg.norm(step))
    if length > stepmx:  # longer than allowed
        step, length = step * (stepmx / length), stepmx
    slope = float(gradient @ step)
    relative = float(np.max(np.abs(step) / np.maximum(np.abs(p), 1.0)))
    smallest = STEP_TOLERANCE / relative
    lam, first, last_lam, last_f = 1.0, True, 0.0, 0.0
    for _ in range(LINE_SEARCH_ITERATIONS):
        trial = project(p + lam * step)
        e_trial, pe_trial = objective_at(trial)
        f_trial = 0.5 * pe_trial
        if f_trial <= f + slope * ALPHA * lam:
            return trial, e_trial, pe_trial
        if lam < smallest:
            return None  # no acceptable point distinct enough from p
        if not np.isfinite(f_trial):
            lam, first = 0.1 * lam, True
            continue
        with np.errstate(all="ignore"):
            if first:  # the first backtrack: a quadratic fit
                new = -lam * slope / ((f_trial - f - slope) * 2.0)
                first = False
            else:  # the others: a cubic through the last two
                t1 = f_trial - f - lam * slope
                t2 = last_f - f - last_lam * slope
                t3 = 1.0 / (lam - last_lam)
                a3 = 3.0 * t3 * (t1 / lam**2 - t2 / last_lam**2)
                b = t3 * (t2 * lam / last_lam**2 - t1 * last_lam / lam**2)
                disc = b * b - a3 * slope
                root = np.sqrt(disc) if disc >= 0 else np.nan
                if disc > b * b:  # one positive critical point: the minimum
                    new = (-b + (-root if a3 < 0 else root)) / a3
                else:  # two positive: the first is the minimum
                    new = (-b + (root if a3 < 0 else -root)) / a3
                new = min(new, 0.5 * lam)
        last_lam, last_f = lam, f_trial
        lam = 0.1 * lam if not new >= 0.1 * lam else new
    return None


def boxed_levenberg_marquardt(
    residuals: Callable[[np.ndarray], np.ndarray],
    jacobian: Callable[[np.ndarray], np.ndarray],
    p0: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    tau: float = 1e-3,
    eps: tuple[float, float, float] = (1e-3, 1e-3, 1e-3),
    itmax: int = 100,
    log: Callable[[str], None] = lambda line: None,
) -> BoxedLM:
    """levmar's box-constrained Levenberg-Marquardt on ``residuals(p)`` = model - data (so
    e = -residuals) with ``jacobian(p)`` = d residuals / d p at a point ``residuals`` was
    last called with or before; ``eps`` = (eps1, eps2, eps3)."""
    eps1, eps2, eps3 = eps
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)

    def project(q: np.ndarray) -> np.ndarray:
        return np.minimum(np.maximum(q, lower), upper)

    def objective_at(q: np.ndarray) -> tuple[np.ndarray, float]:
        e = -np.asarray(residuals(q), dtype=float)
        return e, float(e @ e)

    p = project(np.asarray(p0, dtype=float))
    e, pe = objective_at(p)
    reason = 0 if np.isfinite(pe) else 7
    mu, nu, t, gradient_taken = 0.0, 2, 0.0, False
    history: list[dict] = []
    jtj = np.zeros((len(p), len(p)))
    k = 0
    while k < itmax and not reason:
        if pe <= eps3:
            reason = 6
            break
        J = np.asarray(jacobian(p), dtype=float)
        jtj, g = J.T @ J, J.T @ e  # g = J^T e with J = d model / d p = d residuals / d p
        at_upper, at_lower = p == upper, (p == lower) & (p != upper)
        active = at_upper | at_lower
        outward = (at_upper & (g > 0)) | (at_lower & (g < 0))
        free = ~active
        g_inf = float(np.max(np.abs(g[free]))) if free.any() else 0.0
        p_sq = float(p @ p)
        if outward.sum() == active.sum() and g_inf <= eps1:
            reason = 1
            break
        if k == 0:
            mu = 0.5 * tau * pe
        while True:
            try:
                step = np.linalg.solve(jtj + mu * np.eye(len(p)), g)
            except np.linalg.LinAlgError:
                mu *= nu
                nu *= 2
                if nu > 2**62:
                    reason = 5
                    break
                continue
            trial = project(p + step)
            step = trial - p
            step_sq = float(step @ step)
            if step_sq <= eps2**2 * p_sq:
                reason = 2
                break
            if step_sq >= (p_sq + eps2) / EPSILON**2:
                reason = 4
                break
            e_trial, pe_trial = objective_at(trial)
            if not np.isfinite(pe_trial):
                reason = 7
                break
            kind = "LM"
            if pe_trial <= GAMMA * pe:
                dL = float(step @ (mu * step + g))
                if dL > 0.0:
                    ratio = 2.0 * (pe - pe_trial) / dL - 1.0
                    mu *= max(1.0 - ratio**3, 1.0 / 3.0)
                else:
                    mu = min(mu, 0.1 * pe_trial)
                nu, gradient_taken = 2, False
            else:  # not taken: a line search along it, or a projected gradient step
                descent = -g  # the objective's gradient / 2
                searched = None
                if descent @ step <= -RHO * step_sq ** (2.1 / 2.0):
                    stepmx = 1e3 * max(np.sqrt(p_sq), 1.0)
                    searched = _line_search(objective_at, project, p, pe, descent, step, stepmx)
                if searched is not None:
                    kind = "line search"
                    trial, e_trial, pe_trial = searched
                    gradient_taken = False
                else:
                    kind = "projected gradient"
                    t0 = min(100.0 / (1.0 + float(np.linalg.norm(descent))), T_START)
                    t = t if gradient_taken else t0
                    found = False
                    while t > T_MIN_GRADIENT:
                        trial = project(p - t * descent)
                        e_trial, pe_trial = objective_at(trial)
                        slope = float(descent @ (trial - p))
                        if gradient_taken and pe_trial <= pe + 2.0 * 0.99999 * slope:
                            t, gradient_taken = t0, False  # the last t was too small
                            continue
                        if pe_trial <= pe + 2.0 * ALPHA * slope:
                            found = True
                            break
                        t *= BETA
                    gradient_taken = found
                    if not found:
                        break
                moved = trial - p
                if float(moved @ moved) <= eps2**2 * p_sq:
                    reason = 2
                    break
            p, e, pe = trial, e_trial, pe_trial
            history.append({"iteration": k, "objective": pe, "parameters": p.tolist(),
                            "step": kind})  # fmt: skip
            log(f"major iteration {k}: objective {pe:.6g} ({kind} step)")
            break
        k += 1
    if k >= itmax and not reason:
        reason = 3
    return BoxedLM(p, pe, k, reason, jtj, history)
