"""Fixed corotated elasticity (Stomakhin, Howes, Schroeder, Teran 2012); defined for all F.

    F = R S (polar, det R = +1),   psi = mu |F - R|^2 + lam/2 (J - 1)^2
    P = 2 mu (F - R) + lam (J - 1) J F^{-T}
    A = 2 mu (delta_ik delta_jl - dR_ij/dF_kl) + lam dJ/dF_ij dJ/dF_kl + lam (J - 1) d2J/dF_ij dF_kl

R comes from a sign-fixed SVD F = U diag(s) V^T with det U = det V = +1 (the last singular value
carries the sign of J), R = U V^T, and dR = U Omega V^T with
Omega_ab = (M_ab - M_ba) / (s_a + s_b), M = U^T dF V. In 2D, R = [[a, -b], [b, a]] / n with
a = F_11 + F_22, b = F_21 - F_12, n = |(a, b)| = s_1 + s_2, in closed form.
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

__all__ = ["FixedCorotated"]

_J2 = np.array([[0.0, -1.0], [1.0, 0.0]])  # rotation generator; also db/dF in 2D
# dR/dF ~ 1/(s_a + s_b) blows up where two signed singular values cancel (F collapsed onto a
# lower-dimensional set with mixed orientation; R is discontinuous there). The denominators are
# clamped in magnitude to _TINY * (1 + max |s|), keeping their sign, so the tangent stays finite.
_TINY = 1e-12


def _rotation_2d(F: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray | None]:
    a = F[:, 0, 0] + F[:, 1, 1]
    b = F[:, 1, 0] - F[:, 0, 1]
    n = np.hypot(a, b)
    floor = _TINY * (1.0 + np.abs(F).max(axis=(1, 2)))
    ok = n > floor
    a, b, n = np.where(ok, a, 1.0), np.where(ok, b, 0.0), np.where(ok, n, 1.0)  # n = 0: R = I
    R = np.stack([np.stack([a, -b], -1), np.stack([b, a], -1)], 1) / bcast(n, 3)
    if order < 2:
        return R, None
    # R = R(theta), theta = atan2(b, a): dR/dF_kl = (R J2) dtheta/dF_kl, dtheta = (a db - b da)/n^2
    n2 = np.maximum(n, floor) ** 2
    dtheta = (bcast(a, 3) * _J2 - bcast(b, 3) * np.eye(2)) / bcast(n2, 3)
    return R, outer(R @ _J2, dtheta)


def _rotation_3d(F: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray | None]:
    U, s, Vt = np.linalg.svd(F)
    V = np.swapaxes(Vt, 1, 2)
    sign_u, sign_v = np.sign(np.linalg.det(U)), np.sign(np.linalg.det(V))
    U[:, :, -1] *= sign_u[:, None]
    V[:, :, -1] *= sign_v[:, None]
    s[:, -1] *= sign_u * sign_v
    R = U @ np.swapaxes(V, 1, 2)
    if order < 2:
        return R, None
    den = s[:, :, None] + s[:, None, :]
    floor = bcast(_TINY * (1.0 + np.abs(s).max(axis=1)), 3)
    den = np.where(np.abs(den) < floor, np.where(den < 0.0, -floor, floor), den)
    T = np.einsum("qka,qlb->qabkl", U, V)  # M_ab for dF = e_k e_l^T
    omega = (T - np.swapaxes(T, 1, 2)) / den[:, :, :, None, None]
    return R, np.einsum("qia,qabkl,qjb->qijkl", U, omega, V, optimize=True)


class FixedCorotated(IsotropicMaterial):
    """Fixed corotated elasticity; inversion-robust, defined for all F."""

    name = "fixed_corotated"

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        mu, lam, d = self.mu, self.lam, F.shape[-1]
        R, dR = (_rotation_2d if d == 2 else _rotation_3d)(F, order)
        cof = cofactor(F)
        Jm1 = det(F, cof) - 1.0
        FmR = F - R
        psi = mu * np.einsum("qij,qij->q", FmR, FmR) + 0.5 * lam * Jm1**2
        if order == 0:
            return MaterialResponse(psi)
        P = 2.0 * mu * FmR + bcast(lam * Jm1, 3) * cof
        if order == 1:
            return MaterialResponse(psi, P)
        A = (
            2.0 * mu * (IDENTITY[d] - dR)
            + lam * outer(cof, cof)
            + bcast(lam * Jm1, 5) * det_hessian(F)
        )
        return MaterialResponse(psi, P, A)
