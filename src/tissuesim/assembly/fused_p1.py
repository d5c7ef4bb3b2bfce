"""Fused P1 assembly with Numba: F, material, local gradient and Hessian, scatter, in one loop.

The NumPy path (``kinematics/p1.py`` + ``material.evaluate`` + ``pattern.accumulate``) builds
(m, d, d, d, d) tangents and (m, nloc, nloc) local Hessians in memory and then scatters them:
several passes over arrays of up to 1 GB at 5e5 elements. This loop keeps one element's
F, P, dP/dF and local Hessian in registers/L1 and adds them straight into the global gradient and
the CSR data array through the same scatter map, so memory traffic is the scatter map plus the
output. It computes exactly the same sums (tests compare both paths to round-off):

    F   = sum_a x^a (dN^a/dX)^T
    g   += w dN^a_j P_ij                                   at DOF (a, i)
    H   += w sum_{j,l} dN^a_j A_ijkl dN^b_l                at CSR entry of ((a, i), (b, k))

Only the upper triangle of each local Hessian is computed (it is symmetric for hyperelastic
laws); the scatter adds it to both (r, c) and (c, r). One thread: the benchmark fixes threads,
and a serial loop needs no colouring to avoid write conflicts.

This module imports numba at import time; import it only where ``backend.numba_available()``.
"""

from __future__ import annotations

import os

import numpy as np
from numba import njit

from tissuesim.errors import InputError
from tissuesim.materials.isotropic.point_kernels import evaluate_point

__all__ = ["assemble_p1", "element_jacobians"]


def assemble_p1(law, mu, lam, x, cells, grads, weights, order, scatter, gradient, hessian):
    """Add sum_e w_e psi_e (order 0), its gradient (order >= 1) and Hessian (order 2).

    law: id from ``materials.point_kernels.LAW_IDS``; mu, lam: Lame parameters (Pa);
    x (n*d,) positions; cells (m, d+1); grads (m, d+1, d); weights (m,);
    scatter (m, nloc*nloc) CSR positions; gradient (n*d,) and hessian (nnz,) are added to.
    Returns (energy, bad): bad is the first element whose energy is not finite when order >= 1
    (the law is undefined there, e.g. J <= 0), after which nothing more is added; else -1.
    """
    d, nv = grads.shape[2], grads.shape[1]
    if nv == d + 1:
        kernel = _assemble_2d if d == 2 else _assemble_3d
    elif d == 3:
        kernel = _assemble_nodes_3d  # frames: 4 virtual nodes per frame in the stencil
    else:
        raise InputError(f"no fused kernel for {nv} nodes per point in {d}D")
    if not kernel.signatures:
        _announce_compilation(kernel)
    return kernel(law, mu, lam, x, cells, grads, weights, order, scatter, gradient, hessian)


_announced = False


def _announce_compilation(kernel) -> None:
    """Say once per process that numba compiles, when its cache holds no kernel yet (the first
    run on a machine or after an upgrade: 25-35 s with nothing else on the screen)."""
    global _announced
    if _announced:
        return
    try:
        cached = os.path.exists(kernel._cache._cache_file._index_path)
    except AttributeError:  # numba's cache internals changed: say nothing rather than guess
        cached = True
    if not cached:
        from tissuesim.io.progress import note

        _announced = True
        note(
            "compiling the assembly kernels with numba, once (about 30 s; later runs load "
            "them from numba's cache)"
        )


# d as a literal constant per entry point: after inlining, LLVM unrolls the small loops
# (measured 1.3x faster in 2D and 1.7x in 3D than a run-time d).
@njit(cache=True)
def _assemble_2d(law, mu, lam, x, cells, grads, weights, order, scatter, gradient, hessian):
    return _assemble(
        2, 3, law, mu, lam, x, cells, grads, weights, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _assemble_3d(law, mu, lam, x, cells, grads, weights, order, scatter, gradient, hessian):
    return _assemble(
        3, 4, law, mu, lam, x, cells, grads, weights, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _assemble_nodes_3d(law, mu, lam, x, cells, grads, weights, order, scatter, gradient, hessian):
    nv = cells.shape[1]  # any number of nodes per point (frame models), known at run time
    return _assemble(
        3, nv, law, mu, lam, x, cells, grads, weights, order, scatter, gradient, hessian
    )


@njit(cache=True, inline="always")
def _assemble(d, nv, law, mu, lam, x, cells, grads, weights, order, scatter, gradient, hessian):
    m = cells.shape[0]
    nloc = nv * d
    F = np.empty((d, d))
    P = np.zeros((d, d))
    A = np.zeros((d, d, d, d))
    T = np.empty((nv, d, d, d))
    W = np.empty((2, d, d))  # the laws' scratch space
    energy = 0.0
    for e in range(m):
        G = grads[e]
        for i in range(d):
            for j in range(d):
                s = 0.0
                for a in range(nv):
                    s += x[cells[e, a] * d + i] * G[a, j]
                F[i, j] = s
        psi = evaluate_point(law, F, mu, lam, order, P, A, W)
        w = weights[e]
        energy += w * psi
        if order == 0:
            continue
        if not np.isfinite(psi):
            return energy, e
        for a in range(nv):
            base = cells[e, a] * d
            for i in range(d):
                s = 0.0
                for j in range(d):
                    s += G[a, j] * P[i, j]
                gradient[base + i] += w * s
        if order == 1:
            continue
        # T[a, i, k, l] = sum_j dN^a_j A[i, j, k, l]
        for a in range(nv):
            for i in range(d):
                for k in range(d):
                    for l in range(d):
                        s = 0.0
                        for j in range(d):
                            s += G[a, j] * A[i, j, k, l]
                        T[a, i, k, l] = s
        row = scatter[e]
        for a in range(nv):
            for i in range(d):
                r = a * d + i
                for b in range(a, nv):
                    for k in range(d):
                        c = b * d + k
                        if c < r:
                            continue
                        s = 0.0
                        for l in range(d):
                            s += T[a, i, k, l] * G[b, l]
                        s *= w
                        hessian[row[r * nloc + c]] += s
                        if c != r:
                            hessian[row[c * nloc + r]] += s
    return energy, -1


@njit(cache=True)
def element_jacobians(x, cells, grads):
    """J = det F of every element at positions x (n*d,), (m,): the per-step min J check."""
    m, nv = cells.shape
    d = grads.shape[2]
    out = np.empty(m)
    F = np.empty((d, d))
    for e in range(m):
        for i in range(d):
            for j in range(d):
                s = 0.0
                for a in range(nv):
                    s += x[cells[e, a] * d + i] * grads[e, a, j]
                F[i, j] = s
        if d == 2:
            out[e] = F[0, 0] * F[1, 1] - F[0, 1] * F[1, 0]
        else:
            out[e] = (
                F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1])
                - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
                + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0])
            )
    return out
