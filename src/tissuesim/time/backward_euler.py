"""Backward Euler (notes, eq. 3-7) as minimisation of the incremental potential.

    x_{n+1} = argmin_x 1/(2 h^2) (x - x_pred)^T M (x - x_pred) + E(x) - f(t_{n+1}) . x,
    x_pred = x_n + h v_n,   v_{n+1} = (x_{n+1} - x_n) / h.

Its stationarity condition is the notes' q(u) = 0 divided by h^2. Prescribed DOFs take their
values at t_{n+1} before Newton starts and keep them.
"""

from __future__ import annotations

import numpy as np

from tissuesim.energies.loads import ExternalForce
from tissuesim.energies.mass import Inertia
from tissuesim.solve.newton import minimize
from tissuesim.time.state import State, StepOutcome

__all__ = ["backward_euler_step"]


def backward_euler_step(model, state: State, h: float, solver, options) -> StepOutcome:
    t1 = state.time + h
    x_pred = state.x + h * state.v
    energies = (Inertia(model.mass, x_pred, h), ExternalForce(model.external_force(t1)))

    def evaluate(x: np.ndarray, order: int, project: bool):
        return model.evaluate(x, order, project, energies)

    # Start Newton from the better (lower Phi) of the inertial prediction and the last
    # positions: in violent phases (folding) x_pred can invert many elements at once.
    prescribed = model.prescribed.positions(t1)
    starts = []
    for guess in (x_pred, state.x):
        x0 = guess.copy()
        x0[model.prescribed.dofs] = prescribed
        starts.append((evaluate(x0, 0, False).value, len(starts), x0))
    x0 = min(starts, key=lambda s: (np.nan_to_num(s[0], nan=np.inf), s[1]))[2]

    x1, record = minimize(
        evaluate,
        x0,
        model.elimination,
        solver,
        options,
        force_scale=model.force_scale,
        length_scale=model.length_scale,
    )
    if not record.converged:
        return StepOutcome(None, False, [record], record.reason)
    return StepOutcome(State(t1, x1, (x1 - state.x) / h), True, [record])
