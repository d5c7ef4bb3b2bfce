"""Quasistatic load stepping: x_{n+1} = argmin_x E(x) - f(t_{n+1}) . x, loads and prescribed
displacements taken at t_{n+1}, starting from x_n. No inertia, so the model must be held
against rigid motions by its prescribed DOFs."""

from __future__ import annotations

import numpy as np

from tissuesim.energies.loads import ExternalForce
from tissuesim.time.implicit import solve_implicit_step
from tissuesim.time.state import State, StepOutcome

__all__ = ["quasistatic_step", "check_supported"]


def check_supported(model) -> None:
    """Refuse a quasistatic solve that nothing holds (SciPy would return finite garbage)."""
    d = model.mesh.dim
    needed = d * (d + 1) // 2  # rigid motions: 3 in 2D, 6 in 3D
    if model.prescribed.dofs.size < needed:
        raise ValueError(
            f"a quasistatic solve needs prescribed displacements that remove the {needed} rigid "
            f"motions of a {d}D body; this model prescribes {model.prescribed.dofs.size} DOFs. "
            "Add a [[dirichlet]] condition (e.g. clamp one side) or use backward_euler."
        )


def quasistatic_step(model, state: State, h: float, solver, options) -> StepOutcome:
    energies = (ExternalForce(model.external_force(state.time + h)),)
    outcome = solve_implicit_step(model, state, h, energies, (state.x,), solver, options)
    if outcome.converged:  # a sequence of equilibria has no velocity
        outcome.state = State(outcome.state.time, outcome.state.x, np.zeros_like(state.v))
    return outcome
