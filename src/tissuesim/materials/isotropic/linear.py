"""Small-strain linear elasticity (not rotation invariant; for small deformations only).

    eps = (F + F^T)/2 - I,   psi = mu eps:eps + lam/2 tr(eps)^2,   P = 2 mu eps + lam tr(eps) I
    A   = mu (delta_ik delta_jl + delta_il delta_jk) + lam delta_ij delta_kl   (constant)

Shapes: F (q, d, d) -> psi (q,), P (q, d, d), A[q, i, j, k, l] = dP_ij/dF_kl.
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import IsotropicMaterial, bcast, check_input

__all__ = ["LinearElastic"]


class LinearElastic(IsotropicMaterial):
    """Linear (small-strain) isotropic elasticity."""

    name = "linear"

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        mu, lam, q, d = self.mu, self.lam, F.shape[0], F.shape[-1]
        I = np.eye(d)
        eps = 0.5 * (F + np.swapaxes(F, 1, 2)) - I
        tr = np.trace(eps, axis1=1, axis2=2)
        psi = mu * np.einsum("qij,qij->q", eps, eps) + 0.5 * lam * tr**2
        if order == 0:
            return MaterialResponse(psi)
        P = 2.0 * mu * eps + bcast(lam * tr, 3) * I
        if order == 1:
            return MaterialResponse(psi, P)
        A0 = mu * (
            np.einsum("ik,jl->ijkl", I, I) + np.einsum("il,jk->ijkl", I, I)
        ) + lam * np.einsum("ij,kl->ijkl", I, I)
        return MaterialResponse(psi, P, np.broadcast_to(A0, (q,) + A0.shape).copy())
