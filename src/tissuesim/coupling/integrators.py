"""One implicit step of the coupled organs + tissue system: Backward Euler or quasistatic.

Backward Euler minimises, over every body at once,

    Phi(c) = sum_bodies [ 1/(2 h^2) |c - c_pred|_M^2 + E(c) - f(t_{n+1}) . c ] + W_attach(c)
             + graspers' springs,

with c_pred = c_n (+) h v_n (frames' rotations advanced multiplicatively); quasistatics drops the
inertia. After convergence the full gradient of Phi at c_{n+1} is handed to ``on_converged``:
at prescribed DOFs it is the force the constraint applies (the reaction), used for the
grasper's and the supports' forces.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tissuesim.solve.newton import minimize
from tissuesim.time.implicit import choose_start
from tissuesim.time.state import State, StepOutcome

__all__ = ["coupled_step"]

#: energies(t1, c_pred or None, h) -> (per-organ energy lists, tissue energy list)
EnergyBuilder = Callable[[float, np.ndarray | None, float], tuple[list, list]]


def coupled_step(
    system,
    state: State,
    h: float,
    solver,
    options,
    *,
    dynamic: bool,
    energies: EnergyBuilder,
    on_converged: Callable[[np.ndarray], None] | None = None,
) -> StepOutcome:
    t1 = state.time + h
    c_pred = system.retract(state.x, h * state.v) if dynamic else None
    organ_energies, tissue_energies = energies(t1, c_pred, h)

    def evaluate(c: np.ndarray, order: int, project: bool):
        return system.evaluate(c, order, project, organ_energies, tissue_energies)

    # as for single bodies: start from the better of the inertial prediction and the last state
    candidates = (c_pred, state.x) if dynamic else (state.x,)
    c0 = choose_start(evaluate, candidates, lambda c: system.apply_prescribed(c, t1))
    c1, record = minimize(
        evaluate,
        c0,
        system.elimination,
        solver,
        options,
        force_scale=system.force_scale,
        length_scale=system.length_scale,
        retract=system.retract,
    )
    if not record.converged:
        return StepOutcome(None, False, [record], record.reason)
    v1 = system.difference(c1, state.x) / h if dynamic else np.zeros(system.n_dofs)
    if on_converged is not None:
        on_converged(record.gradient)  # Newton's last evaluation, at c1, not eliminated
    return StepOutcome(State(t1, c1, v1), True, [record])
