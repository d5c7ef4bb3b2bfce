"""The course notes' inversion-robust Neo-Hookean (Teran & Hellrung, eqs. 13 and 20, errata fixed).

ln J is replaced by its cubic Taylor polynomial about J = 1, so the law is defined for every J,
including J <= 0 (inverted elements); with x = J - 1:

    r(J) = x - x^2/2 + x^3/3,   r' = 1 - x + x^2,   r'' = 2x - 1
    psi  = mu/2 (|F|^2 - d) - mu r + lam/2 r^2
    P    = mu F + (lam r - mu) r' dJ/dF,           dJ/dF = J F^{-T} = cof F
    A    = mu delta_ik delta_jl + (lam r'^2 + (lam r - mu) r'') dJ/dF_ij dJ/dF_kl
           + (lam r - mu) r' d2J/dF_ij dF_kl

Shapes: F (q, d, d) -> psi (q,), P (q, d, d), A[q, i, j, k, l] = dP_ij/dF_kl.
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import (
    IDENTITY,
    IsotropicMaterial,
    bcast,
    check_input,
    cofactor,
    det,
    det_hessian,
    outer,
)

__all__ = ["CourseNeoHookean"]


class CourseNeoHookean(IsotropicMaterial):
    """Inversion-robust Neo-Hookean of the course notes; defined for all J."""

    name = "course_neo_hookean"

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        mu, lam, d = self.mu, self.lam, F.shape[-1]
        cof = cofactor(F)
        x = det(F, cof) - 1.0
        r = x - x**2 / 2.0 + x**3 / 3.0
        psi = 0.5 * mu * (np.einsum("qij,qij->q", F, F) - d) - mu * r + 0.5 * lam * r**2
        if order == 0:
            return MaterialResponse(psi)
        dr = 1.0 - x + x**2
        c2 = (lam * r - mu) * dr
        P = mu * F + bcast(c2, 3) * cof
        if order == 1:
            return MaterialResponse(psi, P)
        c1 = lam * dr**2 + (lam * r - mu) * (2.0 * x - 1.0)
        A = mu * IDENTITY[d] + bcast(c1, 5) * outer(cof, cof) + bcast(c2, 5) * det_hessian(F)
        return MaterialResponse(psi, P, A)
