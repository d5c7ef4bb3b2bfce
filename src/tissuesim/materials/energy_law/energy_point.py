"""Numba pieces of the point kernels generated for ``EnergyLaw`` (``energy_kernel.py``).

Every generated kernel has the signature ``SIGNATURE``:

    kernel(F (d, d), p (n_parameters,), order, P (d, d), A (d, d, d, d), S (7, d, d)) -> psi

and fills P (order >= 1) and A (order 2) in place, S being scratch space; it returns +inf where
the law is undefined (J <= 0, psi not finite) and leaves P and A untouched there. The fused
loop (``assembly/fused_energy.py``) takes such a kernel as a first-class function, so the loop
is compiled once for every law and the kernel once per psi.

A kernel of an invariant law computes the derivatives of W(I1, I2, J) and calls
``invariant_tensors_point``, the point form of ``_hyperelastic.invariant_tensors``.

This module imports numba at import time; import it only where ``backend.numba_available()``.
"""

from __future__ import annotations

from numba import njit, types

from tissuesim.materials.isotropic.point_kernels import _add_det_hessian, _cofactor, _det

__all__ = ["SIGNATURE", "invariants_point", "invariant_tensors_point"]

SIGNATURE = types.float64(
    types.float64[:, ::1],
    types.float64[::1],
    types.int64,
    types.float64[:, ::1],
    types.float64[:, :, :, ::1],
    types.float64[:, :, ::1],
)


@njit(cache=True, inline="always")
def invariants_point(d, F):
    """(I1, I2, J) of one F (d, d); in 2D those of plane strain (F_33 = 1). ``d`` is given as a
    literal by the generated kernel, so that the compiler unrolls the loops."""
    extra = 3.0 - d
    I1 = extra
    CC = extra
    for i in range(d):
        for j in range(d):
            I1 += F[i, j] * F[i, j]
            s = 0.0
            for k in range(d):
                s += F[k, i] * F[k, j]
            CC += s * s
    return I1, 0.5 * (I1 * I1 - CC), _det(F)


@njit(cache=True, inline="always")
def invariant_tensors_point(d, F, I1, W1, W2, WJ, W11, W12, W22, W1J, W2J, WJJ, order, P, A, S):
    """P (order >= 1) and A (order 2) of W(I1, I2, J) from its derivatives, in place.

    dI1/dF = g1 = 2 F, dI2/dF = g2 = 2 (I1 F - F C), dJ/dF = cof F; A = sum_ab W_ab g_a (x) g_b
    + 2 W1 delta_ik delta_jl + W2 d2I2 + WJ d2J, d2I2 as in ``_hyperelastic.py``. Every term
    is symmetric (A_ijkl = A_klij): the upper triangle is computed and mirrored. The I2 terms
    are skipped when W does not depend on I2 (all its derivatives zero)."""
    cof, C, g2, h1, h2, hJ, B = S[0], S[1], S[2], S[3], S[4], S[5], S[6]
    _cofactor(F, cof)
    i2 = W2 != 0.0 or W12 != 0.0 or W22 != 0.0 or W2J != 0.0
    if i2:
        for i in range(d):
            for j in range(d):
                s = 0.0
                b = 0.0
                for k in range(d):
                    s += F[k, i] * F[k, j]
                    b += F[i, k] * F[j, k]
                C[i, j] = s
                B[i, j] = b
        for i in range(d):
            for j in range(d):
                s = 0.0
                for k in range(d):
                    s += F[i, k] * C[k, j]
                g2[i, j] = 2.0 * (I1 * F[i, j] - s)
    for i in range(d):
        for j in range(d):
            P[i, j] = 2.0 * W1 * F[i, j] + WJ * cof[i, j]
            if i2:
                P[i, j] += W2 * g2[i, j]
    if order < 2:
        return
    for i in range(d):
        for j in range(d):
            g1 = 2.0 * F[i, j]
            # the 4 W2 F (x) F of W2 d2I2 is W2 g1 (x) g1: it joins h1
            h1[i, j] = (W11 + W2) * g1 + W1J * cof[i, j]
            hJ[i, j] = W1J * g1 + WJJ * cof[i, j]
            if i2:
                h1[i, j] += W12 * g2[i, j]
                h2[i, j] = W12 * g1 + W22 * g2[i, j] + W2J * cof[i, j]
                hJ[i, j] += W2J * g2[i, j]
    iso = 2.0 * W1 + 2.0 * W2 * I1
    n = d * d
    for a in range(n):
        i, j = a // d, a % d
        g1 = 2.0 * F[i, j]
        for b in range(a, n):
            k, l = b // d, b % d
            v = g1 * h1[k, l] + cof[i, j] * hJ[k, l]
            if i == k and j == l:
                v += iso
            if i2:
                # the rest of W2 d2I2: -2 W2 (delta_ik C_lj + F_il F_kj + B_ik delta_jl)
                v += g2[i, j] * h2[k, l] - 2.0 * W2 * F[i, l] * F[k, j]
                if i == k:
                    v -= 2.0 * W2 * C[l, j]
                if j == l:
                    v -= 2.0 * W2 * B[i, k]
            A[i, j, k, l] = v
            A[k, l, i, j] = v
    _add_det_hessian(F, WJ, A)
