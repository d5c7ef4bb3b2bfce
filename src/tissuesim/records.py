"""What one time step did: one entry of summary.json's "steps"."""

from __future__ import annotations

import time as wallclock
from dataclasses import dataclass, field
from typing import Any

__all__ = ["StepRecord"]


@dataclass
class StepRecord:
    """time (s) is start_time + step * time_step; ``newton_reasons`` says why each Newton
    solve stopped ("gradient", "round-off ...", or the failure); ``extra`` holds "forces"
    (name -> 3-vector, N) and, with a tissue, the attachment gap and topology events."""

    step: int
    time: float
    converged: bool
    substeps: int
    newton_iterations: int
    projected_iterations: int
    residual_norms: list[list[float]]
    energies: dict[str, float]
    min_J: float
    wall_time_s: float
    linear_solver: str = ""
    newton_reasons: list[str] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def build(
        cls, step: int, time: float, records, substeps: int, start: float, solver, **fields
    ) -> StepRecord:
        """The record of a converged step from its Newton records; ``start`` is the
        perf_counter value when the step began; ``fields``: energies, min_J, extra."""
        return cls(
            step=step,
            time=time,
            converged=True,
            substeps=substeps,
            newton_iterations=sum(r.iterations for r in records),
            projected_iterations=sum(sum(r.projected) for r in records),
            residual_norms=[r.gradient_norms for r in records],
            wall_time_s=wallclock.perf_counter() - start,
            linear_solver=getattr(solver, "name", "none"),
            newton_reasons=[r.reason for r in records],
            **fields,
        )
