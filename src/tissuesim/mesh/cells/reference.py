"""The reference simplex: Lagrange shape functions of order 1 and 2, and quadrature rules.

Reference coordinates xi in {xi_j >= 0, sum xi_j <= 1}; barycentric L_0 = 1 - sum xi, L_j = xi_j.
Order 1: N_a = L_a. Order 2 (nodes in ``mesh/cells/quadratic.py``'s order): corners
N_a = L_a (2 L_a - 1), midside node of edge (a, b): N = 4 L_a L_b.

Quadrature (weights sum to the reference measure 1/2 or 1/6):
  degree 1: the centroid.
  degree 2: triangle (1/6, 1/6), (2/3, 1/6), (1/6, 2/3), w = 1/6 each (Strang & Fix);
            tetrahedron a = (5 + 3 sqrt 5)/20, b = (5 - sqrt 5)/20, the 4 permutations of
            (a, b, b), (b, b, b), w = 1/24 each (Keast's 4-point rule).
  higher:   collapsed (Duffy) Gauss-Legendre products, n points per direction, exact for
            polynomials of degree 2n - d; used once at set-up (mass, tractions), so their
            extra points cost nothing per iteration.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from tissuesim.mesh.cells.quadratic import EDGES

__all__ = [
    "shape_functions",
    "quadrature",
    "facet_quadrature",
    "stiffness_degree",
    "rest_jacobians",
]


def stiffness_degree(order: int) -> int:
    """The quadrature degree used for the elastic energy: exact for the P1/P2 stiffness of
    straight-sided elements (grad N grad N is of degree 2 (order - 1))."""
    return 2 * (order - 1) if order > 1 else 1


def shape_functions(dim: int, order: int, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """N (q, nv) and dN/dxi (q, nv, d) at reference points xi (q, d)."""
    xi = np.atleast_2d(np.asarray(xi, dtype=float))
    q = xi.shape[0]
    L = np.concatenate([1.0 - xi.sum(axis=1, keepdims=True), xi], axis=1)  # (q, d+1)
    dL = np.concatenate([-np.ones((1, dim)), np.eye(dim)], axis=0)  # (d+1, d)
    if order == 1:
        return L, np.broadcast_to(dL, (q, dim + 1, dim)).copy()
    if order != 2:
        raise ValueError(f"element order must be 1 or 2, not {order}")
    edges = EDGES[dim]
    N_corner = L * (2.0 * L - 1.0)
    dN_corner = (4.0 * L - 1.0)[:, :, None] * dL[None]
    La, Lb = L[:, edges[:, 0]], L[:, edges[:, 1]]
    N_mid = 4.0 * La * Lb
    dN_mid = 4.0 * (La[:, :, None] * dL[edges[:, 1]][None] + Lb[:, :, None] * dL[edges[:, 0]][None])
    return np.concatenate([N_corner, N_mid], axis=1), np.concatenate([dN_corner, dN_mid], axis=1)


@cache
def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w  # on [0, 1]


@cache
def _collapsed(dim: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = _gauss(n)
    if dim == 1:
        return x[:, None], w
    if dim == 2:
        u, v = np.meshgrid(x, x, indexing="ij")
        wu, wv = np.meshgrid(w, w, indexing="ij")
        pts = np.stack([u, v * (1.0 - u)], axis=-1).reshape(-1, 2)
        return pts, (wu * wv * (1.0 - u)).ravel()
    u, v, t = np.meshgrid(x, x, x, indexing="ij")
    wu, wv, wt = np.meshgrid(w, w, w, indexing="ij")
    pts = np.stack([u, v * (1.0 - u), t * (1.0 - u) * (1.0 - v)], axis=-1).reshape(-1, 3)
    return pts, (wu * wv * wt * (1.0 - u) ** 2 * (1.0 - v)).ravel()


@cache
def quadrature(dim: int, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Points (q, dim) and weights (q,) on the reference simplex, exact to ``degree``."""
    if degree <= 1:
        return np.full((1, dim), 1.0 / (dim + 1)), np.array([1.0 / [1, 1, 2, 6][dim]])
    if degree == 2 and dim == 2:
        p = np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]])
        return p, np.full(3, 1 / 6)
    if degree == 2 and dim == 3:
        a, b = (5.0 + 3.0 * np.sqrt(5.0)) / 20.0, (5.0 - np.sqrt(5.0)) / 20.0
        p = np.array([[a, b, b], [b, a, b], [b, b, a], [b, b, b]])
        return p, np.full(4, 1 / 24)
    n = (degree + dim) // 2 + 1  # collapsed Gauss: exact to 2n - 1 after the Duffy factor
    return _collapsed(dim, n)


def facet_quadrature(dim: int, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """A rule on the reference facet (an interval in 2D, a triangle in 3D)."""
    return quadrature(dim - 1, degree)


def rest_jacobians(points: np.ndarray, cells: np.ndarray, dN: np.ndarray) -> np.ndarray:
    """J (m, q, d, d) of the rest map X(xi) at reference points with shape gradients dN
    (q, nv, d): J_ij = sum_a X^a_i dN^a/dxi_j."""
    return np.einsum("mai,qaj->mqij", points[cells], dN)
