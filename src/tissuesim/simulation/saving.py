"""``Simulation.save`` / ``load`` (checkpoints, ``io/checkpoints/checkpoint.py``) and what a
simulation says about itself (``describe``: summary.json's ``simulation``; the linear
solver in use): a mixin of ``Simulation``."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Any, Self

__all__ = ["SavedAndDescribed"]


class SavedAndDescribed:
    """Mixed into ``Simulation``."""

    def save(self, path: str | Path) -> Path:
        """Write the state, history and linear solver's state to ``path`` (.npz, atomically;
        ``io/checkpoints/checkpoint.py``); ``load`` continues from it bit-identically."""
        from tissuesim.io.checkpoints.checkpoint import save_simulation

        return save_simulation(self, path)

    def load(self, path: str | Path) -> Self:
        """Restore a ``save``-d state into this simulation, set up as the saved one was and not
        stepped yet (InputError naming what differs otherwise); returns the simulation."""
        from tissuesim.io.checkpoints.checkpoint import load_simulation

        load_simulation(self, path)
        return self

    def linear_solver_info(self) -> dict[str, Any]:
        """The linear solver in use (None before the first implicit step) and why."""
        return {"name": getattr(self._solver, "name", None), "reason": self.solver_reason}

    def describe(self) -> dict[str, Any]:
        """A JSON-ready description of the simulation: integrator, time step, gravity, every
        body's description, the number of DOFs and prescribed DOFs, the Newton options, the
        linear solver and the contact settings (``summary.json``'s ``simulation``)."""
        s = self.system
        return {
            "integrator": self.integrator,
            "time_step": self.time_step,
            "adaptive": None if self.adaptive is None else asdict(self.adaptive),
            "start_time": self.start_time,
            "gravity": [g.tolist() for g in self.gravity],
            "bodies": {name: b.describe() for name, b in self.bodies.items()},
            "n_dofs": s.n_dofs,
            "prescribed_dofs": int(s.prescribed_dofs.size),
            "newton": asdict(self.newton),
            "linear_solver": self.linear_solver_info(),
            "contact": None if s.contact is None else s.contact.describe(),
            "visual_surfaces": {n: v.describe() for n, v in self.visual_surfaces.items()},
        }
