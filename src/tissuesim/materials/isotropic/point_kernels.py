"""Numba versions of the material laws, one integration point at a time (optional backend).

Each ``*_point(F, mu, lam, order, P, A)`` evaluates the same formulas as the law's NumPy
``evaluate`` (see the law's module for the derivation) for a single F (d, d), d = 2 or 3:
it returns psi and, for order >= 1, fills P (d, d) and, for order 2, A (d, d, d, d) in place.
Laws undefined for J <= 0 return +inf and leave P and A untouched. The fused assembler
(``assembly/fused_p1.py``) calls them from inside its element loop, so no (q, d, d, d, d) array
is ever built. Tests check every kernel against its NumPy law to round-off.

This module imports numba at import time; import it only where ``backend.numba_available()``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["KERNELS", "LAW_IDS", "evaluate_point"]

#: Law name -> integer id used by the fused assembler's dispatch.
LAW_IDS = {"neo_hookean": 0, "course_neo_hookean": 1, "stvk": 2, "linear": 3}


@njit(cache=True, inline="always")
def _det(F):
    if F.shape[0] == 2:
        return F[0, 0] * F[1, 1] - F[0, 1] * F[1, 0]
    return (
        F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1])
        - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
        + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0])
    )


@njit(cache=True, inline="always")
def _cofactor(F, C):
    """C = dJ/dF = J F^{-T}, valid for singular F."""
    if F.shape[0] == 2:
        C[0, 0] = F[1, 1]
        C[0, 1] = -F[1, 0]
        C[1, 0] = -F[0, 1]
        C[1, 1] = F[0, 0]
        return
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            C[i, j] = F[i1, j1] * F[i2, j2] - F[i1, j2] * F[i2, j1]


@njit(cache=True, inline="always")
def _add_det_hessian(F, c, A):
    """A[i, j, k, l] += c d2J/dF_ij dF_kl."""
    if F.shape[0] == 2:
        A[0, 0, 1, 1] += c
        A[1, 1, 0, 0] += c
        A[0, 1, 1, 0] -= c
        A[1, 0, 0, 1] -= c
        return
    # d2J/dF_ij dF_kl = eps_ikm eps_jln F_mn: nonzero only for i != k and j != l
    for i in range(3):
        for k in range(3):
            if i == k:
                continue
            m = 3 - i - k
            sik = 1.0 if (k - i) % 3 == 1 else -1.0
            for j in range(3):
                for l in range(3):
                    if j == l:
                        continue
                    n = 3 - j - l
                    sjl = 1.0 if (l - j) % 3 == 1 else -1.0
                    A[i, j, k, l] += c * sik * sjl * F[m, n]


@njit(cache=True, inline="always")
def _frobenius_sq(F):
    """|F|^2 = F : F."""
    d = F.shape[0]
    sq = 0.0
    for i in range(d):
        for j in range(d):
            sq += F[i, j] * F[i, j]
    return sq


@njit(cache=True, inline="always")
def _add_identity(c, A):
    """A[i, j, k, l] += c delta_ik delta_jl."""
    d = A.shape[0]
    for i in range(d):
        for j in range(d):
            A[i, j, i, j] += c


@njit(cache=True, inline="always")
def neo_hookean_point(F, mu, lam, order, P, A, W):
    d = F.shape[0]
    J = _det(F)
    if not J > 0.0:
        return np.inf
    lnJ = math.log(J)
    sq = _frobenius_sq(F)
    psi = 0.5 * mu * (sq - d) - mu * lnJ + 0.5 * lam * lnJ * lnJ
    if order == 0:
        return psi
    G = W[0]
    _cofactor(F, G)
    for i in range(d):
        for j in range(d):
            G[i, j] /= J
    c = lam * lnJ - mu
    for i in range(d):
        for j in range(d):
            P[i, j] = mu * F[i, j] + c * G[i, j]
    if order == 1:
        return psi
    for i in range(d):
        for j in range(d):
            for k in range(d):
                for l in range(d):
                    A[i, j, k, l] = lam * G[i, j] * G[k, l] - c * G[i, l] * G[k, j]
    _add_identity(mu, A)
    return psi


@njit(cache=True, inline="always")
def course_neo_hookean_point(F, mu, lam, order, P, A, W):
    d = F.shape[0]
    x = _det(F) - 1.0
    r = x - x * x / 2.0 + x * x * x / 3.0
    sq = _frobenius_sq(F)
    psi = 0.5 * mu * (sq - d) - mu * r + 0.5 * lam * r * r
    if order == 0:
        return psi
    C = W[0]
    _cofactor(F, C)
    dr = 1.0 - x + x * x
    c2 = (lam * r - mu) * dr
    for i in range(d):
        for j in range(d):
            P[i, j] = mu * F[i, j] + c2 * C[i, j]
    if order == 1:
        return psi
    c1 = lam * dr * dr + (lam * r - mu) * (2.0 * x - 1.0)
    for i in range(d):
        for j in range(d):
            for k in range(d):
                for l in range(d):
                    A[i, j, k, l] = c1 * C[i, j] * C[k, l]
    _add_identity(mu, A)
    _add_det_hessian(F, c2, A)
    return psi


@njit(cache=True, inline="always")
def stvk_point(F, mu, lam, order, P, A, W):
    d = F.shape[0]
    E = W[0]
    for i in range(d):
        for j in range(d):
            s = 0.0
            for k in range(d):
                s += F[k, i] * F[k, j]
            E[i, j] = 0.5 * (s - (1.0 if i == j else 0.0))
    trE = 0.0
    EE = 0.0
    for i in range(d):
        trE += E[i, i]
        for j in range(d):
            EE += E[i, j] * E[i, j]
    psi = mu * EE + 0.5 * lam * trE * trE
    if order == 0:
        return psi
    S = W[1]
    for i in range(d):
        for j in range(d):
            S[i, j] = 2.0 * mu * E[i, j] + (lam * trE if i == j else 0.0)
    for i in range(d):
        for j in range(d):
            s = 0.0
            for k in range(d):
                s += F[i, k] * S[k, j]
            P[i, j] = s
    if order == 1:
        return psi
    # A = delta_ik S_lj + lam F_ij F_kl + mu F_il F_kj + mu (F F^T)_ik delta_jl
    for i in range(d):
        for k in range(d):
            B = 0.0
            for m in range(d):
                B += F[i, m] * F[k, m]
            for j in range(d):
                for l in range(d):
                    v = lam * F[i, j] * F[k, l] + mu * F[i, l] * F[k, j]
                    if i == k:
                        v += S[l, j]
                    if j == l:
                        v += mu * B
                    A[i, j, k, l] = v
    return psi


@njit(cache=True, inline="always")
def linear_point(F, mu, lam, order, P, A, W):
    d = F.shape[0]
    tr = 0.0
    ee = 0.0
    for i in range(d):
        tr += F[i, i] - 1.0
        for j in range(d):
            e = 0.5 * (F[i, j] + F[j, i]) - (1.0 if i == j else 0.0)
            ee += e * e
    psi = mu * ee + 0.5 * lam * tr * tr
    if order == 0:
        return psi
    for i in range(d):
        for j in range(d):
            P[i, j] = mu * (F[i, j] + F[j, i]) - (2.0 * mu if i == j else 0.0)
            if i == j:
                P[i, j] += lam * tr
    if order == 1:
        return psi
    for i in range(d):
        for j in range(d):
            for k in range(d):
                for l in range(d):
                    v = 0.0
                    if i == k and j == l:
                        v += mu
                    if i == l and j == k:
                        v += mu
                    if i == j and k == l:
                        v += lam
                    A[i, j, k, l] = v
    return psi


@njit(cache=True, inline="always")
def evaluate_point(law, F, mu, lam, order, P, A, W):
    """Dispatch on the law id of ``LAW_IDS``."""
    if law == 0:
        return neo_hookean_point(F, mu, lam, order, P, A, W)
    if law == 1:
        return course_neo_hookean_point(F, mu, lam, order, P, A, W)
    if law == 2:
        return stvk_point(F, mu, lam, order, P, A, W)
    return linear_point(F, mu, lam, order, P, A, W)


KERNELS = {
    "neo_hookean": neo_hookean_point,
    "course_neo_hookean": course_neo_hookean_point,
    "stvk": stvk_point,
    "linear": linear_point,
}
