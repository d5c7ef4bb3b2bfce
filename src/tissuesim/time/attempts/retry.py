"""Advancing one time step, splitting it into halves when Newton fails (as FEBio does).

A failed step of length h is retried as two steps of h/2, recursively, down to
h / 2**max_halvings; if that still fails, ConvergenceError says when, why, and what to try.
Around every attempt ``time/attempts/history.py`` freezes the bodies' internal variables and,
once the attempt converged, updates them.
"""

from __future__ import annotations

from dataclasses import replace

from tissuesim.errors import ConvergenceError, InputError
from tissuesim.time.attempts.history import begin_attempt, end_attempt
from tissuesim.time.state import State, StepOutcome

__all__ = ["advance", "validate_stepping"]

DEFAULT_ADVICE = (
    "Try a smaller time_step, more newton.max_iterations, or a material defined for inverted "
    "elements (course_neo_hookean)."
)
#: in a quasistatic run a shorter step changes only what depends on t: a constant load (full
#: gravity from the start) is as hard at h / 64 as at h
QUASISTATIC_ADVICE = (
    "In a quasistatic run a shorter step only helps loads and supports that change with t: "
    "apply the load gradually (as an expression of t over several steps), raise "
    "newton.max_iterations, or use integrator = 'backward_euler'."
)


def advance(
    step_fn,
    model,
    state: State,
    h: float,
    solver,
    options,
    max_halvings: int,
    end_time: float | None = None,
    advice: str | None = None,
):
    """Advance by h; returns (new State, list of NewtonResult, number of substeps).

    advice: what the error says to try when even the smallest step fails (default: a smaller
    time step, more iterations, an inversion-safe law).

    end_time: the time the new state gets (start + n h, given by the caller) instead of the
    running sum of (sub)step lengths, which drifts by round-off (ten steps of 0.1 would end
    at 0.9999999999999999)."""
    records, substeps = [], 0

    def attempt(s: State, dt: float, level: int) -> State:
        nonlocal substeps
        begin_attempt(model, s, dt)  # internal variables frozen for the attempt
        try:
            outcome: StepOutcome = step_fn(model, s, dt, solver, options)
        except BaseException:
            end_attempt(model, StepOutcome(None, False))
            raise
        end_attempt(model, outcome)  # updated once, only if it converged
        records.extend(outcome.newton)
        if outcome.converged:
            substeps += 1
            return outcome.state
        if level >= max_halvings:
            raise ConvergenceError(
                f"the step from t = {s.time:.6g} s with time_step {dt:.3g} s did not converge "
                f"after {max_halvings} halvings: {outcome.reason}. {advice or DEFAULT_ADVICE}"
            )
        mid = attempt(s, dt / 2, level + 1)
        return attempt(mid, dt / 2, level + 1)

    new_state = attempt(state, h, 0)
    if end_time is not None:
        new_state = replace(new_state, time=float(end_time))
    return new_state, records, substeps


def validate_stepping(time_step, max_step_halvings) -> tuple[float, int]:
    """Checked (1e-12 s <= time_step <= 1e9 s, 0 <= max_step_halvings <= 30) for every
    simulation object: outside, the inertia scale 1/h^2 over- or underflows."""
    from tissuesim import validate

    h = validate.real(time_step, "time_step", low=0.0, low_open=True, unit="s")
    if not MIN_TIME_STEP <= h <= MAX_TIME_STEP:
        raise InputError(
            f"time_step {h:g} s is outside {MIN_TIME_STEP:g}..{MAX_TIME_STEP:g} s, where the "
            "inertia term 1/h^2 over- or underflows; choose a time step in that range"
        )
    return h, validate.integer(max_step_halvings, "max_step_halvings", low=0, high=30)


MIN_TIME_STEP, MAX_TIME_STEP = 1e-12, 1e9
