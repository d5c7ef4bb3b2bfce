"""Advancing one time step, splitting it into halves when Newton fails (as FEBio does).

A failed step of length h is retried as two steps of h/2, recursively, down to
h / 2**max_halvings; if that still fails, ConvergenceError says when, why, and what to try.
"""

from __future__ import annotations

import numbers
from dataclasses import replace

import numpy as np

from tissuesim.errors import ConvergenceError
from tissuesim.time.state import State, StepOutcome

__all__ = ["advance", "validate_stepping"]


def advance(
    step_fn,
    model,
    state: State,
    h: float,
    solver,
    options,
    max_halvings: int,
    end_time: float | None = None,
):
    """Advance by h; returns (new State, list of NewtonResult, number of substeps).

    end_time: the time the new state gets (start + n h, given by the caller) instead of the
    running sum of (sub)step lengths, which drifts by round-off (ten steps of 0.1 would end
    at 0.9999999999999999)."""
    records, substeps = [], 0

    def attempt(s: State, dt: float, level: int) -> State:
        nonlocal substeps
        outcome: StepOutcome = step_fn(model, s, dt, solver, options)
        records.extend(outcome.newton)
        if outcome.converged:
            substeps += 1
            return outcome.state
        if level >= max_halvings:
            raise ConvergenceError(
                f"the step from t = {s.time:.6g} s with time_step {dt:.3g} s did not converge "
                f"after {max_halvings} halvings: {outcome.reason}. Try a smaller time_step, more "
                "newton.max_iterations, or a material defined for inverted elements "
                "(course_neo_hookean)."
            )
        mid = attempt(s, dt / 2, level + 1)
        return attempt(mid, dt / 2, level + 1)

    new_state = attempt(state, h, 0)
    if end_time is not None:
        new_state = replace(new_state, time=float(end_time))
    return new_state, records, substeps


def validate_stepping(time_step, max_step_halvings) -> tuple[float, int]:
    """Checked (time_step > 0 s, max_step_halvings >= 0) for every simulation object."""
    if not (
        isinstance(time_step, numbers.Real)
        and not isinstance(time_step, bool)
        and np.isfinite(time_step)
        and time_step > 0
    ):
        raise ValueError(f"time_step must be > 0 seconds, not {time_step!r}")
    if not (isinstance(max_step_halvings, numbers.Integral) and max_step_halvings >= 0):
        raise ValueError(f"max_step_halvings must be an integer >= 0, not {max_step_halvings!r}")
    return float(time_step), int(max_step_halvings)
