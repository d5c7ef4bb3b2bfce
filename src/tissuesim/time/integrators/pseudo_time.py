"""Quasistatic steps for bodies that only contact holds (an organ resting on a table, pressed by
a probe): pseudo-transient continuation.

A quasistatic step minimises Phi(x) = E(x) - f(t_{n+1}) . x + B(x) (elasticity, loads, the
contact barrier and friction). For a body with no support that minimum is only reached once the
body rests on something, and until then Newton has nothing to stand on: the free body's
Hessian is singular (rigid motions) and the first steps would send it anywhere. So the step is
taken as a sequence of Backward Euler steps *from rest* at the fixed time t_{n+1} (loads,
prescribed values and obstacles there), with pseudo-time steps tau_k growing geometrically:

    x_{k+1} = argmin_x Phi(x) + 1/(2 tau_k^2) |x - x_k|_M^2,   tau_{k+1} = GROWTH tau_k,

each an ordinary implicit step (CCD-limited line search: no iterate intersects). The proximal
term's gradient M (x_{k+1} - x_k) / tau_k^2 is the only difference from the static balance, so
the sequence stops when the *static* residual |grad Phi(x_{k+1})| on the free DOFs is below
TOLERANCE of the step's force scale (the start's residual, or, for bodies already at rest,
the force their contacts carry there; at least the model's absolute tolerance): then x_{k+1} is
a quasistatic equilibrium to that accuracy, reactions and contact forces included. The first
tau lets the unbalanced start fall FIRST_MOTION of the body's size. Friction slides from the
physical step's start (not from each pseudo-step's), with its smoothing velocity scaled by the
physical load step, as in a quasistatic step of a supported body. A pseudo-step that fails is
retried with tau / 4, which then stays the longest (the proximal iteration converges at a fixed
tau too); the step fails (and is halved by the caller) after MAX_FAILURES of them or when the
body has not come to rest in MAX_PSEUDO_STEPS.
"""

from __future__ import annotations

import numpy as np

from tissuesim.system import is_frame_body
from tissuesim.time.state import State, StepOutcome
from tissuesim.time.steps import EnergyBuilder, implicit_step

__all__ = ["pseudo_time_step", "MAX_PSEUDO_STEPS", "TOLERANCE", "GROWTH"]

#: the static residual, relative to the step's start, at which the body is at rest
TOLERANCE = 1e-6
#: pseudo-time step growth per pseudo-step
GROWTH = 2.0
#: the first pseudo-step lets the unbalanced start fall this fraction of the body's size
FIRST_MOTION = 0.01
MAX_PSEUDO_STEPS = 60
MAX_FAILURES = 6


def pseudo_time_step(
    system,
    state: State,
    h: float,
    solver,
    options,
    *,
    energies: EnergyBuilder,
    budget: dict | None = None,
) -> StepOutcome:
    """One quasistatic step of length h for a system held by contact (see the module
    docstring); the returned state is at rest (zero velocity) at t_n + h."""
    t1 = state.time + h
    contact = system.contact
    static = energies(t1, None, h)
    zero = np.zeros(system.n_dofs)
    free = np.ones(system.n_dofs, dtype=bool)
    free[system.elimination.dofs] = False

    def residual(c: np.ndarray, lagged: bool, with_contact: bool = True) -> float:
        if lagged:
            with contact.last_step_lag():
                g = system.evaluate(c, 1, False, static, contact=with_contact).gradient
        else:
            g = system.evaluate(c, 1, False, static, contact=with_contact).gradient
        return float(np.linalg.norm(g[free]))

    x = system.apply_prescribed(state.x, t1)
    if contact.moving and contact.obstacle_state is None:
        contact.obstacle_state = contact.obstacle_positions(state.time)
    contact.time = t1
    y_start = contact.obstacle_state if contact.moving else None
    friction_from = contact.vertices(state.x, obstacle=y_start) if contact.has_friction else None
    # the scale of the balance: the start's residual at the end's loads, or (a body already
    # at rest) what contact carries there, the residual without it
    scale = max(residual(x, lagged=False), residual(x, lagged=False, with_contact=False))
    target = max(TOLERANCE * scale, options.absolute_tolerance * system.force_scale)
    tau = _first_pseudo_step(system, x, static, free)
    records, failures, ceiling = [], 0, np.inf
    current = State(state.time, state.x, zero)
    for _ in range(MAX_PSEUDO_STEPS):
        outcome = implicit_step(
            system,
            current,
            tau,
            solver,
            options,
            dynamic=True,
            energies=energies,
            budget=budget,
            t_end=t1,
            friction_from=friction_from,
            friction_h=h,
        )
        records.extend(outcome.newton)
        if not outcome.converged:
            failures += 1
            if failures > MAX_FAILURES:
                return StepOutcome(None, False, records, f"pseudo-time: {outcome.reason}")
            # no longer steps than the last that converged: a body held only where it touches
            # (no friction) has near-free motions that a long pseudo-step leaves unchecked
            tau = ceiling = tau / 4.0
            continue
        current = State(state.time, outcome.state.x, zero)
        if residual(current.x, lagged=True) <= target:
            return StepOutcome(State(t1, current.x, zero), True, records)
        tau = min(GROWTH * tau, ceiling)
    return StepOutcome(
        None,
        False,
        records,
        f"the bodies did not come to rest on their contacts in {MAX_PSEUDO_STEPS} pseudo-time "
        "steps (nothing holds them there?)",
    )


def _first_pseudo_step(system, x: np.ndarray, static, free: np.ndarray) -> float:
    """The pseudo-time step in which the start's unbalanced force moves the bodies about
    FIRST_MOTION of their size: tau = sqrt(2 d / a) with a = |f| / m over the free DOFs."""
    g = system.evaluate(x, 1, False, static, contact=False).gradient
    mass = np.zeros(system.n_dofs)  # lumped, per DOF; frame bodies' DOFs left out
    for j, body in enumerate(system.bodies):
        if not is_frame_body(body):
            mass[system.tangent_slices[j]] = body.mass.lumped
    counted = free & (mass > 0.0)
    force = float(np.abs(g[counted]).sum())
    m = float(mass[counted].sum())
    if force <= 0.0 or m <= 0.0:
        return 1.0
    a = force / m
    return float(np.sqrt(2.0 * FIRST_MOTION * system.length_scale / a))
