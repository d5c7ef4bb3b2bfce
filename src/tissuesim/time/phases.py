"""A run in phases: consecutive stretches of time, each with its own number of steps, time step
and integrator (a FEBio model's ``<step>`` sections; a static preload followed by a dynamic
release), and the time windows during which a condition holds.

A phase of ``steps`` steps of ``time_step`` s starts where the previous one ends (the first at
the simulation's start time). A step belongs to the phase its end time falls in; after the
last phase, steps continue with the last phase's settings. A window (t0, t1] holds a
condition for every step that ends after t0 and no later than t1, so a condition whose window
closes at a phase's end holds through that phase's last step and is gone from the next one's
first step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from tissuesim import validate
from tissuesim.errors import InputError

__all__ = ["Phase", "Schedule", "check_window", "in_window", "PHASE_INTEGRATORS"]

#: the integrators a phase may switch between (the mass a body is built with is the same)
PHASE_INTEGRATORS = ("quasistatic", "backward_euler", "newmark", "generalized_alpha")


@dataclass(frozen=True)
class Phase:
    """``steps`` steps of ``time_step`` s with ``integrator`` (None: the simulation's).

    adaptive: FEBio's adaptive steps over the phase's time (``time/adaptive.py``
    AdaptiveStepping or a dict of its fields): ``time_step`` is then the first step and the
    phase ends at start + steps time_step whatever steps the rule takes (None: the
    simulation's ``adaptive``, or fixed steps)."""

    steps: int
    time_step: float
    integrator: str | None = None
    adaptive: Any = None


def check_window(window, what: str) -> tuple[float, float] | None:
    """A checked window (t0, t1) in s, t0 < t1 (t1 may be inf); None passes through."""
    if window is None:
        return None
    try:
        t0, t1 = (float(v) for v in window)
    except (TypeError, ValueError):
        raise InputError(
            f"{what}: active must be two times [start, end] in s (end may be inf), not "
            f"{validate.short(window)}"
        ) from None
    if math.isnan(t0) or math.isnan(t1) or not t0 < t1 or t0 == math.inf:
        raise InputError(f"{what}: active = [{t0:g}, {t1:g}] must have start < end (s)")
    return t0, t1


def in_window(window: tuple[float, float] | None, t_end: float, tol: float) -> bool:
    """Whether a step ending at t_end lies in the window (t0, t1] (None: always)."""
    if window is None:
        return True
    return window[0] + tol < t_end <= window[1] + tol


class Schedule:
    """Phases from ``start`` (s); ``at(t)`` gives the phase a step starting at t belongs to."""

    def __init__(self, phases: Sequence[Phase | dict], start: float, explicit: bool) -> None:
        from tissuesim.time.adaptive import check_adaptive
        from tissuesim.time.attempts.retry import validate_stepping

        if explicit:
            raise InputError(
                "phases: an explicit simulation cannot switch integrators between phases; "
                "use integrator = 'backward_euler' or 'quasistatic'"
            )
        if isinstance(phases, (str, bytes)) or not isinstance(phases, Sequence) or not phases:
            raise InputError(f"phases must be a non-empty list of phases, not {phases!r:.60}")
        self.phases: list[Phase] = []
        self.bounds: list[tuple[float, float]] = []  # (start, end) of each phase, s
        t = start
        for k, p in enumerate(phases, start=1):
            what = f"phase {k}"
            if isinstance(p, dict):
                unknown = set(p) - {"steps", "time_step", "integrator", "adaptive"}
                if unknown:
                    raise InputError(
                        f"{what}: unknown key {sorted(unknown)[0]!r}; a phase has steps, "
                        "time_step, integrator and adaptive"
                    )
                if "steps" not in p or "time_step" not in p:
                    raise InputError(f"{what}: needs steps and time_step")
                p = Phase(p["steps"], p["time_step"], p.get("integrator"), p.get("adaptive"))
            elif not isinstance(p, Phase):
                raise InputError(f"{what}: expected a Phase or a dict, not {p!r:.60}")
            steps = validate.integer(p.steps, f"{what} steps", low=1, high=10**9)
            h, _ = validate_stepping(p.time_step, 0)
            integrator = p.integrator
            if integrator is not None:
                integrator = validate.choice(integrator, f"{what} integrator", PHASE_INTEGRATORS)
            adaptive = check_adaptive(p.adaptive, f"{what} adaptive")
            self.phases.append(Phase(steps, h, integrator, adaptive))
            self.bounds.append((t, t + steps * h))
            t += steps * h

    @property
    def end(self) -> float:
        """Where the last phase ends (s)."""
        return self.bounds[-1][1]

    @property
    def steps(self) -> int:
        """The steps of all phases together."""
        return sum(p.steps for p in self.phases)

    def at(self, t: float) -> tuple[Phase, float, float]:
        """(phase, its start, its end) for a step starting at t; past the end, the last phase
        continued (its end: inf)."""
        for p, (t0, t1) in zip(self.phases, self.bounds, strict=True):
            if t < t1 - 1e-9 * p.time_step:
                return p, t0, t1
        return self.phases[-1], self.bounds[-1][0], math.inf

    def end_time(self, t: float) -> float:
        """The end of the step that starts at t: on its phase's grid (no running sum), capped
        at the phase's end; a time off the grid steps by one time step."""
        p, t0, t1 = self.at(t)
        h = p.time_step
        k = round((t - t0) / h)
        if abs(t0 + k * h - t) <= 1e-9 * h:
            end = t0 + (k + 1) * h
        else:
            end = t + h
        return t1 if abs(end - t1) <= 1e-9 * h or end > t1 else end
