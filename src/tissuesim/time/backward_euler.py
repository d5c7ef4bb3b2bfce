"""Backward Euler (notes, eq. 3-7) as minimisation of the incremental potential.

    x_{n+1} = argmin_x 1/(2 h^2) (x - x_pred)^T M (x - x_pred) + E(x) - f(t_{n+1}) . x,
    x_pred = x_n + h v_n,   v_{n+1} = (x_{n+1} - x_n) / h.

Its stationarity condition is the notes' q(u) = 0 divided by h^2. Prescribed DOFs take their
values at t_{n+1} before Newton starts and keep them.
"""

from __future__ import annotations

from tissuesim.energies.loads import ExternalForce
from tissuesim.energies.mass import Inertia
from tissuesim.time.implicit import solve_implicit_step
from tissuesim.time.state import State, StepOutcome

__all__ = ["backward_euler_step"]


def backward_euler_step(model, state: State, h: float, solver, options) -> StepOutcome:
    x_pred = state.x + h * state.v
    energies = (Inertia(model.mass, x_pred, h), ExternalForce(model.external_force(state.time + h)))
    # Start Newton from the better (lower Phi) of the inertial prediction and the last
    # positions: in violent phases (folding) x_pred can invert many elements at once.
    return solve_implicit_step(model, state, h, energies, (x_pred, state.x), solver, options)
