"""How a Simulation steps (a mixin of ``Simulation``, ``simulation/simulation.py``): the step
function of its integrator (explicit, Backward Euler, Newmark, quasistatic, pseudo-time), the
phases of a run (``time/phases.py``), the end time of the next step, and adaptive steps (FEBio's
rule, ``time/adaptive.py``: one controller per phase, or one for a run without phases)."""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np

from tissuesim.errors import InputError
from tissuesim.time.adaptive import (
    AdaptiveStepping,
    TimeStepController,
    advance_adaptive,
    check_adaptive,
)
from tissuesim.time.attempts.retry import QUASISTATIC_ADVICE, advance
from tissuesim.time.phases import Phase, Schedule

__all__ = ["Stepping"]


class Stepping:
    """Mixed into Simulation (uses its bodies, system, state, integrator and newton)."""

    def _step_function(self, budget: dict | None, explicit_gradient: dict, by_contact: bool):
        """(step_fn(system, state, h, solver, options), linear solver) for the integrator."""
        from tissuesim.time.steps import explicit_step, implicit_step

        if self.rigid_bodies and self.explicit:
            raise InputError(
                f"rigid bodies run with the quasistatic, backward_euler, newmark and "
                f"generalized_alpha integrators, "
                f"not {self.integrator!r} (its steps have no rigid body DOFs yet)"
            )
        if self.explicit:

            def step_fn(system, state, h, solver, options):
                return explicit_step(
                    system,
                    state,
                    h,
                    energies=self.step_energies,
                    limit=self.critical_time_step,
                    keep=explicit_gradient,
                )

            return step_fn, None
        solver = self._linear_solver()
        if self.integrator == "newmark":
            from tissuesim.time.integrators.newmark import newmark_step

            self._check_newmark_bodies()
            beta, gamma = self.newmark
            step_fn = functools.partial(
                newmark_step,
                beta=beta,
                gamma=gamma,
                implicit_step=implicit_step,
                energies=self.step_energies,
                budget=budget,
            )
            return step_fn, solver
        if self.integrator == "generalized_alpha":
            from tissuesim.time.integrators.generalized_alpha import generalized_alpha_step

            self._check_newmark_bodies()
            alpha_f, alpha_m, beta, gamma = self.generalized_alpha
            step_fn = functools.partial(
                generalized_alpha_step,
                alpha_f=alpha_f,
                alpha_m=alpha_m,
                beta=beta,
                gamma=gamma,
                implicit_step=implicit_step,
                energies=self.step_energies,
                budget=budget,
            )
            return step_fn, solver
        step_fn = functools.partial(
            implicit_step,
            dynamic=self.integrator == "backward_euler",
            energies=self.step_energies,
            budget=budget,
        )
        if by_contact:  # quasistatics of bodies only contact holds: rest in pseudo-time
            from tissuesim.time.integrators.pseudo_time import pseudo_time_step

            step_fn = functools.partial(
                pseudo_time_step, energies=self.step_energies, budget=budget
            )
        return step_fn, solver

    def _check_newmark_bodies(self) -> None:
        """Newmark (and generalised-alpha) steps FEM bodies without Rayleigh damping; the first
        step of a run starts from the initial acceleration of the loads (FEBio's)."""
        for b in self.bodies.values():
            if b.kind != "fem":
                raise InputError(
                    f"integrator {self.integrator!r} steps FEM bodies; {b.kind} body {b.name!r} "
                    "needs 'backward_euler'"
                )
            if b.model.damping is not None:
                raise InputError(
                    f"integrator {self.integrator!r} with Rayleigh damping on {b.name!r}: the "
                    "damping is a term of Backward Euler's step; use 'backward_euler', or no "
                    "damping"
                )
        s, state = self.system, self._state
        if state.a is None and not self.history and state.time == self.start_time:
            from dataclasses import replace

            from tissuesim.time.integrators.newmark import initial_acceleration

            a0 = initial_acceleration(s, s.bodies, state.time)
            self._state = replace(state, a=a0 if np.any(a0) else None)

    def _end_time(self) -> float:
        """The end of the next step: an adaptive step's from its controller; otherwise
        start + (k + 1) h for a state at start + k h (no running sum: ten steps of 0.1 end
        at 1.0); a state off that grid (set by hand, or a changed time_step) steps to t + h.
        In phases, the grid is the phase's and a step ends at its phase's end at the latest."""
        if self._controller is not None:
            return self._controller.t_end
        if self.schedule is not None:
            return self.schedule.end_time(self.time)
        h, t = self.time_step, self.time
        k = round((t - self.start_time) / h)
        if abs(self.start_time + k * h - t) <= 1e-9 * h:
            return self.start_time + (k + 1) * h
        return t + h

    def set_phases(self, phases: Sequence[Phase | dict]) -> None:
        """Run in phases from the start time: each ``Phase(steps, time_step, integrator)`` (or
        dict with those keys) starts where the previous one ends, with its own time step and
        integrator ("quasistatic", "backward_euler", "newmark" or "generalized_alpha"; None keeps
        the simulation's).
        After the last phase, steps go on with its settings. ``sim.set_phases([Phase(5, 0.2,
        "quasistatic"), Phase(20, 0.01, "backward_euler")])``: a static preload to t = 1 s,
        then 0.2 s of dynamics. Conditions and loads follow time (``active`` windows of
        ``add_dirichlet``, expressions of t), not phases."""
        self._base_integrator = getattr(self, "_base_integrator", self.integrator)
        explicit = self._base_integrator in ("explicit", "symplectic_euler")
        self.schedule = Schedule(phases, self.start_time, explicit)
        if self._state is None:
            self._enter_phase()

    def _enter_phase(self) -> None:
        """The time step and integrator of the phase the next step belongs to; with adaptive
        steps, its controller (a new one at each phase's start) and the step it plans."""
        settings, start, end, dt0 = self.adaptive, self.start_time, math.inf, None
        if self.schedule is not None:
            phase, start, end = self.schedule.at(self.time)
            self.time_step = dt0 = phase.time_step
            self.integrator = phase.integrator or self._base_integrator
            settings = phase.adaptive or self.adaptive
        if settings is None:
            self._controller = None
            return
        c = self._controller
        if c is None or (c.settings, c.start, c.end) != (settings, start, end):
            if dt0 is None:  # no phases: the first step is the time step set (kept from then)
                self._dt0 = self._dt0 or self.time_step
                dt0 = self._dt0
            c = self._controller = TimeStepController(settings, dt0, self.time, end)
            c.start = start  # the stretch it steps (the controller plans from self.time)
            pending = getattr(self, "_pending_stepper", None)
            if pending is not None and (pending["start"], pending["end"]) == (start, end):
                c.set_state(pending)  # a resumed run: the controller where it was
            self._pending_stepper = None
        self.time_step = c.dt

    def set_adaptive(self, adaptive: AdaptiveStepping | dict | None) -> None:
        """Step adaptively as FEBio does (``time/adaptive.py``): ``AdaptiveStepping(dtmax=...,
        dtmin=..., opt_iter=..., max_retries=..., dtmax_curve=..., must_points=...)`` or a dict
        of those fields; None steps ``time_step`` again. It applies to a run without phases
        (from ``time_step`` as the first step, with no end) and to every phase without its own
        ``adaptive`` (over the phase's time, ending exactly at its end). Failed steps are cut
        back as FEBio does instead of halved."""
        if self.explicit and adaptive is not None:
            raise InputError("adaptive steps need an implicit integrator, not 'explicit'")
        self.adaptive = check_adaptive(adaptive)
        self._controller = self._dt0 = None

    def adaptive_end(self) -> float | None:
        """Where an adaptive run in phases ends (the last phase's end; None: no such end)."""
        s = self.schedule
        if s is None or not any((p.adaptive or self.adaptive) for p in s.phases):
            return None
        return s.end

    @property
    def finished(self) -> bool:
        """True when an adaptive run in phases has reached its end (``run`` stops there)."""
        end = self.adaptive_end()
        return end is not None and self.time >= end - 1e-12 * max(abs(end), self.time_step)

    def _advance(self, step_fn, system, solver) -> tuple:
        """One step (fixed: halved on failure; adaptive: FEBio's retries, then the next step
        planned): (new state, Newton records, substeps, the adaptive step's report or None)."""
        advice = QUASISTATIC_ADVICE if self.integrator == "quasistatic" else None
        c = self._controller
        if c is None:
            state, records, substeps = advance(
                step_fn, system, self._state, self.time_step, solver, self.newton,
                self.max_step_halvings, self._end_time(), advice,
            )  # fmt: skip
            return state, records, substeps, None
        state, records, retries, iterations = advance_adaptive(
            step_fn, system, self._state, c, solver, self.newton
        )
        report = {"dt": c.dt, "retries": retries, "must_point": c.must_point}
        c.accepted(state.time, iterations)
        self.time_step = c.dt
        return state, records, 1, report
