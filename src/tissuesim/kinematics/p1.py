"""P1 (linear simplex) kinematics: triangles in 2D, tetrahedra in 3D.

Each element is one integration point. With rest vertices X^a and shape functions N^a
(barycentric coordinates), the constant shape gradients are (notes, eq. 16)

    dN/dX = [X^1 .. X^{d+1}; 1 .. 1]^{-1} [I_d; 0]          (d+1, d) per element

and the deformation gradient of current positions x^a is F = sum_a x^a (dN^a/dX)^T
(notes, eq. 17 with x = X + u). F is linear in the element's DOFs, so its derivative

    B[e, (i, j), (a, k)] = dF_ij / dx^a_k = delta_ik dN^a/dX_j        (m, d*d, (d+1)*d)

is constant, and the geometric term P : d2F/dx2 vanishes.

DOF numbering: vertex a, component i -> a * d + i (vertex-major, as the notes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.mesh.mesh import Mesh

__all__ = ["P1Kinematics", "shape_gradients"]


def shape_gradients(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shape-function gradients (m, d+1, d) and rest measures (m,) (area or volume)."""
    d = points.shape[1]
    Xe = points[cells]  # (m, d+1, d)
    Dm = np.swapaxes(Xe[:, 1:] - Xe[:, :1], 1, 2)  # (m, d, d) edge matrix, columns X^a - X^0
    Dm_inv = np.linalg.inv(Dm)  # rows: gradients of N^1..N^d
    grads = np.empty((cells.shape[0], d + 1, d))
    grads[:, 1:] = Dm_inv
    grads[:, 0] = -Dm_inv.sum(axis=1)
    measure = np.abs(np.linalg.det(Dm)) / (2.0 if d == 2 else 6.0)
    return grads, measure


@dataclass(frozen=True, eq=False)
class P1Kinematics:
    """Deformation gradients of a P1 mesh; one integration point per element.

    stencil: (m, (d+1)*d) global DOFs of each element, in local order (a, k).
    weights: (m,) rest areas / volumes (integration weights).
    grads:   (m, d+1, d) shape gradients dN^a/dX.
    """

    mesh: Mesh
    stencil: np.ndarray
    weights: np.ndarray
    grads: np.ndarray

    @classmethod
    def from_mesh(cls, mesh: Mesh) -> P1Kinematics:
        d = mesh.dim
        grads, measure = shape_gradients(mesh.points, mesh.cells)
        stencil = (mesh.cells[:, :, None] * d + np.arange(d)).reshape(mesh.n_cells, -1)
        return cls(mesh=mesh, stencil=stencil, weights=measure, grads=grads)

    @property
    def dim(self) -> int:
        return self.mesh.dim

    @property
    def n_dofs(self) -> int:
        return self.mesh.n_points * self.mesh.dim

    @property
    def constant_jacobian(self) -> bool:
        return True

    def deformation_gradients(self, x: np.ndarray) -> np.ndarray:
        """F (m, d, d) from positions x, flat (n*d,) or (n, d)."""
        xe = x.reshape(-1, self.dim)[self.mesh.cells]  # (m, d+1, d)
        return np.matmul(np.swapaxes(xe, 1, 2), self.grads)  # F_ij = sum_a x^a_i dN^a_j

    def stress_to_gradient(self, P: np.ndarray) -> np.ndarray:
        """Local gradient (m, (d+1)*d) of sum_e w_e psi_e: w dN^a_j P_ij, given P (m, d, d)."""
        g = np.matmul(self.grads, np.swapaxes(P, 1, 2))  # (m, d+1, d): [a, i] = sum_j dN^a_j P_ij
        return (g * self.weights[:, None, None]).reshape(P.shape[0], -1)

    def tangent_to_hessian(self, A: np.ndarray) -> np.ndarray:
        """Local Hessian (m, nloc, nloc) from dP/dF A (m, d, d, d, d).

        H[(a,i),(b,k)] = w sum_{j,l} A[i,j,k,l] dN^a_j dN^b_l.
        """
        m, d = A.shape[0], self.dim
        G = self.grads  # (m, d+1, d)
        # contract j with dN^a, then l with dN^b; batched matmuls, no Python loop over elements
        T = np.matmul(G[:, None, :, :], A.reshape(m, d, d, d * d))  # (m, i, a, (k,l))
        T = T.reshape(m, d, d + 1, d, d)  # [m, i, a, k, l]
        H = np.matmul(T, np.swapaxes(G, 1, 2)[:, None, None, :, :])  # (m, i, a, k, b)
        H = H.transpose(0, 2, 1, 4, 3).reshape(m, (d + 1) * d, (d + 1) * d)
        return H * self.weights[:, None, None]
