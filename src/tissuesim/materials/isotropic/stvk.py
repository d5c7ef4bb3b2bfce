"""St Venant-Kirchhoff: Hooke's law on the Green-Lagrange strain.

    E = (F^T F - I)/2,   S = lam tr(E) I + 2 mu E,   P = F S,   psi = mu E:E + lam/2 tr(E)^2
    A = delta_ik S_lj + lam F_ij F_kl + mu F_il F_kj + mu (F F^T)_ik delta_jl

Shapes: F (q, d, d) -> psi (q,), P (q, d, d), A[q, i, j, k, l] = dP_ij/dF_kl. Defined for all F
(it softens and can collapse under strong compression).
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import IsotropicMaterial, bcast, check_input

__all__ = ["StVenantKirchhoff"]


class StVenantKirchhoff(IsotropicMaterial):
    """St Venant-Kirchhoff hyperelasticity."""

    name = "stvk"

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        mu, lam, d = self.mu, self.lam, F.shape[-1]
        I = np.eye(d)
        E = 0.5 * (np.einsum("qki,qkj->qij", F, F) - I)
        trE = np.trace(E, axis1=1, axis2=2)
        psi = mu * np.einsum("qij,qij->q", E, E) + 0.5 * lam * trE**2
        if order == 0:
            return MaterialResponse(psi)
        S = bcast(lam * trE, 3) * I + 2.0 * mu * E
        P = F @ S
        if order == 1:
            return MaterialResponse(psi, P)
        B = F @ np.swapaxes(F, 1, 2)
        A = (
            np.einsum("ik,qlj->qijkl", I, S)
            + lam * np.einsum("qij,qkl->qijkl", F, F)
            + mu * np.einsum("qil,qkj->qijkl", F, F)
            + mu * np.einsum("qik,jl->qijkl", B, I)
        )
        return MaterialResponse(psi, P, A)
