"""Kinematics where F is linear in nodal vectors with constant gradients: F = sum_a z^a (G^a)^T.

P1 elements are the first case (z^a vertex positions, G^a = dN^a/dX, d+1 nodes per point). Frame
models are the second: a frame (x_i, A_i) is four "virtual nodes" in R^3, its origin x_i and the
columns of A_i, and F at an integration point is again sum_a z^a (G^a)^T with constant G
(``frames/kinematics.py``). Both share the batched NumPy maps below and the fused Numba loop.

    F_ij = sum_a z^a_i G^a_j
    dE/dz^a_i = w sum_j G^a_j P_ij
    d2E/dz^a_i dz^b_k = w sum_{j,l} A_ijkl G^a_j G^b_l
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["NodalKinematics", "local_hessians"]


@dataclass(frozen=True, eq=False)
class NodalKinematics:
    """F at q integration points from nodal vectors.

    cells:   (q, nv) node indices per integration point.
    stencil: (q, nv*d) global DOFs of each point, in local order (a, k): node a, component k.
    weights: (q,) integration weights (rest areas / volumes).
    grads:   (q, nv, d) constant gradients G^a.
    n_nodes: number of nodes; DOF of node a, component k is a * d + k.
    points_per_cell: consecutive points that share one element's stencil (P2: its quadrature
        points); the Hessian is summed over them and scattered once per element.
    """

    cells: np.ndarray
    stencil: np.ndarray
    weights: np.ndarray
    grads: np.ndarray
    n_nodes: int
    points_per_cell: int = 1

    @staticmethod
    def dof_stencil(cells: np.ndarray, d: int) -> np.ndarray:
        return (cells[:, :, None] * d + np.arange(d)).reshape(cells.shape[0], -1)

    @property
    def cell_stencil(self) -> np.ndarray:
        """(m, nv*d) the stencil once per element (the sparsity pattern's stencil)."""
        return self.stencil[:: self.points_per_cell]

    @property
    def cell_weights(self) -> np.ndarray:
        """(m,) rest measure of each element (the sum of its points' weights)."""
        return self.per_cell_sum(self.weights)

    def per_cell_sum(self, values: np.ndarray) -> np.ndarray:
        """Sum of per-point values (q, ...) over each element's points: (m, ...)."""
        nq = self.points_per_cell
        if nq == 1:
            return values
        return values.reshape(-1, nq, *values.shape[1:]).sum(axis=1)

    def cell_average(self, values: np.ndarray) -> np.ndarray:
        """Weighted mean of per-point values (q, ...) over each element: (m, ...)."""
        if self.points_per_cell == 1:
            return values
        w = self.weights.reshape(-1, *([1] * (values.ndim - 1)))
        return self.per_cell_sum(values * w) / self.per_cell_sum(w)

    @property
    def dim(self) -> int:
        return int(self.grads.shape[2])

    @property
    def n_dofs(self) -> int:
        return self.n_nodes * self.dim

    @property
    def constant_jacobian(self) -> bool:
        return True

    def deformation_gradients(self, x: np.ndarray) -> np.ndarray:
        """F (q, d, d) from nodal vectors x, flat (n*d,) or (n, d)."""
        xe = x.reshape(-1, self.dim)[self.cells]  # (q, nv, d)
        return np.matmul(np.swapaxes(xe, 1, 2), self.grads)  # F_ij = sum_a x^a_i G^a_j

    def stress_to_gradient(self, P: np.ndarray) -> np.ndarray:
        """Local gradient (q, nv*d) of sum_q w_q psi_q: w G^a_j P_ij, given P (q, d, d)."""
        g = np.matmul(self.grads, np.swapaxes(P, 1, 2))  # (q, nv, d): [a, i] = sum_j G^a_j P_ij
        return (g * self.weights[:, None, None]).reshape(P.shape[0], -1)

    def tangent_to_hessian(self, A: np.ndarray) -> np.ndarray:
        """Local Hessian (q, nloc, nloc) from dP/dF A (q, d, d, d, d).

        H[(a,i),(b,k)] = w sum_{j,l} A[i,j,k,l] G^a_j G^b_l.
        """
        return local_hessians(self.grads, self.weights, A)


def local_hessians(G: np.ndarray, w: np.ndarray, A: np.ndarray) -> np.ndarray:
    """w sum_{j,l} A[i,j,k,l] G^a_j G^b_l as (q, nv*d, nv*d), for G (q, nv, d), w (q,)."""
    m, nv, d = G.shape
    # contract j with G^a, then l with G^b; batched matmuls, no Python loop over points
    T = np.matmul(G[:, None, :, :], A.reshape(m, d, d, d * d))  # (m, i, a, (k,l))
    T = T.reshape(m, d, nv, d, d)  # [m, i, a, k, l]
    H = np.matmul(T, np.swapaxes(G, 1, 2)[:, None, None, :, :])  # (m, i, a, k, b)
    H = H.transpose(0, 2, 1, 4, 3).reshape(m, nv * d, nv * d)
    return H * w[:, None, None]
