"""Fused assembly with Numba for elements of several quadrature points (P2, Q1 and quadratic
quadrilaterals and hexahedra, wedges).

The same sums as ``fused_p1.py`` (F, the law's point kernel, w G^T P, w G^T A G), but an
element's nq points are summed into one local Hessian before it is scattered: a P2 tetrahedron
has a 30 x 30 local block, and scattering it once instead of four times halves the memory
traffic and keeps the scatter map per element (m, nloc^2), not per point.

This module imports numba at import time; import it only where ``backend.numba_available()``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from tissuesim.materials.isotropic.point_kernels import evaluate_point

__all__ = ["assemble_points"]


def assemble_points(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    """Add sum_q w_q psi_q (order 0), its gradient (order >= 1) and Hessian (order 2).

    cells (m*nq, nv) and grads (m*nq, nv, d) per point, element-major; weights (m*nq,);
    scatter (m, nloc*nloc) per element. Returns (energy, bad) as ``assemble_p1``.
    """
    kernel = _KERNELS[grads.shape[2], grads.shape[1]]
    return kernel(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian)


@njit(cache=True)
def _points_2d(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(
        2, 6, law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _points_3d(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(
        3, 10, law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _points_q4(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(
        2, 4, law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _points_h8(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(
        3, 8, law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _points_q8(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(
        2, 8, law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _points_q9(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(
        2, 9, law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _points_h20(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(
        3, 20, law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _points_h27(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(
        3, 27, law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(cache=True)
def _points_w6(law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian):
    return _points(
        3, 6, law, mu, lam, x, cells, grads, weights, nq, order, scatter, gradient, hessian
    )


@njit(cache=True, inline="always")
def _points(d, nv, law, mu, lam, x, cells, grads, weights, nq, order, scatter, grad, hess):
    m = cells.shape[0] // nq
    nloc = nv * d
    F = np.empty((d, d))
    P = np.zeros((d, d))
    A = np.zeros((d, d, d, d))
    T = np.empty((nv, d, d, d))
    W = np.empty((2, d, d))
    H = np.empty((nloc, nloc))
    energy = 0.0
    for e in range(m):
        if order == 2:
            H[:, :] = 0.0
        for p in range(e * nq, (e + 1) * nq):
            G = grads[p]
            for i in range(d):
                for j in range(d):
                    s = 0.0
                    for a in range(nv):
                        s += x[cells[p, a] * d + i] * G[a, j]
                    F[i, j] = s
            psi = evaluate_point(law, F, mu, lam, order, P, A, W)
            w = weights[p]
            energy += w * psi
            if order == 0:
                continue
            if not np.isfinite(psi):
                return energy, e
            for a in range(nv):
                base = cells[p, a] * d
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


#: (dimension, nodes per element) -> the compiled loop: P2 triangles and tetrahedra, Q1 and
#: quadratic quadrilaterals and hexahedra, wedges
_KERNELS = {
    (2, 6): _points_2d,
    (3, 10): _points_3d,
    (2, 4): _points_q4,
    (3, 8): _points_h8,
    (2, 8): _points_q8,
    (2, 9): _points_q9,
    (3, 20): _points_h20,
    (3, 27): _points_h27,
    (3, 6): _points_w6,
}
