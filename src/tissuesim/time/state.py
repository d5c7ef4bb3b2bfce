"""The state of a simulation between steps, and what one step reports."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tissuesim.solve.newton import NewtonResult

__all__ = ["State", "StepOutcome"]


@dataclass(frozen=True, eq=False)
class State:
    """time (s); x current positions and v velocities, flat (n_dofs,) vertex-major; a the
    accelerations Newmark's method carries from step to step (None for the others)."""

    time: float
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray | None = None


@dataclass
class StepOutcome:
    """One attempted (sub)step: the new state if it converged and the solver records."""

    state: State | None
    converged: bool
    newton: list[NewtonResult] = field(default_factory=list)
    reason: str = ""
