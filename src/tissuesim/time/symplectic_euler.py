"""Symplectic (semi-implicit) Euler with the lumped mass, for comparison with Backward Euler:

    v_{n+1} = v_n + h M_L^{-1} (f(t_n) - dE/dx(x_n)),   x_{n+1} = x_n + h v_{n+1}.

Prescribed DOFs follow g(t_{n+1}) and their velocity is the difference quotient. Stable only
below the CFL limit h < h_min / c with c = sqrt((lambda + 2 mu) / rho).
"""

from __future__ import annotations

import numpy as np

from tissuesim.time.state import State, StepOutcome

__all__ = ["symplectic_euler_step", "critical_time_step"]


def critical_time_step(model) -> float:
    """CFL estimate h_min / c (s): h_min the smallest element height, c the P-wave speed."""
    w = model.kinematics.weights
    grads = model.kinematics.grads
    heights = 1.0 / np.max(np.linalg.norm(grads, axis=2), axis=1)  # 1/|grad N| = height
    c = np.sqrt((model.material.lam + 2 * model.material.mu) / model.density)
    return float(np.min(heights / c)) if w.size else np.inf


def symplectic_euler_step(model, state: State, h: float, solver=None, options=None) -> StepOutcome:
    acc = model.evaluate(state.x, 1, False)
    force = model.external_force(state.time) - acc.gradient
    v1 = state.v + h * force / model.mass.lumped
    x1 = state.x + h * v1
    t1 = state.time + h
    dofs = model.prescribed.dofs
    if dofs.size:
        x1[dofs] = model.prescribed.positions(t1)
        v1[dofs] = (x1[dofs] - state.x[dofs]) / h
    if not (np.all(np.isfinite(x1)) and np.isfinite(acc.value)):
        return StepOutcome(
            None,
            False,
            [],
            f"explicit step blew up; time_step {h:g} s exceeds the stability limit "
            f"(CFL estimate {critical_time_step(model):.3g} s)",
        )
    return StepOutcome(State(t1, x1, v1), True, [])
