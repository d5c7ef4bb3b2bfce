"""A point's closest-point projection onto a facet surface and its signed gap, with the gap's
exact first and second derivatives.

For a point x (on the sampled surface, x = sum_k Hs_k X_k) and a facet q(r, s) = sum_a H_a x_a
(any of ``faces.py``'s kinds: tri3, quad4, tri6, quad8), the projection (r, s) makes
r_vec = q - x normal to the facet (q_a . r_vec = 0, a = r, s; found by Newton);
nu = q_r x q_s / |q_r x q_s| is the facet's outward normal there and the gap g = nu . (q - x)
is positive where x lies behind the surface (penetration: FEBio's sign,
``FEFacet2FacetSliding::ProjectSurface``). Over the stencil y = (X_k, x_a):

    dg/dy = J^T nu,   J = dr_vec/dy at fixed (r, s) = [-Hs_k I, H_a I],

exactly (nu and (r, s) move only along directions normal to r_vec). Its Hessian, from the
envelope theorem on D = |q - x|^2 / 2 = g^2 / 2 (d2D = dg dg^T + g d2g) and the metric
G = [q_a . q_b], curvature K = [q_ab . nu] (q_rr, q_ss zero on linear facets), A = G + g K,
T = [q_r; q_s], C = [0, dH_a/d(r, s) nu^T]:

    d2g = J^T T^T G^-1 K A^-1 T J - C^T A^-1 T J - J^T T^T A^-1 C - g C^T A^-1 C,

finite at g = 0 (tests check both against finite differences).
"""

from __future__ import annotations

import numpy as np

from tissuesim.contact.penalty.faces import TRIANGLES, shape, shape_derivatives

__all__ = ["project", "gap_derivatives", "outside", "projection_jacobian"]

_NEWTON_ITERATIONS = 12


def project(x: np.ndarray, X: np.ndarray, kind: np.ndarray):
    """Project points x (n, 3) onto facets with nodes X (n, m, 3) of the given kinds (n,).
    Returns (r, s) (n, 2) of the point where q - x is normal to the facet's surface, not
    clamped to the facet."""
    n, m = len(x), X.shape[1]
    triangle = np.isin(kind, TRIANGLES)
    rs = np.where(triangle[:, None], 1.0 / 3.0, 0.0) * np.ones((n, 2))
    for _ in range(_NEWTON_ITERATIONS):
        Hr, Hs, Hrr, Hss, Hrs = shape_derivatives(rs[:, 0], rs[:, 1], kind, m)
        H = shape(rs[:, 0], rs[:, 1], kind, m)
        q = np.einsum("na,nad->nd", H, X)
        qr = np.einsum("na,nad->nd", Hr, X)
        qs = np.einsum("na,nad->nd", Hs, X)
        d = q - x
        grad = np.column_stack([np.sum(qr * d, 1), np.sum(qs * d, 1)])
        A = np.empty((n, 2, 2))
        A[:, 0, 0] = np.sum(qr * qr, 1) + np.sum(np.einsum("na,nad->nd", Hrr, X) * d, 1)
        A[:, 1, 1] = np.sum(qs * qs, 1) + np.sum(np.einsum("na,nad->nd", Hss, X) * d, 1)
        A[:, 0, 1] = A[:, 1, 0] = np.sum(qr * qs, 1) + np.sum(
            np.einsum("na,nad->nd", Hrs, X) * d, 1
        )
        det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] ** 2
        bad = np.abs(det) <= 1e-300
        det = np.where(bad, 1.0, det)
        step = np.column_stack(
            [
                (A[:, 1, 1] * grad[:, 0] - A[:, 0, 1] * grad[:, 1]) / det,
                (A[:, 0, 0] * grad[:, 1] - A[:, 0, 1] * grad[:, 0]) / det,
            ]
        )
        step[bad] = 0.0
        rs = rs - step
        scale = np.sqrt(np.maximum(np.sum(qr * qr, 1) + np.sum(qs * qs, 1), 1e-300))
        if np.all(np.abs(grad).max(axis=1) <= 1e-14 * scale * (scale + np.abs(d).max(1))):
            break
    return rs


def outside(rs: np.ndarray, kind: np.ndarray) -> np.ndarray:
    """How far (r, s) lies outside its facet, in natural coordinates (0 on it)."""
    r, s = rs[:, 0], rs[:, 1]
    quad = np.maximum(np.maximum(np.abs(r), np.abs(s)) - 1.0, 0.0)
    tri = np.maximum.reduce([-r, -s, r + s - 1.0, np.zeros_like(r)])
    return np.where(np.isin(kind, TRIANGLES), tri, quad)


def gap_derivatives(x, Hs, X, rs, kind, order: int):
    """At projections rs of points x (n, 3) onto facets X (n, m, 3) of the given kinds: the
    gap g (n,), the normal nu (n, 3), the master shape values Hm (n, m), and with order >= 1
    dg/dy (n, k + m, 3) over the stencil (the sampled facet's k nodes with weights Hs (n, k),
    then the facet's m), with order >= 2 d2g/dy2 (n, 3(k + m), 3(k + m)) (module docstring)."""
    r, s = rs[:, 0], rs[:, 1]
    m = X.shape[1]
    Hm = shape(r, s, kind, m)
    Hr, Hsd, Hrr, Hss, Hrs = shape_derivatives(r, s, kind, m)
    q = np.einsum("na,nad->nd", Hm, X)
    qr = np.einsum("na,nad->nd", Hr, X)
    qs = np.einsum("na,nad->nd", Hsd, X)
    N = np.cross(qr, qs)
    nu = N / np.linalg.norm(N, axis=1)[:, None]
    g = np.sum(nu * (q - x), axis=1)
    out = [g, nu, Hm]
    if order < 1:
        return out
    w = np.concatenate([-Hs, Hm], axis=1)  # (n, k + m): J = w (x) I
    grad = w[:, :, None] * nu[:, None, :]
    out.append(grad)
    if order < 2:
        return out
    n, width = len(x), w.shape[1]
    k = width - m
    T = np.stack([qr, qs], axis=1)  # (n, 2, 3)
    G = np.einsum("nad,nbd->nab", T, T)
    K = np.empty((n, 2, 2))
    K[:, 0, 0] = np.sum(np.einsum("na,nad->nd", Hrr, X) * nu, 1)
    K[:, 1, 1] = np.sum(np.einsum("na,nad->nd", Hss, X) * nu, 1)
    K[:, 0, 1] = K[:, 1, 0] = np.sum(np.einsum("na,nad->nd", Hrs, X) * nu, 1)
    A = G + g[:, None, None] * K
    Ai = np.linalg.inv(A)
    Gi = np.linalg.inv(G)
    M = Gi @ K @ Ai
    M = 0.5 * (M + np.swapaxes(M, 1, 2))
    TJ = w[:, None, :, None] * T[:, :, None, :]  # (n, 2, k + m, 3): T J
    TJ = TJ.reshape(n, 2, 3 * width)
    dH = np.zeros((n, 2, width))
    dH[:, 0, k:] = Hr
    dH[:, 1, k:] = Hsd
    C = (dH[:, :, :, None] * nu[:, None, None, :]).reshape(n, 2, 3 * width)
    hess = np.einsum("nai,nab,nbj->nij", TJ, M, TJ)
    cross = np.einsum("nai,nab,nbj->nij", C, Ai, TJ)
    hess -= cross + np.swapaxes(cross, 1, 2)
    hess -= g[:, None, None] * np.einsum("nai,nab,nbj->nij", C, Ai, C)
    out.append(hess)
    return out


def projection_jacobian(x, Hs, X, rs, kind):
    """At projections rs of points x (n, 3) (x = sum_k Hs_k X_k) onto facets X (n, m, 3):
    the gap g (n,) and dr/dy (n, 2, 3(k + m)), the natural coordinates' derivative over the
    stencil (the sampled facet's k nodes, then the facet's m), from the projection's
    optimality q_a . (q - x) = 0:

        A dr = -(T J + g C) dy,   A = G + g K

    (T, J, C, G, K as in the module docstring)."""
    r, s = rs[:, 0], rs[:, 1]
    n, m = X.shape[0], X.shape[1]
    Hm = shape(r, s, kind, m)
    Hr, Hsd, Hrr, Hss, Hrs = shape_derivatives(r, s, kind, m)
    q = np.einsum("na,nad->nd", Hm, X)
    qr = np.einsum("na,nad->nd", Hr, X)
    qs = np.einsum("na,nad->nd", Hsd, X)
    N = np.cross(qr, qs)
    nu = N / np.linalg.norm(N, axis=1)[:, None]
    g = np.sum(nu * (q - x), axis=1)
    T = np.stack([qr, qs], axis=1)
    K = np.empty((n, 2, 2))
    K[:, 0, 0] = np.sum(np.einsum("na,nad->nd", Hrr, X) * nu, 1)
    K[:, 1, 1] = np.sum(np.einsum("na,nad->nd", Hss, X) * nu, 1)
    K[:, 0, 1] = K[:, 1, 0] = np.sum(np.einsum("na,nad->nd", Hrs, X) * nu, 1)
    A = np.einsum("nad,nbd->nab", T, T) + g[:, None, None] * K
    w = np.concatenate([-Hs, Hm], axis=1)
    width, k = w.shape[1], Hs.shape[1]
    TJ = (w[:, None, :, None] * T[:, :, None, :]).reshape(n, 2, 3 * width)
    dH = np.zeros((n, 2, width))
    dH[:, 0, k:] = Hr
    dH[:, 1, k:] = Hsd
    C = (dH[:, :, :, None] * nu[:, None, None, :]).reshape(n, 2, 3 * width)
    return g, -np.linalg.solve(A, TJ + g[:, None, None] * C)
