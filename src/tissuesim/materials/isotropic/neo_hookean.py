"""Standard compressible Neo-Hookean; undefined (psi = +inf) for J <= 0.

    psi = mu/2 (|F|^2 - d) - mu ln J + lam/2 (ln J)^2
    P   = mu F + (lam ln J - mu) F^{-T}
    A   = mu delta_ik delta_jl + lam G_ij G_kl - (lam ln J - mu) G_il G_kj,   G = F^{-T}

In 2D (plane strain, F_33 = 1) |F|^2 - d with d = 2 equals the 3D I1 - 3.
Shapes: F (q, d, d) -> psi (q,), P (q, d, d), A[q, i, j, k, l] = dP_ij/dF_kl. Stress and tangent
raise InvertedElementError (``.indices`` = offending q) where J <= 0.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import InvertedElementError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import (
    IDENTITY,
    IsotropicMaterial,
    bcast,
    check_input,
    cofactor,
    det,
    outer,
)

__all__ = ["NeoHookean"]


class NeoHookean(IsotropicMaterial):
    """Compressible Neo-Hookean with ln J; +inf energy and InvertedElementError for J <= 0."""

    name = "neo_hookean"

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        mu, lam, d = self.mu, self.lam, F.shape[-1]
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0  # also False for NaN
        safe_J = np.where(ok, J, 1.0)
        lnJ = np.log(safe_J)
        psi = 0.5 * mu * (np.einsum("qij,qij->q", F, F) - d) - mu * lnJ + 0.5 * lam * lnJ**2
        psi = np.where(ok, psi, np.inf)
        if order == 0:
            return MaterialResponse(psi)
        if not ok.all():
            bad = np.flatnonzero(~ok)
            raise InvertedElementError(
                f"neo_hookean is undefined for J <= 0 but {bad.size} point(s) are inverted or "
                f"degenerate (q indices {bad[:10].tolist()}{' ...' if bad.size > 10 else ''}, "
                f"J = {J[bad[:3]].tolist()}); use course_neo_hookean or fixed_corotated for "
                "inversion-robust simulation, or take smaller steps",
                indices=bad,
            )
        G = cof / bcast(J, 3)
        c = lam * lnJ - mu
        P = mu * F + bcast(c, 3) * G
        if order == 1:
            return MaterialResponse(psi, P)
        A = mu * IDENTITY[d] + lam * outer(G, G) - bcast(c, 5) * np.einsum("qil,qkj->qijkl", G, G)
        return MaterialResponse(psi, P, A)
