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
With contact (``contact_projection``) a failed exact Hessian is next tried with only the
contact part projected per collision (IPC's projection), the elasticity kept exact: the
barrier's exact Hessian is indefinite where a surface rotates under a point, and shifting the
whole matrix for it (the old path) turned Newton into 100+ iterations of gradient descent.
Convergence (``criterion``: "relative", the default, the relative one alone; "physical" either
of the two; "auto" the physical one too in steps with contact). The physical criterion is
experimental: its force part is relative to the model's force scale, far above a small contact
force (the Hertz example stopped with its probe force 4x too large), so it is not the default:
  physical (in the model's units, as IPC and FEBio stop): after a full step
      (alpha = 1), max |g_free| <= force_tolerance * force_scale and the estimated remaining
      motion max |dx| * ||g_new|| / ||g_old|| (the next Newton step, from the contraction of
      the last) <= displacement_tolerance * the motion of this solve so far (the sum of its
      steps' largest DOF moves); force_scale a model force (mu * volume / length);
  relative: ||g_free|| <= gradient_tolerance * ||g_free at start|| + absolute_tolerance *
      force_scale (gradient_tolerance 1e-8: tight, for references and tests).
If a step moves no DOF by more than step_tolerance * length_scale while ||g_free|| is within
1e3 of the target, the iteration is at round-off and counts as converged.
Linear solves: exact with a direct solver; with a reused factor (``solve/reuse.py``) CG to a
relative residual of 1e-6, or, in steps with contact whose Hessian the factor takes by Woodbury
(PARDISO, CHOLMOD), after a full step (or at the start), to the forcing term min(FORCING,
||g|| / ||g_0||) (an inexact Newton method; Eisenstat & Walker): loose while far from the
solution, proportional to the gradient near it, which keeps the quadratic rate.
``relag(x)``: lagged terms (friction) re-lagged at a converged point inside the same solve;
the solve goes on until a point converges with the lag unchanged (or the relags run out).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from tissuesim.constraints.dirichlet import Elimination
from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError
from tissuesim.solve.line_search import line_search
from tissuesim.solve.linear import LinearSolver, NotPositiveDefiniteError
from tissuesim.solve.reuse import factorize_with_update
from tissuesim.solve.tangent_start import tangent_start

__all__ = ["NewtonOptions", "NewtonResult", "minimize"]

Projection = Literal["auto", "always", "never"]
Criterion = Literal["auto", "physical", "relative"]


@dataclass(frozen=True)
class NewtonOptions:
    """Options of the Newton solver (the ``[newton]`` table of a scene file)."""

    max_iterations: int = 40
    gradient_tolerance: float = 1e-8
    absolute_tolerance: float = 1e-10
    step_tolerance: float = 1e-12
    # the stopping criterion (module docstring): "relative" (the default), "physical" or
    # "auto" (physical in contact steps). The physical one is experimental: on the Hertz
    # example it stopped with the block out of balance (probe force 4x too large)
    criterion: Criterion = "relative"
    force_tolerance: float = 1e-5
    displacement_tolerance: float = 1e-3
    hessian_projection: Projection = "auto"
    linear_solver: str = "auto"
    # a direct solver's factor kept as the preconditioner of CG on later matrices (solve/reuse)
    reuse_factorization: bool = True
    max_line_search: int = 40
    armijo: float = 1e-4
    # "newton": this module's solve to the tolerances above; "febio": FEBio's quasi-Newton
    # (BFGS, its line search and its norms: solve/quasin.py) to FEBio's own stopping point,
    # with the settings ``febio`` (a FebioSettings or a table of them; FEBio's defaults)
    method: Literal["newton", "febio"] = "newton"
    febio: object = None
    # method "febio": a step FEBio's solver gives up on is tried once more by this module's
    # Newton from the same start before it is halved (time/steps.py)
    febio_fallback: bool = True

    def __post_init__(self) -> None:
        from tissuesim import validate

        validate.choice(self.method, "method", ("newton", "febio"))
        if self.febio is not None or self.method == "febio":
            from tissuesim.solve.febio_settings import febio_settings

            object.__setattr__(self, "febio", febio_settings(self.method, self.febio))

        validate.choice(self.hessian_projection, "hessian_projection", ("auto", "always", "never"))
        validate.choice(self.criterion, "criterion", ("auto", "physical", "relative"))
        validate.integer(self.max_iterations, "max_iterations", low=1, high=10_000)
        validate.integer(self.max_line_search, "max_line_search", low=1, high=200)
        validate.real(self.armijo, "armijo", low=0.0, high=1.0, low_open=True, high_open=True)
        for key in ("gradient_tolerance", "absolute_tolerance", "step_tolerance"):
            validate.real(getattr(self, key), key, low=0.0, low_open=True)
        for key in ("force_tolerance", "displacement_tolerance"):
            validate.real(getattr(self, key), key, low=0.0)
        for key in ("reuse_factorization", "febio_fallback"):
            if not isinstance(getattr(self, key), bool):
                raise InputError(f"{key} must be true or false")
        if not isinstance(self.linear_solver, str):
            given = validate.short(self.linear_solver)
            raise InputError(f"linear_solver must be a name such as 'auto', not {given}")

    def tighter(self, factor: float) -> NewtonOptions:
        """These options with every tolerance divided by ``factor`` (accuracy checks)."""
        from dataclasses import replace

        return replace(
            self,
            gradient_tolerance=self.gradient_tolerance / factor,
            absolute_tolerance=self.absolute_tolerance / factor,
            force_tolerance=self.force_tolerance / factor,
            displacement_tolerance=self.displacement_tolerance / factor,
        )


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
    contact_projected: list[bool] = field(default_factory=list)  # only contact's projected
    relags: int = 0  # lagged terms (friction) re-lagged inside the solve
    budget_stop: bool = False  # stopped by an interactive budget before converging
    fallback: bool = False  # method "febio": this module's Newton solved a step FEBio's gave up on
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
            "contact_projected": self.contact_projected,
            "relags": self.relags,
            "budget_stop": self.budget_stop,
        }


#: iterations after an indefinite exact Hessian that go straight to the contact projection
EXACT_RETRY = 3
#: lagged terms are re-lagged when the residual is below this fraction of the start's
RELAG_AT = 1e-3

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
    reference_norm: float | None = None,
    path_free: Callable[[np.ndarray, np.ndarray], bool] | None = None,
    contact_projection: bool = False,
    relag: Callable[[np.ndarray], bool] | None = None,
    max_relags: int = 0,
    budget: dict | None = None,
    physical_default: bool = False,
    start: Accumulator | None = None,
    relag_early: bool = True,
    prescribed_from: np.ndarray | None = None,
) -> tuple[np.ndarray, NewtonResult]:
    """Minimise Phi from x0 (prescribed DOFs already at their values) over the free DOFs.

    evaluate(x, order, project) -> Accumulator with value / gradient / Hessian data; project
    is False (exact), True (every part projected to PSD) or "contact" (only the contact part).
    retract(x, dx) -> the point reached from x by the step dx: x + dx (the default) for vector
    DOFs; frame rotations are updated multiplicatively, R <- exp(dtheta^) R, so the
    configuration x and the step dx (a tangent vector) may even differ in size. The gradient and
    Hessian from ``evaluate`` are then with respect to dx at 0.
    max_step(x, y) -> the largest fraction of the move x -> y that is free of intersection
    (contact's CCD); every line search starts there instead of at 1.
    path_free(x, y) -> whether the straight move x -> y is free of intersection: checked for
    every line-search trial when ``retract`` does not move the surfaces on straight lines
    (rigid frames rotate their points on arcs), so no accepted iterate intersects.
    reference_rows: the gradient rows whose starting norm sets the relative tolerance and
    whose values the physical criterion checks (default all): the moving-obstacle solve leaves
    out its obstacles' rows, whose penalty forces at the start dwarf the bodies'.
    reference_norm: the gradient norm the relative tolerance is taken of, instead of the
    start's: a start near the solution (the contact predictor's) would otherwise be held to
    a tighter absolute tolerance the better it is.
    contact_projection: try "contact" before shifting an indefinite exact Hessian.
    physical_default: whether criterion "auto" uses the physical criterion (contact steps).
    relag(x) -> whether re-lagging at x changed Phi (then up to ``max_relags`` times).
    budget: an interactive step's {"deadline": time.perf_counter() value, "iterations": n}
    (either may be left out); when it runs out after at least one iteration the solve stops
    with ``budget_stop`` set (every iterate is intersection-free: the caller may accept it).
    start: evaluate(x0, 1, False) when the caller has it already.
    prescribed_from: the step's start (prescribed DOFs at their old values): where x0 holds an
    inverted element, Newton starts from the linear response to the prescribed increment
    (``tangent_start.py``, FEBio's first iteration) if that one holds none.
    Returns the final x and the record.
    """
    result = NewtonResult()
    retract = retract or _add
    x = x0.copy()
    current = evaluate(x, 1, False) if start is None else start
    free = np.ones(current.gradient.size, dtype=bool)
    free[elimination.dofs] = False
    checked = free.copy()
    if reference_rows is not None:
        checked[: reference_rows.start] = False
        checked[reference_rows.stop :] = False
    vector = prescribed_from is not None and prescribed_from.shape == x0.shape
    if not np.isfinite(current.value) and vector and current.gradient.shape == x0.shape:
        xs = x0.copy()
        xs[elimination.dofs] = prescribed_from[elimination.dofs]
        found = tangent_start(evaluate, x0, xs, elimination, solver, retract)
        if found is not None:
            x, current = found
    if not np.isfinite(current.value):
        result.reason = "the starting point has infinite energy (an inverted element?)"
        return x, result
    g0 = float(np.linalg.norm(current.gradient[free]))
    reference = float(np.linalg.norm(current.gradient[checked]))
    if reference_norm is not None:
        reference = max(reference, float(reference_norm))
    target = options.gradient_tolerance * reference + options.absolute_tolerance * force_scale
    use_physical = options.criterion == "physical" or (
        options.criterion == "auto" and physical_default
    )
    force_target = options.force_tolerance * force_scale if use_physical else 0.0
    result.gradient_norms.append(g0)
    result.energies.append(current.value)
    shift = 0.0  # Levenberg-Marquardt shift of "auto", kept between iterations
    exact_failed = -10  # the last iteration whose exact Hessian was not positive definite
    # round-off of Phi: relative to the model's energy scale (force x length), not to |Phi|,
    # which can be tiny next to the terms it sums (a small net energy of large parts)
    noise_scale = force_scale * length_scale

    def physical(alpha: float, step: float, g_old: float, g_new: float, acc) -> bool:
        if not use_physical or alpha < 1.0:
            return False
        if np.max(np.abs(acc.gradient[checked]), initial=0.0) > force_target:
            return False
        # relative to how far this solve has moved the DOFs (a probe's 50 um step and a
        # stroke's millimetre get the same relative accuracy), never below round-off
        moved = max(sum(result.step_norms), 1e-9 * length_scale)
        return step * g_new / max(g_old, 1e-300) <= options.displacement_tolerance * moved

    def converged_at(x, acc, reason: str) -> tuple[bool, object]:
        """The lag re-set at a converged x; True when nothing changed (or no relag left)."""
        if relag is None or result.relags >= max_relags or not relag(x):
            result.converged, result.reason = True, reason
            return True, acc
        result.relags += 1
        acc = evaluate(x, 1, False)
        result.gradient_norms[-1] = float(np.linalg.norm(acc.gradient[free]))
        result.energies[-1] = acc.value
        if force_target > 0.0 and np.max(np.abs(acc.gradient[checked])) <= force_target:
            result.converged, result.reason = True, reason  # the new lag is balanced too
            return True, acc
        return False, acc

    # lagged terms are re-lagged once the solve is loosely converged, not at the tight target:
    # the lag only needs the point to about RELAG_AT of the start's residual, and re-lagging
    # there saves the iterations from it to the target (they are redone after the re-lag)
    # (``relag_early`` False: only at converged points, as FEBio augments its contact)
    relag_target = max(target, RELAG_AT * reference) if relag_early else target
    iteration = 0
    lagged_at = 0  # the iteration of the last re-lag: max_iterations counts from there (an
    # augmented Lagrangian's augmentations are each a solve, as FEBio counts them)
    while True:
        gnorm = result.gradient_norms[-1]
        if relag is not None and result.relags < max_relags and gnorm <= relag_target:
            result.relags += 1
            if relag(x):
                lagged_at = iteration
                current = evaluate(x, 1, False)
                result.gradient_norms[-1] = float(np.linalg.norm(current.gradient[free]))
                result.energies[-1] = current.value
                gnorm = result.gradient_norms[-1]
        if gnorm <= target:
            done, current = converged_at(x, current, "gradient")
            if done:
                break
            lagged_at = iteration
            continue
        if iteration >= 1 and _budget_spent(budget, iteration):
            result.budget_stop = True
            result.reason = "stopped by the step's budget before converging"
            break
        if iteration - lagged_at >= options.max_iterations:
            result.reason = f"no convergence in {options.max_iterations} iterations"
            break
        system = {}  # the assembled (eliminated) system at x, built at most once per kind
        # contact steps take inexact Newton steps (a forcing term proportional to the
        # gradient's decrease so far keeps the quadratic rate; module docstring), while the
        # steps are full ones: a shortened step says the model is poor, and an inexact
        # direction there (a stale factor's, by Woodbury with the contact) cost a grasp at
        # 3e4 tetrahedra 117 iterations and a halving where exact ones took 36
        full = not result.step_lengths or result.step_lengths[-1] >= 1.0
        forcing = float(min(FORCING, gnorm / max(g0, 1e-300))) if full else 0.0

        def attempt(project, s: float, x=x, system=system, forcing=forcing):
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
                forcing,
            )

        if options.hessian_projection == "always":
            accepted = attempt(True, 0.0)
        elif options.hessian_projection == "never":
            accepted = attempt(False, 0.0)
        else:
            kind = False
            # after an indefinite exact Hessian, "contact" first for a few iterations (each
            # failed try costs a factorisation)
            if contact_projection and iteration - exact_failed <= EXACT_RETRY:
                kind = "contact"
            accepted = attempt(kind, shift)
            if accepted is None and kind is False and contact_projection and shift == 0.0:
                exact_failed = iteration
                kind = "contact"
                accepted = attempt(kind, 0.0)
            while accepted is None:
                shift = max(10.0 * shift, 1e-6)
                if shift > 1e4:  # the shifted Hessian is nearly a scaled gradient: project
                    accepted = attempt(True, 0.0)
                    shift = 1e-3
                    break
                accepted = attempt(kind, shift)
            if accepted is not None and accepted[0] is not True:
                shift = shift / 10.0 if shift > 1e-6 else 0.0
        if accepted is None:
            result.reason = "no descent step found (line search failed)"
            break
        project, dx, alpha, new = accepted
        x = retract(x, alpha * dx)
        current = new
        iteration += 1
        result.iterations = iteration
        result.projected.append(project is True)
        result.contact_projected.append(project == "contact")
        result.step_lengths.append(alpha)
        result.step_norms.append(float(np.max(np.abs(alpha * dx))))
        result.gradient_norms.append(float(np.linalg.norm(current.gradient[free])))
        result.energies.append(current.value)
        g_old, g_new = result.gradient_norms[-2], result.gradient_norms[-1]
        if g_new <= target:
            continue  # the loop's head converges (and re-lags)
        if physical(alpha, result.step_norms[-1], g_old, g_new, current):
            done, current = converged_at(x, current, "physical")
            if done:
                break
            lagged_at = iteration
            continue
        if result.step_norms[-1] <= options.step_tolerance * length_scale:
            if g_new <= 1e3 * target:
                done, current = converged_at(x, current, "round-off (step below step_tolerance)")
                if done:
                    break
                lagged_at = iteration
                continue
            result.reason = "stagnated: steps below step_tolerance, gradient still large"
            break
    result.energy_terms = dict(current.terms)
    result.gradient = current.gradient
    return x, result


#: the relative residual a contact step's linear solve needs at most (``forcing`` in
#: ``minimize``): at 1e4 tetrahedra half the back-solves of the barrier's palpation, grasp and
#: drop for 0-1 more Newton iterations a step; a contact-free step (1.85 iterations) took
#: 3.05 with it and is solved to the solver's own tolerance
FORCING = 0.1


def _budget_spent(budget: dict | None, iteration: int) -> bool:
    """Whether an interactive budget ({"deadline", "iterations"}) has run out."""
    if not budget:
        return False
    deadline, iterations = budget.get("deadline"), budget.get("iterations")
    return (deadline is not None and time.perf_counter() >= deadline) or (
        iterations is not None and iteration >= iterations
    )


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
    forcing: float | None = None,
):
    """Solve (H + shift diag|H|) dx = -g for an eliminated system ``acc`` and line-search;
    with a contact Hessian and a reused factor, to the relative residual ``forcing`` (at most
    the solver's own tolerance where that is looser).

    Returns (project, dx, alpha, accumulator at the new point) or None when the matrix is not
    positive definite, dx is no descent direction, or no step length is acceptable."""
    g = acc.gradient
    H = acc.hessian
    if shift > 0.0:
        H = H.copy()
        diag = acc.pattern.diagonal
        H[diag] += shift * np.abs(H[diag])
    A = acc.pattern.matrix(H)
    update = None
    if acc.extra_hessian is not None:  # contact's, local: a reused factor takes it apart
        update = elimination.eliminate_matrix(acc.extra_hessian).tocsr()
        A = A + update
    try:
        # inexact only where the contact rides on the factor (Woodbury): with a plain stale
        # factor a loose CG took a cut beam's falling pieces 23 iterations a step, not 15
        factorize_with_update(solver, A.tocsr(), update, forcing)
        dx = solver.solve(-g)
    except NotPositiveDefiniteError:
        return None
    slope = float(g @ dx)
    if not np.all(np.isfinite(dx)) or slope >= -1e-14 * np.linalg.norm(g) * np.linalg.norm(dx):
        return None  # not a descent direction: the (shifted) Hessian was indefinite
    first = 1.0 if max_step is None else min(1.0, max_step(x, retract(x, dx)))
    if first <= 0.0:
        return None
    step = line_search(evaluate, x, acc, slope, dx, options, retract, noise_scale, first, path_free)
    if step is None:
        return None
    return (project, dx, *step)
