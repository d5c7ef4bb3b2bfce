"""Adaptive time steps as FEBio takes them (``FECore/FETimeStepController.cpp``, FEBio 4).

After a converged step in which Newton took n iterations, the next step is

    s = sqrt(opt_iter / n)
    s >= 1: dt <- dt + (dtmax - dt) min(0.2, s - 1)          (at most dtmax; dtmax 0: none)
    s <  1: dt <- dt - (dt - dtmin) (1 - s)                   (at least dtmin)

where dt is the previous step as the rule set it (not as a must point shortened it) and dtmax
may follow a load curve of t (FEBio's must-point curve, ``dtmax_curve``), whose point times
are then *must points*: a step that would pass one is shortened to end on it exactly. A step
never passes the end of its phase (FEBio's step end). The first step is ``time_step`` clamped
to [dtmin, dtmax].

A step that fails is retried from the same state with a shorter step, at most ``max_retries``
times: with ``aggressiveness = 0`` (FEBio's default) dt - dt_0 / (max_retries + 1), where dt_0
is the step that failed first (so the retries go down linearly), otherwise dt ``cutback``. Unlike
FEBio, a retry never goes below ``dtmin``: a step that fails at dtmin stops the run.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from tissuesim import validate
from tissuesim.errors import ConvergenceError, InputError
from tissuesim.time.attempts.history import begin_attempt, end_attempt
from tissuesim.time.state import State, StepOutcome

__all__ = ["AdaptiveStepping", "TimeStepController", "check_adaptive", "advance_adaptive"]

KEYS = (
    "dtmin", "dtmax", "max_retries", "opt_iter", "aggressiveness", "cutback", "dtforce",
    "must_points", "dtmax_curve", "dtmax_interpolation", "frames",
)  # fmt: skip


@dataclass(frozen=True)
class AdaptiveStepping:
    """FEBio's ``<time_stepper>`` settings (its defaults, dtmax aside).

    dtmin, dtmax: the step's bounds (s); dtmax_curve: points (t, dtmax) instead of dtmax, whose
    times are must points (``dtmax_interpolation`` "linear" or "step", FEBio's LINEAR / STEP,
    constant outside); must_points: further times every run lands on exactly. opt_iter: the
    Newton iterations a step should take; max_retries, aggressiveness, cutback: how a failed
    step is cut back (above); dtforce: always step dtmax. frames: "steps" writes every step
    (FEBio's PLOT_MAJOR_ITRS), "must_points" only the must points and the last step
    (PLOT_MUST_POINTS)."""

    dtmax: float | None = None
    dtmin: float = 0.0
    max_retries: int = 5
    opt_iter: int = 11
    aggressiveness: int = 0
    cutback: float = 0.5
    dtforce: bool = False
    must_points: tuple[float, ...] = ()
    dtmax_curve: tuple[tuple[float, float], ...] | None = None
    dtmax_interpolation: str = "linear"
    frames: str = "steps"

    def dtmax_at(self, t: float) -> float:
        """dtmax at time t (the curve's value, constant outside its points)."""
        if self.dtmax_curve is None:
            return float(self.dtmax)
        p = np.asarray(self.dtmax_curve, dtype=float)
        ts, fs = p[:, 0], p[:, 1]
        if t <= ts[0]:
            return float(fs[0])
        if t >= ts[-1]:
            return float(fs[-1])
        n = int(np.searchsorted(ts, t, side="right"))  # ts[n-1] <= t < ts[n]
        if self.dtmax_interpolation == "step":
            return float(fs[n])
        w = (t - ts[n - 1]) / (ts[n] - ts[n - 1])
        return float(fs[n - 1] + (fs[n] - fs[n - 1]) * w)

    def all_must_points(self) -> np.ndarray:
        """The sorted must points: the curve's times and ``must_points``."""
        times = list(self.must_points)
        if self.dtmax_curve is not None:
            times += [p[0] for p in self.dtmax_curve]
        return np.unique(np.asarray(times, dtype=float))


def check_adaptive(value: AdaptiveStepping | Mapping | None, what: str = "adaptive"):
    """A checked AdaptiveStepping from one or a dict of its fields (None passes through)."""
    if value is None or value is False:
        return None
    if isinstance(value, Mapping):
        unknown = set(value) - set(KEYS)
        if unknown:
            raise InputError(
                f"{what}: unknown key {sorted(unknown)[0]!r}; adaptive stepping has "
                f"{', '.join(KEYS)}"
            )
        value = AdaptiveStepping(**dict(value))
    elif not isinstance(value, AdaptiveStepping):
        raise InputError(f"{what} must be an AdaptiveStepping or a table, not {value!r:.60}")
    v = value
    dtmin = validate.real(v.dtmin, f"{what} dtmin", low=0.0, unit="s")
    curve = None
    if v.dtmax_curve is not None:
        try:
            curve = np.asarray(v.dtmax_curve, dtype=float)
        except (TypeError, ValueError):
            curve = None
        if curve is None or curve.ndim != 2 or curve.shape[1] != 2 or len(curve) < 2:
            raise InputError(f"{what} dtmax_curve must be two or more points [t, dtmax]")
        if not np.all(np.isfinite(curve)) or np.any(np.diff(curve[:, 0]) <= 0):
            raise InputError(f"{what} dtmax_curve: times must be finite and increasing")
        if np.any(curve[:, 1] < 0):
            raise InputError(f"{what} dtmax_curve: dtmax must be >= 0 at every point (0: none)")
        curve = tuple((float(a), float(b)) for a, b in curve)
        dtmax = None if v.dtmax is None else float(v.dtmax)
    else:
        if v.dtmax is None:
            raise InputError(f"{what} needs dtmax (s) or a dtmax_curve")
        dtmax = validate.real(v.dtmax, f"{what} dtmax", low=0.0, low_open=True, unit="s")
        if dtmax < dtmin:
            raise InputError(f"{what}: dtmax {dtmax:g} s is below dtmin {dtmin:g} s")
    must = tuple(float(t) for t in np.atleast_1d(np.asarray(v.must_points, dtype=float)))
    if not all(math.isfinite(t) for t in must):
        raise InputError(f"{what} must_points must be finite times (s)")
    return AdaptiveStepping(
        dtmax=dtmax,
        dtmin=dtmin,
        max_retries=validate.integer(v.max_retries, f"{what} max_retries", low=0, high=1000),
        opt_iter=validate.integer(v.opt_iter, f"{what} opt_iter", low=0, high=10**6),
        aggressiveness=validate.integer(v.aggressiveness, f"{what} aggressiveness", low=0),
        cutback=validate.real(v.cutback, f"{what} cutback", low=0.0, high=1.0, low_open=True),
        dtforce=bool(v.dtforce),
        must_points=must,
        dtmax_curve=curve,
        dtmax_interpolation=validate.choice(
            v.dtmax_interpolation, f"{what} dtmax_interpolation", ("linear", "step")
        ),
        frames=validate.choice(v.frames, f"{what} frames", ("steps", "must_points")),
    )


class TimeStepController:
    """FEBio's step-size rule over one stretch of time [start, end] (end may be inf).

    ``dt`` is the next step's length; ``accepted(t, iterations)`` after a converged step and
    ``retry()`` after a failed one update it; ``must_point`` says whether the step planned
    ends on a must point."""

    def __init__(self, settings: AdaptiveStepping, dt0: float, start: float, end: float) -> None:
        self.settings = settings
        self.start, self.end = float(start), float(end)
        self.must = settings.all_must_points()
        self.dtp = float(dt0)  # the rule's previous step (FEBio's m_dtp)
        self.ddt = 0.0  # the linear cut back (FEBio's m_ddt)
        self.retries = 0
        self.must_point = False
        self.dt = self.t_end = 0.0
        self._plan(start, 0)

    def state(self) -> dict[str, Any]:
        """What a checkpoint keeps."""
        keys = ("dtp", "ddt", "dt", "t_end", "must_point", "retries")
        return {k: getattr(self, k) for k in keys}

    def set_state(self, state: Mapping[str, Any]) -> None:
        """Put back what ``state`` returned."""
        for k in ("dtp", "ddt", "dt", "t_end"):
            setattr(self, k, float(state[k]))
        self.must_point, self.retries = bool(state["must_point"]), int(state["retries"])

    def _eps(self, t: float) -> float:
        scale = self.end if math.isfinite(self.end) else abs(t) + self.dtp
        return 1e-12 * max(abs(scale), self.dtp)

    def _plan(self, t: float, iterations: int) -> None:
        """FEBio's AutoTimeStep(iterations) at time t (0: the first step, only clamped)."""
        c = self.settings
        dtn = max(self.dtp, c.dtmin)
        dtmax = c.dtmax_at(t)
        if c.dtforce:
            dtn = dtmax
        elif iterations > 0:  # opt_iter = 0: dtmin (FEBio's rule as it stands)
            scale = math.sqrt(c.opt_iter / iterations)
            # a dtmax of 0 (a must-point curve's value) sets no bound, as in FEBio
            if scale >= 1.0:
                dtn = min(dtn + (dtmax - dtn) * min(0.2, scale - 1.0), 5.0 * self.dtp)
            else:
                dtn = max(dtn - (dtn - c.dtmin) * (1.0 - scale), c.dtmin)
            dtn = min(dtn, dtmax) if dtmax > 0 else dtn
        else:
            dtn = max(dtn, c.dtmin)
            dtn = min(dtn, dtmax) if dtmax > 0 else dtn
        self.dtp = dtn  # the rule's own value, before the must points shorten it
        eps = self._eps(t)
        self.must_point = False
        ahead = self.must[self.must > t + eps]
        t_end = t + dtn
        if ahead.size and ahead[0] < t + dtn + eps:
            t_end, self.must_point = float(ahead[0]), True
        if t_end > self.end - eps:  # the phase's end (a must point there counts as one)
            self.must_point = self.must_point and abs(t_end - self.end) <= eps
            t_end = self.end
        self.t_end, self.dt = t_end, t_end - t

    def accepted(self, t: float, iterations: int) -> None:
        """A step ending at t converged in ``iterations`` Newton iterations: plan the next
        (none at the end: FEBio's step is over)."""
        self.retries = 0
        if t < self.end - self._eps(t):
            self._plan(t, iterations)

    def finished(self, t: float) -> bool:
        """Whether t is the end."""
        return t >= self.end - self._eps(t)

    def last_attempt(self) -> bool:
        """Whether a failure of the attempt now planned stops the run (``retry`` refuses)."""
        c = self.settings
        return self.retries >= c.max_retries or self.dt <= c.dtmin * (1.0 + 1e-12)

    def retry(self, t: float, reason: str) -> None:
        """The step from t failed: cut it back (ConvergenceError when it may not)."""
        c = self.settings
        if self.retries >= c.max_retries:
            raise ConvergenceError(
                f"the step from t = {t:.6g} s with time_step {self.dt:.3g} s did not converge "
                f"after {c.max_retries} retries (max_retries): {reason}"
            )
        if self.dt <= c.dtmin * (1.0 + 1e-12):
            raise ConvergenceError(
                f"the step from t = {t:.6g} s did not converge at the smallest time step, "
                f"dtmin = {c.dtmin:.3g} s: {reason}"
            )
        if self.retries == 0:
            self.ddt = self.dt / (c.max_retries + 1)
        dtn = self.dt - self.ddt if c.aggressiveness == 0 else self.dt * c.cutback
        self.retries += 1
        self.dtp = self.dt = max(dtn, c.dtmin)
        self.t_end, self.must_point = t + self.dt, False


def attempt_options(options: Any, last: bool) -> Any:
    """The Newton options of one attempt: FEBio's solver falls back to tissuesim's Newton
    (``febio_fallback``, time/steps.py) only on the last attempt the step may make. Before
    it, a step FEBio's solver gives up on is cut back as FEBio cuts it back, so the steps stay
    FEBio's (with the fallback on every attempt, dy03, dy04 and sh59 of FEBio's suite took
    other steps and ended 0.85, 9.4e-3 and 1.5e-2 from FEBio's result, against -1.4e-3,
    -2.1e-3 and -4.2e-7). Fixed steps (``time/attempts/retry.py``) fall back at once: FEBio
    without its stepper stops at a failed step, so there are no steps of FEBio's to keep."""
    if last or getattr(options, "method", "newton") != "febio" or not options.febio_fallback:
        return options
    return replace(options, febio_fallback=False)


def advance_adaptive(
    step_fn: Callable,
    model: Any,
    state: State,
    controller: TimeStepController,
    solver: Any,
    options: Any,
) -> tuple[State, list, int, int]:
    """One accepted step of ``controller.dt`` (its state at ``controller.t_end`` exactly: a
    must point, the phase's end): (new State, every attempt's Newton records, retries, the
    accepted attempt's Newton iterations). Failed attempts are retried as the controller says."""
    records: list = []
    retries = 0
    while True:
        dt = controller.dt
        begin_attempt(model, state, dt)  # internal variables frozen for the attempt
        try:
            last = controller.last_attempt()
            outcome: StepOutcome = step_fn(model, state, dt, solver, attempt_options(options, last))
        except BaseException:
            end_attempt(model, StepOutcome(None, False))
            raise
        end_attempt(model, outcome)
        records.extend(outcome.newton)
        if outcome.converged:
            iterations = sum(r.iterations for r in outcome.newton)
            new = replace(outcome.state, time=float(controller.t_end))
            return new, records, retries, iterations
        controller.retry(state.time, outcome.reason)
        retries += 1
