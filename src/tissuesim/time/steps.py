"""One time step of a whole system (``system.py``): implicit (Backward Euler, quasistatic) or
explicit (symplectic Euler). The same code steps one body or many.

Backward Euler (notes, eq. 3-7; Bosman et al. 3.3.2 for frames) minimises, over every body at
once, the incremental potential

    Phi(c) = sum_bodies [ 1/(2 h^2) |c - c_pred|_M^2 + E(c) - f(t_{n+1}) . c ] + couplings,

with c_pred = c_n (+) h v_n (frame rotations advanced multiplicatively), and
v_{n+1} = (c_{n+1} (-) c_n) / h. Quasistatics drops the inertia and reports zero velocity.
Newton starts from the better (lower Phi) of c_pred and c_n: in violent phases (folding) the
prediction can invert many elements at once. Prescribed DOFs take their values at t_{n+1}.
After convergence Newton's last gradient (at c_{n+1}, prescribed DOFs included) is in the
record: at prescribed DOFs it is the force the constraint applies, the reaction.

Explicit (symplectic Euler, eq. 18 for frames): a = M^-1 (f(t_n) - dE/dc(c_n)) per body, FEM
bodies with their lumped (diagonal) mass, frame bodies with the generalised tangent mass
M_q = T^T M_z T and the centripetal term; v_{n+1} = v_n + h a, c_{n+1} = c_n (+) h v_{n+1}.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse.linalg as spla

from tissuesim.errors import InputError, InstabilityError
from tissuesim.solve.newton import minimize
from tissuesim.system import is_frame_body
from tissuesim.time.attempts.start import choose_start
from tissuesim.time.contact_step import (
    accurate_start,
    barrier_pull,
    certify,
    interactive_step,
    resolve_mode,
)
from tissuesim.time.lags import StepLags, lagged_pressure
from tissuesim.time.state import State, StepOutcome

__all__ = ["implicit_step", "explicit_step", "EnergyBuilder"]

#: energies(t, c_pred or None, h) -> one list of extra energies per body (configuration space)
EnergyBuilder = Callable[[float, np.ndarray | None, float], list[list]]


def implicit_step(
    system,
    state: State,
    h: float,
    solver,
    options,
    *,
    dynamic: bool,
    energies: EnergyBuilder,
    budget: dict | None = None,
    t_end: float | None = None,
    friction_from: np.ndarray | None = None,
    friction_h: float | None = None,
) -> StepOutcome:
    """One implicit step; ``budget`` ({"deadline": perf_counter value, "iterations": n}) ends
    Newton early for interactive loops: the state reached is accepted and flagged.

    For pseudo-time steps (``time/integrators/pseudo_time.py``): ``t_end`` the time of the
    loads, the prescribed values and the obstacles (default state.time + h, while h sets the
    inertia); ``friction_from`` the contact vertices friction's slip is measured from (default
    the state's) and ``friction_h`` the step its smoothing velocity scales with (default h).

    With ``method = "febio"`` and ``febio_fallback``, a step FEBio's solver gives up on is
    solved again by tissuesim's Newton from the same start (the lagged terms as they were)
    before the caller halves it (FEBio's adaptive stepper: on its last attempt only,
    ``time/adaptive.py attempt_options``): our Quasin stops in a few models where FEBio's own
    does not (benchmarks/results/febio_suite_febio_solver.md), and a step converged tightly is
    within FEBio's tolerance of FEBio's answer."""
    if options.method == "febio" and options.febio_fallback:
        return _with_fallback(
            system, state, h, solver, options, dict(dynamic=dynamic, energies=energies,
            budget=budget, t_end=t_end, friction_from=friction_from, friction_h=friction_h),
        )  # fmt: skip
    if options.method == "febio" and system.contact is not None:
        raise InputError("newton method 'febio' does not run with barrier contact: use 'newton'")
    t1 = state.time + h if t_end is None else t_end
    c_pred = system.retract(state.x, h * state.v) if dynamic else None
    body_energies = energies(t1, c_pred, h)

    def evaluate(c: np.ndarray, order: int, project):
        return system.evaluate(c, order, project, body_energies)

    candidates = plain = (c_pred, state.x) if dynamic else (state.x,)
    contact = system.contact
    max_step = None
    reference_norm, lag_at = None, None
    if contact is not None:
        contact.time = t1
        y0, y1 = None, None
        if contact.moving:
            y0 = contact.obstacle_state
            if y0 is None:
                y0 = contact.obstacle_positions(state.time)
            y1 = contact.obstacle_positions(t1)
        contact.begin_step()
        predicted = None
        # the step's contacts predicted on the compliance first (time/contact_step.py), except
        # in pseudo-time steps and with a blade in its kerf (their starts are special)
        mode = "barrier"
        if t_end is None and friction_from is None and contact.clear_path is None:
            mode = resolve_mode(contact, budget)
        if mode == "interactive":
            done = interactive_step(
                system, state, h, solver, options, dynamic, body_energies, t1, y0, y1, budget
            )
            if done is not None:
                return done
        elif mode == "accurate":
            predicted, reference_norm = accurate_start(
                system, state, h, solver, options, dynamic, body_energies, t1, y0, y1
            )
        starts = []
        if predicted is not None:
            # the predictor's start, certified as an interactive step is (its straight move
            # from x_n is a chord through a curved instrument): Newton's only start, friction
            # lagged there
            c = system.apply_prescribed(predicted, t1)
            if certify(contact, state.x, c, y0, y1):
                starts, lag_at = [c], c
        if lag_at is None:
            reference_norm = None
            # Newton must start where the bodies can get from x_n without crossing a surface,
            # the obstacles and prescribed vertices moving to their t1 places on the way: with
            # moving obstacles the prediction c_n + h v_n carries the surface under an
            # instrument along with it, so the obstacles can sit at their targets from the
            # start (one solve)
            starts = _reachable_starts(system, state, candidates, t1, y0, y1)
        if not starts and contact.moving and contact.clear_path is not None:
            starts = _cleared_starts(system, contact, state.x, candidates, y0, y1, t1)
        if not starts and contact.moving:  # an instrument runs into a body at rest: pull it in
            return _step_with_moving_obstacles(
                system,
                state,
                h,
                solver,
                options,
                dynamic,
                body_energies,
                candidates,
                evaluate,
                budget,
                t1,
                friction_from,
                friction_h,
            )
        if not starts:
            return StepOutcome(
                None,
                False,
                [],
                "the obstacles' or prescribed motion in this step crosses a surface",
            )
        if contact.moving:
            contact.obstacle_state = y1
        candidates = tuple(starts)
        max_step = contact.max_step
    # the step's start, prescribed DOFs where they were: where the prescribed motion alone
    # inverts an element, Newton starts from the linear response to it (FEBio's first
    # iteration; solve/tangent_start.py)
    solve = minimize
    if options.method == "febio":  # FEBio's Quasin (solve/quasin.py): from x_n, as FEBio
        from tissuesim.solve.quasin import follow_pressures, minimize_febio

        solve, candidates = minimize_febio, (state.x,)
    start_acc = None
    if contact is None and not lagged_pressure(body_energies):
        # the start's gradient is Newton's first evaluation: kept (nothing is set at c0)
        c0, start_acc = choose_start(
            evaluate, candidates, lambda c: system.apply_prescribed(c, t1), keep=True
        )
    else:
        c0 = choose_start(evaluate, candidates, lambda c: system.apply_prescribed(c, t1))
    friction = None
    if contact is not None:
        # IPC's adaptive kappa balances the other forces at the start the barrier alone would
        # take, also when Newton starts at the prediction: the same kappa, the same answer
        start = c0
        if lag_at is not None and contact.adaptive is not None:
            if not contact.adaptive.initialized:
                reached = _reachable_starts(system, state, plain, t1, y0, y1)
                reached = reached or [system.apply_prescribed(state.x, t1)]
                start = choose_start(evaluate, tuple(reached), lambda c: c)
        _initialize_stiffness(system, start, body_energies)
        if contact.has_friction:
            # friction lagged at the last solution (IPC): normal forces, tangent bases
            friction = _start_friction(
                contact, state.x, y0, h, friction_from, friction_h, lag_at, y1
            )
    lags = StepLags(system, body_energies, c0, options, contact, friction, state.x)
    if options.method == "febio":  # FEBio's follower pressures: the load at x in every residual
        lags.pressures = follow_pressures(lags.pressures)
    relag, max_relags = lags.newton_relag(), lags.max_relags

    c1, record = solve(
        evaluate,
        c0,
        system.elimination,
        solver,
        options,
        force_scale=system.force_scale,
        length_scale=system.length_scale,
        retract=system.retract,
        max_step=max_step,
        reference_norm=reference_norm,
        path_free=None if contact is None or contact.linear else contact.path_free,
        contact_projection=contact is not None,
        physical_default=contact is not None,
        relag=relag,
        max_relags=max_relags,
        budget=budget,
        start=start_acc if relag is None else None,
        relag_early=not (lags.penalty or lags.febio_joints),  # FEBio's: at converged points
        prescribed_from=state.x,
        **({"difference": _increment(system)} if options.method == "febio" else {}),
    )
    lags.check(c1, record)
    if contact is not None:
        contact.clear_friction()
        contact.stats.friction_solves += lags.friction_relags + 1 if contact.has_friction else 0
        if not record.converged and not record.budget_stop and contact.moving:
            contact.obstacle_state = y0  # the halved step starts where this one did
    if not record.converged and not record.budget_stop:
        return StepOutcome(None, False, [record], record.reason)
    if contact is not None:
        if record.budget_stop and contact.moving:
            contact.obstacle_state = y1
        if lag_at is not None:  # the barrier's own weights per pair, for the next prediction
            contact.predictor.calibrate(contact, c1, lambda d: barrier_pull(contact, d))
        contact.update_stiffness(c1)
    system.last_step_energies = body_energies  # the step's Phi, for haptics.py's linearisation
    v1 = system.difference(c1, state.x) / h if dynamic else np.zeros(system.n_dofs)
    return StepOutcome(State(t1, c1, v1), True, [record])


def _with_fallback(system, state, h, solver, options, kw: dict) -> StepOutcome:
    """FEBio's solver on the step, then (if it gave up) tissuesim's Newton from the same start
    with the lagged terms as they were (``implicit_step``'s docstring)."""
    from dataclasses import replace

    from tissuesim.time.attempts.history import keep_lags, restore_lags

    kept = keep_lags(system)
    outcome = implicit_step(system, state, h, solver, replace(options, febio_fallback=False), **kw)
    if outcome.converged:
        return outcome
    restore_lags(kept)
    newton = replace(options, method="newton", febio=None)
    retry = implicit_step(system, state, h, solver, newton, **kw)
    if not retry.converged:
        restore_lags(kept)
        return StepOutcome(None, False, outcome.newton + retry.newton, outcome.reason)
    for record in retry.newton:
        record.fallback = True  # counted in the step's extra (simulation/simulation.py)
    return StepOutcome(retry.state, True, outcome.newton + retry.newton)


def _reachable_starts(system, state, candidates, t1, y0, y1) -> list[np.ndarray]:
    """The candidates (prescribed values applied) that the bodies reach from x_n without
    crossing a surface, the obstacles moving from y0 to y1 (or from their places at the
    step's start to t1 when they do not move)."""
    contact = system.contact
    starts = []
    for c in candidates:
        c = system.apply_prescribed(c, t1)
        if contact.moving:
            ok = contact.start_free(state.x, c, y0, y1)
        else:
            ok = contact.reachable(state.x, state.time, c, t1)
        if ok:
            starts.append(c)
    return starts


def _cleared_starts(system, contact, x0, candidates, y0, y1, t1) -> list[np.ndarray]:
    """Starts with the kerf ahead of a blade in contact opened (``contact.clear_path``,
    contact/cut/blade_clearance.py) where the plain ones would put the blade through the faces the
    loaded body closed on its path. A start counts when the bodies get there from x0 with the
    obstacles where they are, and the obstacles then get to their targets, both free of
    intersection (exact CCD): the same proof as one straight move, taken in two legs."""
    starts = []
    for c in candidates:
        cleared = contact.clear_path(system.apply_prescribed(c, t1))
        if cleared is None:
            continue
        cleared = system.apply_prescribed(cleared, t1)
        if contact.start_free(x0, cleared, y0, y0) and contact.start_free(cleared, cleared, y0, y1):
            starts.append(cleared)
    return starts


def _start_friction(
    contact, x0, y0, h, friction_from=None, friction_h=None, lag_at=None, y_lag=None
):
    """Lag friction at the step's start (the configuration x0, obstacles at y0), or at
    ``lag_at`` (obstacles at ``y_lag``: the contact predictor's start, whose normal forces are
    the step's own): slip measured from ``friction_from`` (default x0's vertices), smoothed
    with ``friction_h`` (default h). Returns relag(c, y) that re-lags it at c (obstacles at y,
    or where they are) and says it changed, for Newton's ``relag``."""
    V_here = contact.vertices(x0, obstacle=y0)
    V_start = V_here if friction_from is None else friction_from
    h_f = h if friction_h is None else friction_h
    V_lag = V_here if lag_at is None else contact.vertices(lag_at, obstacle=y_lag)
    contact.lag_friction(V_start, V_lag, h_f)

    def relag(c: np.ndarray, y: np.ndarray | None) -> bool:
        contact.lag_friction(V_start, contact.vertices(c, obstacle=y), h_f)
        return True

    return relag


def _initialize_stiffness(system, c0, body_energies, obstacle=None) -> None:
    """IPC's adaptive barrier stiffness starts when contact first appears (contact/stiffness)."""
    contact = system.contact
    if contact.adaptive is None or contact.adaptive.initialized:
        return
    g = system.evaluate(c0, 1, False, body_energies, contact=False).gradient
    contact.initialize_stiffness(c0, g, system.elimination.dofs, obstacle)


def _step_with_moving_obstacles(
    system,
    state,
    h,
    solver,
    options,
    dynamic,
    body_energies,
    candidates,
    evaluate,
    budget=None,
    t1=None,
    friction_from=None,
    friction_h=None,
) -> StepOutcome:
    """Implicit step in which Newton moves the obstacles too (contact/barrier/kinematic.py): the
    start must only be reachable with the obstacles where they are. Under a budget that runs out the
    obstacles stay where Newton got them (short of their targets, like a haptic proxy).
    ``t1``, ``friction_from``, ``friction_h``: as ``implicit_step``'s t_end and friction."""
    from tissuesim.contact.barrier.kinematic import solve_with_moving_obstacles

    contact = system.contact
    t1 = state.time + h if t1 is None else t1
    if contact.obstacle_state is None:
        contact.obstacle_state = contact.obstacle_positions(state.time)
    y = contact.obstacle_state
    contact.time = t1
    starts = []
    for c in candidates:
        c = system.apply_prescribed(c, t1)
        if contact.max_step(state.x, c, y, y) >= 1.0:
            starts.append(c)
    if not starts:
        return StepOutcome(None, False, [], "the prescribed motion of this step crosses a surface")
    c0 = choose_start(evaluate, starts, lambda c: c)
    _initialize_stiffness(system, c0, body_energies, y)
    friction = None
    if contact.has_friction:
        # inside the solves, as in implicit_step: the lag at the loosely converged point
        friction = _start_friction(contact, state.x, y, h, friction_from, friction_h)
    lags = StepLags(system, body_energies, c0, options, contact, friction, state.x)

    c1, y1, record, results = solve_with_moving_obstacles(
        system,
        c0,
        state.time,
        t1,
        body_energies,
        solver,
        options,
        y0=y,
        budget=budget,
        relag=None if lags.newton_relag() is None else lags.relag,
        max_relags=lags.max_relags,
    )
    lags.check(c1, record)
    contact.clear_friction()
    if contact.has_friction:
        contact.stats.friction_solves += 1 + lags.friction_relags
    if not record.converged and not record.budget_stop:
        return StepOutcome(None, False, results, record.reason)
    contact.obstacle_state = y1
    contact.update_stiffness(c1)
    system.last_step_energies = body_energies
    v1 = system.difference(c1, state.x) / h if dynamic else np.zeros(system.n_dofs)
    return StepOutcome(State(t1, c1, v1), True, [*results[:-1], record])


def explicit_step(
    system,
    state: State,
    h: float,
    *,
    energies: EnergyBuilder,
    limit: Callable,
    keep: dict | None = None,
) -> StepOutcome:
    """``energies(t_n, None, h)``: loads and springs at t_n; ``limit()`` the stability estimate
    (s) quoted when a step blows up; ``keep``: gets the gradient at x_n ("gradient": the
    prescribed DOFs' reactions at t_n, for the forces report)."""
    t0, t1 = state.time, state.time + h
    acc = system.evaluate(state.x, 1, False, energies(t0, None, h))
    if keep is not None:
        keep["gradient"] = acc.gradient
    a = np.zeros(system.n_dofs)
    for j, body in enumerate(system.bodies):
        sc, st = system.config_slices[j], system.tangent_slices[j]
        force = -acc.gradient[st]
        if is_frame_body(body):
            a[st] = _frame_acceleration(body, state.x[sc], state.v[st], force)
        else:
            a[st] = force / body.mass.lumped
    v1 = state.v + h * a
    held = system.prescribed_dofs
    v1[held] = 0.0
    c1 = system.apply_prescribed(system.retract(state.x, h * v1), t1)
    # prescribed DOFs move with their condition: their velocity is the difference quotient
    if held.size:
        v1[held] = (system.difference(c1, state.x) / h)[held]
    moved, size = largest_motion(system, state.x, c1)
    if not (np.all(np.isfinite(c1)) and np.isfinite(acc.value)) or moved > BLOW_UP * size:
        what = "non-finite positions" if not np.isfinite(moved) else f"a point moved {moved:.3g} m"
        raise InstabilityError(
            f"explicit steps blew up at t = {t0:.6g} s ({what} in one step of {h:g} s, more than "
            f"{BLOW_UP:g} x the body size {size:.3g} m: the energy grows without bound); "
            f"time_step {h:g} s exceeds the stability limit (estimate {limit():.3g} s): use a "
            "time_step below the estimate, or integrator = backward_euler"
        )
    return StepOutcome(State(t1, c1, v1), True, [])


#: an explicit step in which a point moves more than this fraction of its body's size is
#: unstable: a stable step moves every point far less than an element (CFL), and no tissue
#: motion covers half its own size in one step
BLOW_UP = 0.5


def largest_motion(system, c0: np.ndarray, c1: np.ndarray) -> tuple[float, float]:
    """(the largest displacement of a FEM vertex or frame origin from c0 to c1 (m), the size
    of that body (m)); (nan, size) if c1 is not finite."""
    worst, size = 0.0, system.length_scale
    for j, body in enumerate(system.bodies):
        sc = system.config_slices[j]
        d = (c1[sc] - c0[sc]).reshape(-1, 12 if is_frame_body(body) else body.mesh.dim)
        d = d[:, :3] if is_frame_body(body) else d
        if not np.all(np.isfinite(d)):
            return float("nan"), body.length_scale
        step = float(np.sqrt(np.max(np.einsum("ij,ij->i", d, d)))) if d.size else 0.0
        if step / body.length_scale > worst / size:
            worst, size = step, body.length_scale
    return worst, size


def _frame_acceleration(body, z: np.ndarray, v: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Solve M_q a = force - T^T M_z c (c: the centripetal part) on the free tangent DOFs."""
    ft = body.frame_type
    rhs = force - ft.tangent_gradient(z, body.mass.dot(ft.centripetal(z, v)))
    free = np.ones(body.n_dofs, dtype=bool)
    free[body.prescribed_dofs] = False
    cache = getattr(body, "_explicit_factor", None)
    if ft.rigid or cache is None or cache[0] is not body.elimination:
        M = body.tangent_mass(z)
        cache = (body.elimination, spla.splu(M[free][:, free].tocsc()))
        if not ft.rigid:
            body._explicit_factor = cache  # affine frames: M_q = M_z is constant
    a = np.zeros(body.n_dofs)
    a[free] = cache[1].solve(rhs[free])
    return a


def _increment(system):
    """The tangent step between two configurations with the vertices linked to rigid bodies
    left out: their stiffness reaches the rigid body's DOFs through the links' reduction
    (rigid/links.py), so an increment on both would count it twice (FEBio's m_Fd sees the
    rigid body's)."""
    links = system.links
    if links is None:
        return system.difference
    return lambda c1, c0: np.where(links.mask, 0.0, system.difference(c1, c0))
