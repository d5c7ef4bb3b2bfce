"""Newton's method with a backtracking line search, minimising an energy Phi(x).

Phi knows the physics; Newton does not. Each iteration (Gast et al., TVCG 2015):

    H dx = -g on the free DOFs (prescribed DOFs eliminated in place on the fixed pattern)
    x <- x + alpha dx, alpha halved until Phi decreases enough (Armijo) and stays finite

so every accepted step lowers Phi and the iteration cannot run away (erratum 9 of the notes).
Definiteness, ``hessian_projection``:
    "never":  the exact Hessian, always;
    "always": each point's dP/dF projected to PSD (a descent direction, linear convergence);
    "auto":   the exact Hessian, shifted Levenberg-Marquardt style to H + s diag|H| when it is
              not positive definite, gives no descent direction or no acceptable step (s grows
              tenfold per failure from 1e-6, shrinks tenfold per success, and past 1e4 one
              projected iteration is taken instead). Near a stable solution s returns to zero
              and convergence is quadratic.
Convergence: ||g_free|| <= gradient_tolerance * ||g_free at start|| + absolute_tolerance *
force_scale, with force_scale a model force (mu * volume / length). If a step moves no DOF by
more than step_tolerance * length_scale while ||g_free|| is within 1e3 of the target, the
iteration is at round-off and counts as converged.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from tissuesim.constraints.dirichlet import Elimination
from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError
from tissuesim.solve.linear import LinearSolver, NotPositiveDefiniteError

__all__ = ["NewtonOptions", "NewtonResult", "minimize"]

Projection = Literal["auto", "always", "never"]


@dataclass(frozen=True)
class NewtonOptions:
    """Options of the Newton solver (the ``[newton]`` table of a scene file)."""

    max_iterations: int = 40
    gradient_tolerance: float = 1e-8
    absolute_tolerance: float = 1e-10
    step_tolerance: float = 1e-12
    hessian_projection: Projection = "auto"
    linear_solver: str = "auto"
    max_line_search: int = 40
    armijo: float = 1e-4

    def __post_init__(self) -> None:
        from tissuesim import validate

        validate.choice(self.hessian_projection, "hessian_projection", ("auto", "always", "never"))
        validate.integer(self.max_iterations, "max_iterations", low=1, high=10_000)
        validate.integer(self.max_line_search, "max_line_search", low=1, high=200)
        validate.real(self.armijo, "armijo", low=0.0, high=1.0, low_open=True, high_open=True)
        for key in ("gradient_tolerance", "absolute_tolerance", "step_tolerance"):
            validate.real(getattr(self, key), key, low=0.0, low_open=True)
        if not isinstance(self.linear_solver, str):
            given = validate.short(self.linear_solver)
            raise InputError(f"linear_solver must be a name such as 'auto', not {given}")


@dataclass
class NewtonResult:
    """Record of one Newton solve (no printing: tests and the CLI read it)."""

    converged: bool = False
    iterations: int = 0
    reason: str = ""
    gradient_norms: list[float] = field(default_factory=list)  # ||g_free|| per iterate
    step_norms: list[float] = field(default_factory=list)  # max |alpha dx| per iteration
    step_lengths: list[float] = field(default_factory=list)  # alpha per iteration
    energies: list[float] = field(default_factory=list)  # Phi per iterate
    projected: list[bool] = field(default_factory=list)  # Hessian projected per iteration
    energy_terms: dict[str, float] = field(default_factory=dict)  # at the solution
    # the full gradient of Phi at the solution, prescribed DOFs included (their reactions);
    # not in as_dict: it is one vector per solve, kept for whoever reports forces
    gradient: np.ndarray | None = field(default=None, repr=False)

    def as_dict(self) -> dict:
        return {
            "converged": self.converged,
            "iterations": self.iterations,
            "reason": self.reason,
            "gradient_norms": self.gradient_norms,
            "step_norms": self.step_norms,
            "step_lengths": self.step_lengths,
            "energies": self.energies,
            "projected": self.projected,
        }


Evaluate = Callable[[np.ndarray, int, bool], Accumulator]
Retract = Callable[[np.ndarray, np.ndarray], np.ndarray]


def _add(x: np.ndarray, dx: np.ndarray) -> np.ndarray:
    return x + dx


def minimize(
    evaluate: Evaluate,
    x0: np.ndarray,
    elimination: Elimination,
    solver: LinearSolver,
    options: NewtonOptions,
    *,
    force_scale: float,
    length_scale: float,
    retract: Retract | None = None,
    max_step: Callable[[np.ndarray, np.ndarray], float] | None = None,
    reference_rows: slice | None = None,
    path_free: Callable[[np.ndarray, np.ndarray], bool] | None = None,
) -> tuple[np.ndarray, NewtonResult]:
    """Minimise Phi from x0 (prescribed DOFs already at their values) over the free DOFs.

    evaluate(x, order, project) -> Accumulator with value / gradient / Hessian data.
    retract(x, dx) -> the point reached from x by the step dx: x + dx (the default) for vector
    DOFs; frame rotations are updated multiplicatively, R <- exp(dtheta^) R, so the
    configuration x and the step dx (a tangent vector) may even differ in size. The gradient and
    Hessian from ``evaluate`` are then with respect to dx at 0.
    max_step(x, y) -> the largest fraction of the move x -> y that is free of intersection
    (contact's CCD); every line search starts there instead of at 1.
    path_free(x, y) -> whether the straight move x -> y is free of intersection: checked for
    every line-search trial when ``retract`` does not move the surfaces on straight lines
    (rigid frames rotate their points on arcs), so no accepted iterate intersects.
    reference_rows: the gradient rows whose starting norm sets the relative tolerance (default
    all): the moving-obstacle solve leaves out its obstacles' rows, whose penalty forces at the
    start dwarf the bodies' and would end Newton while the bodies are far from balance.
    Returns the final x and the record. x0 must give a finite Phi.
    """
    result = NewtonResult()
    retract = retract or _add
    x = x0.copy()
    current = evaluate(x, 1, False)
    free = np.ones(current.gradient.size, dtype=bool)
    free[elimination.dofs] = False
    if not np.isfinite(current.value):
        result.reason = "the starting point has infinite energy (an inverted element?)"
        return x, result
    g0 = float(np.linalg.norm(current.gradient[free]))
    g_ref = g0
    if reference_rows is not None:
        g_ref = float(np.linalg.norm(current.gradient[reference_rows][free[reference_rows]]))
    target = options.gradient_tolerance * g_ref + options.absolute_tolerance * force_scale
    result.gradient_norms.append(g0)
    result.energies.append(current.value)
    shift = 0.0  # Levenberg-Marquardt shift of "auto", kept between iterations
    # round-off of Phi: relative to the model's energy scale (force x length), not to |Phi|,
    # which can be tiny next to the terms it sums (a small net energy of large parts)
    noise_scale = force_scale * length_scale
    for iteration in range(options.max_iterations):
        gnorm = result.gradient_norms[-1]
        if gnorm <= target:
            result.converged, result.reason = True, "gradient"
            break
        system = {}  # the assembled (eliminated) system at x, built at most once per kind

        def attempt(project: bool, s: float, x=x, system=system):
            if project not in system:
                acc = evaluate(x, 2, project)
                elimination.apply(acc.hessian, acc.gradient)
                system[project] = acc
            return _try_direction(
                evaluate,
                x,
                system[project],
                solver,
                options,
                project,
                s,
                retract,
                noise_scale,
                elimination,
                max_step,
                path_free,
            )

        if options.hessian_projection == "always":
            accepted = attempt(True, 0.0)
        else:
            accepted = attempt(False, shift)
            while accepted is None and options.hessian_projection == "auto":
                shift = max(10.0 * shift, 1e-6)
                if shift > 1e4:  # the shifted Hessian is nearly a scaled gradient: project
                    accepted = attempt(True, 0.0)
                    shift = 1e-3
                    break
                accepted = attempt(False, shift)
            if accepted is not None and not accepted[0]:
                shift = shift / 10.0 if shift > 1e-6 else 0.0
        if accepted is None:
            result.reason = "no descent step found (line search failed)"
            break
        project, dx, alpha, new = accepted
        x = retract(x, alpha * dx)
        current = new
        result.iterations = iteration + 1
        result.projected.append(project)
        result.step_lengths.append(alpha)
        result.step_norms.append(float(np.max(np.abs(alpha * dx))))
        result.gradient_norms.append(float(np.linalg.norm(current.gradient[free])))
        result.energies.append(current.value)
        if result.gradient_norms[-1] <= target:
            result.converged, result.reason = True, "gradient"
            break
        if result.step_norms[-1] <= options.step_tolerance * length_scale:
            if result.gradient_norms[-1] <= 1e3 * target:
                result.converged, result.reason = True, "round-off (step below step_tolerance)"
            else:
                result.reason = "stagnated: steps below step_tolerance, gradient still large"
            break
    else:
        result.reason = f"no convergence in {options.max_iterations} iterations"
    if not result.converged and not result.reason:
        result.reason = f"no convergence in {options.max_iterations} iterations"
    result.energy_terms = dict(current.terms)
    result.gradient = current.gradient
    return x, result


def _try_direction(
    evaluate,
    x,
    acc,
    solver,
    options,
    project,
    shift,
    retract,
    noise_scale,
    elimination=None,
    max_step=None,
    path_free=None,
):
    """Solve (H + shift diag|H|) dx = -g for an eliminated system ``acc`` and line-search.

    Returns (project, dx, alpha, accumulator at the new point) or None when the matrix is not
    positive definite, dx is no descent direction, or no step length is acceptable."""
    g = acc.gradient
    H = acc.hessian
    if shift > 0.0:
        H = H.copy()
        diag = acc.pattern.diagonal
        H[diag] += shift * np.abs(H[diag])
    A = acc.pattern.matrix(H)
    if acc.extra_hessian is not None:
        A = A + elimination.eliminate_matrix(acc.extra_hessian)
    try:
        solver.factorize(A.tocsr())
        dx = solver.solve(-g)
    except NotPositiveDefiniteError:
        return None
    slope = float(g @ dx)
    if not np.all(np.isfinite(dx)) or slope >= -1e-14 * np.linalg.norm(g) * np.linalg.norm(dx):
        return None  # not a descent direction: the (shifted) Hessian was indefinite
    first = 1.0 if max_step is None else min(1.0, max_step(x, retract(x, dx)))
    if first <= 0.0:
        return None
    step = _line_search(
        evaluate, x, acc, slope, dx, options, retract, noise_scale, first, path_free
    )
    if step is None:
        return None
    return (project, dx, *step)


def _line_search(
    evaluate, x, acc, slope, dx, options, retract, noise_scale, first=1.0, path_free=None
):
    """Backtracking: the largest alpha in 1, 1/2, ... with Armijo decrease and finite Phi.

    A trial may exceed the Armijo bound by Phi's round-off, 1e-12 times the largest of |Phi|,
    the sum of its terms' magnitudes and the model's energy scale: near the solution the true
    decrease of the last, correct step is below what Phi can resolve. ``first``: the first
    trial (below 1 when contact's CCD limits the step); ``path_free``: a trial whose move from x
    is not free of intersection is halved before it is evaluated."""
    alpha = first
    value = acc.value
    magnitude = max(abs(value), sum(abs(v) for v in acc.terms.values()), noise_scale)
    noise = 1e-12 * max(magnitude, 1e-300)
    for _ in range(options.max_line_search):
        y = retract(x, alpha * dx)
        if path_free is not None and not path_free(x, y):
            alpha *= 0.5
            continue
        trial = evaluate(y, 1, False)
        if (
            np.isfinite(trial.value)
            and trial.value <= value + options.armijo * alpha * slope + noise
        ):
            return alpha, trial
        alpha *= 0.5
    return None
