"""The part every implicit scheme shares: minimise the step's energy with Newton from x0 and
turn the result into the next state, v_{n+1} = (x_{n+1} - x_n) / h."""

from __future__ import annotations

import numpy as np

from tissuesim.solve.newton import minimize
from tissuesim.time.state import State, StepOutcome

__all__ = ["solve_implicit_step", "choose_start"]


def solve_implicit_step(model, state: State, h: float, energies, x0_candidates, solver, options):
    """Minimise elastic + ``energies`` over the free DOFs; prescribed DOFs at t_n + h.

    x0_candidates: starting guesses (n_dofs,); Newton starts from the one of lowest energy
    (ties: the first)."""
    t1 = state.time + h

    def evaluate(x: np.ndarray, order: int, project: bool):
        return model.evaluate(x, order, project, energies)

    prescribed = model.prescribed.positions(t1)

    def with_prescribed(guess: np.ndarray) -> np.ndarray:
        x0 = guess.copy()
        x0[model.prescribed.dofs] = prescribed
        return x0

    x0 = choose_start(evaluate, x0_candidates, with_prescribed)
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


def choose_start(evaluate, candidates, apply_prescribed) -> np.ndarray:
    """The candidate (with prescribed values applied) of lowest energy; ties and NaN: the
    first. One candidate is returned without evaluating it."""
    starts = []
    for guess in candidates:
        x0 = apply_prescribed(guess)
        value = evaluate(x0, 0, False).value if len(candidates) > 1 else 0.0
        starts.append((np.nan_to_num(value, nan=np.inf), len(starts), x0))
    return min(starts, key=lambda s: (s[0], s[1]))[2]
