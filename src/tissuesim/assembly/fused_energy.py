"""Fused Numba assembly for laws whose point kernel is generated (``EnergyLaw``).

The sums of ``fused_p1.py`` and ``fused_quadrature.py`` (F, the law's point kernel, w G^T P,
w G^T A G into the global gradient and CSR data through the scatter map), but the kernel is an
argument: a first-class function of type ``energy_point.SIGNATURE``, so this loop is compiled
once per element shape for every law (and kept in Numba's cache), the kernel once per psi. An
element's nq points are summed into one local Hessian before the scatter (nq = 1 for P1).

This module imports numba at import time; import it only where ``backend.numba_available()``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

from tissuesim.materials.energy_law.energy_point import SIGNATURE

__all__ = ["assemble_energy"]

_F8 = types.float64
_ARGS = (
    types.FunctionType(SIGNATURE),
    _F8[::1],  # parameters
    _F8[::1],  # x
    types.int64[:, ::1],  # cells, per point
    _F8[:, :, ::1],  # grads, per point
    _F8[::1],  # weights
    types.int64,  # nq
    types.int64,  # order
    types.int64[:, ::1],  # scatter, per element
    _F8[::1],  # gradient
    _F8[::1],  # hessian
)
_SIGNATURE = types.Tuple((_F8, types.int64))(*_ARGS)
_compiled: dict = {}


def assemble_energy(kernel, params, x, cells, grads, weights, nq, order, scatter, gradient, hess):
    """Add sum_q w_q psi_q (order 0), its gradient (order >= 1) and Hessian (order 2).

    kernel: a generated point kernel; params (k,) its parameters' values; x (n*d,) positions;
    cells (m*nq, nv) and grads (m*nq, nv, d) per point, element-major; weights (m*nq,);
    scatter (m, nloc*nloc) per element. Returns (energy, bad) as ``fused_p1.assemble_p1``."""
    d, nv = grads.shape[2], grads.shape[1]
    loop = _loop(d, nv)
    return loop(
        kernel,
        np.ascontiguousarray(params, dtype=float),
        np.ascontiguousarray(x, dtype=float),
        np.ascontiguousarray(cells, dtype=np.int64),
        np.ascontiguousarray(grads, dtype=float),
        np.ascontiguousarray(weights, dtype=float),
        int(nq),
        int(order),
        np.ascontiguousarray(scatter, dtype=np.int64),
        gradient,
        hess,
    )


def _loop(d: int, nv: int):
    """The compiled loop for d and nv (P1 triangles and tetrahedra with d and nv as literal
    constants, which LLVM unrolls; any other element with both known at run time)."""
    key = (d, nv) if (d, nv) in ((2, 3), (3, 4)) else None
    if key not in _compiled:
        fun = {(2, 3): _tri, (3, 4): _tet, None: _any}[key]
        _compiled[key] = njit(_SIGNATURE, cache=True)(fun)
    return _compiled[key]


def _tri(kernel, p, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(2, 3, kernel, p, x, cells, grads, weights, nq, order, scatter, gradient, hessian)


def _tet(kernel, p, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(3, 4, kernel, p, x, cells, grads, weights, nq, order, scatter, gradient, hessian)


def _any(kernel, p, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    d, nv = grads.shape[2], grads.shape[1]
    return _points(
        d, nv, kernel, p, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(inline="always")
def _points(d, nv, kernel, p, x, cells, grads, weights, nq, order, scatter, grad, hess):
    m = cells.shape[0] // nq
    nloc = nv * d
    F = np.empty((d, d))
    P = np.zeros((d, d))
    A = np.zeros((d, d, d, d))
    S = np.empty((7, d, d))  # the kernel's scratch space
    T = np.empty((nv, d, d, d))
    H = np.empty((nloc, nloc))
    energy = 0.0
    for e in range(m):
        if order == 2:
            H[:, :] = 0.0
        for q in range(e * nq, (e + 1) * nq):
            G = grads[q]
            for i in range(d):
                for j in range(d):
                    s = 0.0
                    for a in range(nv):
                        s += x[cells[q, a] * d + i] * G[a, j]
                    F[i, j] = s
            psi = kernel(F, p, order, P, A, S)
            w = weights[q]
            energy += w * psi
            if order == 0:
                continue
            if not np.isfinite(psi):
                return energy, e
            for a in range(nv):
                base = cells[q, a] * d
                for i in range(d):
                    s = 0.0
                    for j in range(d):
                        s += G[a, j] * P[i, j]
                    grad[base + i] += w * s
            if order == 1:
                continue
            for a in range(nv):
                for i in range(d):
                    for k in range(d):
                        for l in range(d):
                            s = 0.0
                            for j in range(d):
                                s += G[a, j] * A[i, j, k, l]
                            T[a, i, k, l] = s * w
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
                            H[r, c] += s
        if order == 2:
            row = scatter[e]
            for r in range(nloc):
                hess[row[r * nloc + r]] += H[r, r]
                for c in range(r + 1, nloc):
                    hess[row[r * nloc + c]] += H[r, c]
                    hess[row[c * nloc + r]] += H[r, c]
    return energy, -1
