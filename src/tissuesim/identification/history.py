"""Sensitivities through laws with internal variables (``sensitivity.py``): viscoelasticity,
reactive viscoelasticity, damage, multigeneration, active contraction in time.

A step of such a law minimises a potential whose stress depends on the state x_n and on the
internal variables q_{n-1} the last step left (``begin_step`` freezes them for the step); once
the step converged, ``accept_step`` makes q_n = U(F(x_n), q_{n-1}, theta). The derivative
carries Q = dq/dtheta from step to step:

    b_j   = d g / d theta_j along (theta_j, q_{n-1} + Q_j): the copies' gradients at x_n with
            their internal variables at q_{n-1} +- delta Q_j (central differences, as for the
            law's own parameters),
    Q_j^n = (U(F(x_n + delta S_j), q_{n-1} + delta Q_j, theta + delta e_j)
             - U(F(x_n - delta S_j), q_{n-1} - delta Q_j, theta - delta e_j)) / (2 delta),

a directional difference of the update through the copies' own laws (their ``state_arrays``:
the variables' counts and times do not move, so their differences are 0). Exact to the
differences' order where the update is smooth (a Prony series; damage while it grows or holds
away from its threshold). The step's Hessian is evaluated with the base's q_{n-1} restored and
the step begun again, as its solve saw it.
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np

__all__ = ["HistoryDerivative", "has_history"]


def has_history(model) -> bool:
    """Whether a FEM body's law (or a region's) carries internal variables."""
    return hasattr(model.material, "accept_step") or (
        model.parts is not None and any(hasattr(p.material, "accept_step") for p in model.parts)
    )


def _states(sim, names: list[str]) -> dict[str, dict[str, np.ndarray]]:
    return {name: sim.bodies[name].model.material.state_arrays() for name in names}


class HistoryDerivative:
    """dq/dtheta of every body with a history law, per parameter, from step to step."""

    def __init__(self, base, copies: list) -> None:
        self.names = [n for n, b in base.bodies.items() if has_history(b.model)]
        self.copies = copies
        start = _states(base, self.names)
        # each copy's internal variables at the run's start (their own laws': differences)
        self.Q = []
        for delta, pair in copies:
            plus, minus = (_states(sim, self.names) for sim in pair)
            self.Q.append({n: {k: (plus[n][k] - minus[n][k]) / (2 * delta) for k in start[n]}
                           for n in self.names})  # fmt: skip
        self.before: dict | None = None

    @classmethod
    def of(cls, base, copies: list) -> HistoryDerivative | None:
        if not any(has_history(b.model) for b in base.bodies.values() if b.kind == "fem"):
            return None
        return cls(base, copies)

    def start_step(self, base) -> None:
        """Before the base's step: its internal variables q_{n-1}."""
        self.before = _states(base, self.names)

    @contextmanager
    def as_solved(self, base, x_prev: np.ndarray, h: float, x: np.ndarray | None = None):
        """Within: the base's laws as its step's solve saw them (q_{n-1}, the step begun, a
        lagged term at its fixed point: re-lagged at the step's solution x); after: q_n
        again."""
        after = _states(base, self.names)
        s = base.system
        try:
            for name in self.names:
                model = base.bodies[name].model
                model.material.set_state_arrays(self.before[name])
                where = s.config_slices[s.names.index(name)]
                model.begin_step(x_prev[where], h)
                if x is not None and model.lagged_materials():
                    model.relag_materials(x[where], np.inf)
            yield
        finally:
            for name in self.names:
                model = base.bodies[name].model
                model.material.set_state_arrays(after[name])

    def set_copies(self, x_prev: np.ndarray, h: float, x: np.ndarray | None = None) -> None:
        """Each parameter's copies with their internal variables at q_{n-1} +- delta Q_j, the
        step begun, a lagged term at the base's solution x (before their gradients: b)."""
        for (delta, pair), Q in zip(self.copies, self.Q, strict=True):
            for sign, sim in zip((1.0, -1.0), pair, strict=True):
                s = sim.system
                for name in self.names:
                    q = {k: v + sign * delta * Q[name][k] for k, v in self.before[name].items()}
                    model = sim.bodies[name].model
                    model.material.set_state_arrays(q)
                    where = s.config_slices[s.names.index(name)]
                    model.begin_step(x_prev[where], h)
                    if x is not None and model.lagged_materials():
                        model.relag_materials(x[where], np.inf)

    def update(self, x: np.ndarray, S: np.ndarray) -> None:
        """After the step's derivative S: Q_j^n by the copies' updates at x +- delta S_j."""
        for j, (delta, pair) in enumerate(self.copies):
            got = []
            for sign, sim in zip((1.0, -1.0), pair, strict=True):
                s = sim.system
                moved = s.retract(x, sign * delta * S[:, j])
                for name in self.names:
                    model = sim.bodies[name].model
                    model.end_step(moved[s.config_slices[s.names.index(name)]])
                got.append(_states(sim, self.names))
            self.Q[j] = {
                n: {k: (got[0][n][k] - got[1][n][k]) / (2 * delta) for k in got[0][n]}
                for n in self.names
            }
