"""Q1 kinematics: 4-node quadrilaterals and 8-node hexahedra, 2^d Gauss points per cell.

At Gauss point xi_q of [-1, 1]^d the rest map X(xi) = sum_a X^a N_a(xi) has the Jacobian
J_q = sum_a X^a (dN_a/dxi)^T (``mesh/cells/tensor.py``); the shape gradients there are
dN_a/dX = J_q^{-T} dN_a/dxi and the weight w_q det J_q. F = sum_a x^a (dN_a/dX)^T is linear in
the cell's DOFs with constant gradients at each point, so ``NodalKinematics`` computes F,
forces and Hessians per point unchanged, and ``points_per_cell`` = 2^d groups a cell's points
(the Hessian is summed over them and scattered once per cell), exactly as for P2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.kinematics.nodal import NodalKinematics
from tissuesim.mesh.cells.tensor import gauss_rule, rest_jacobians, shape_functions
from tissuesim.mesh.mesh import Mesh

__all__ = ["Q1Kinematics", "q1_shape_values", "tensor_kinematics"]

#: Gauss points per direction of the stiffness (exact for a parallelepiped's Q1 stiffness)
STIFFNESS_POINTS = 2


def q1_shape_values(points: np.ndarray, cells: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """N (q, nv) at the n^d Gauss points and the weights (m, q) w_q det J of every cell."""
    d = points.shape[1]
    xi, w = gauss_rule(d, n)
    N, dN = shape_functions(d, xi)
    return N, w[None, :] * np.linalg.det(rest_jacobians(points, cells, dN))


@dataclass(frozen=True, eq=False)
class Q1Kinematics(NodalKinematics):
    """Deformation gradients of a Q1 mesh at its 2^d Gauss points per cell.

    Arrays are per Gauss point, cell-major: point e * nq + k is point k of cell e.
    """

    mesh: Mesh | None = None

    @classmethod
    def from_mesh(cls, mesh: Mesh) -> Q1Kinematics:
        if mesh.cell_fractions is not None:
            from tissuesim.errors import InputError

            raise InputError("a virtual-node cut applies to linear simplices; this mesh is Q1")
        xi, w = gauss_rule(mesh.dim, STIFFNESS_POINTS)
        _, dN = shape_functions(mesh.dim, xi)  # (nq, nv, d)
        return tensor_kinematics(cls, mesh, w, dN)


def tensor_kinematics(cls, mesh: Mesh, w: np.ndarray, dN: np.ndarray):
    """``cls`` (Q1 or Q2 kinematics) of ``mesh`` from its reference shape gradients dN
    (nq, nv, d) at Gauss points of weights w (nq,): per point dN/dX = J^-T dN/dxi and the
    weight w det J, cell-major."""
    d = mesh.dim
    Jac = rest_jacobians(mesh.points, mesh.cells, dN)  # (m, nq, d, d)
    inv = np.linalg.inv(Jac)
    grads = np.einsum("qaj,mqji->mqai", dN, inv)  # dN/dX_i = sum_j dN/dxi_j (J^-1)_ji
    weights = w[None, :] * np.linalg.det(Jac)
    m, nq = Jac.shape[:2]
    cells = np.repeat(mesh.cells, nq, axis=0)
    return cls(
        cells=cells,
        stencil=cls.dof_stencil(cells, d),
        weights=weights.reshape(-1),
        grads=np.ascontiguousarray(grads.reshape(m * nq, -1, d)),
        n_nodes=mesh.n_points,
        points_per_cell=nq,
        mesh=mesh,
    )
