"""The stability limit of explicit (symplectic Euler) steps of a FEM body (the step itself is
``time/steps.py``'s): stable only below the CFL limit h < h_min / c, c = sqrt((lambda + 2 mu)
/ rho) the P-wave speed."""

from __future__ import annotations

import numpy as np

__all__ = ["critical_time_step"]


def critical_time_step(model) -> float:
    """CFL estimate h_min / c (s): h_min the smallest element height, c the P-wave speed."""
    w = model.kinematics.weights
    grads = model.kinematics.grads
    heights = 1.0 / np.max(np.linalg.norm(grads, axis=2), axis=1)  # 1/|grad N| = height
    nq = model.kinematics.points_per_cell
    heights = heights.reshape(-1, nq).min(axis=1)  # P2: the smallest over an element's points
    c = np.sqrt((model.material.lam + 2 * model.material.mu) / model.density)
    return float(np.min(heights / c)) if w.size else np.inf
