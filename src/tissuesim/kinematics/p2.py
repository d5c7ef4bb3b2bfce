"""P2 (quadratic simplex) kinematics: 6-node triangles and 10-node tetrahedra, possibly curved.

At each quadrature point xi_q of the reference simplex (``kinematics/reference.py``) the rest
map X(xi) = sum_a X^a N^a(xi) has the Jacobian J_q = sum_a X^a (dN^a/dxi)^T; the shape
gradients there are dN^a/dX = J_q^{-T} dN^a/dxi and the integration weight w_q |det J_q|.
F = sum_a x^a (dN^a/dX)^T is again linear in the element's DOFs with constant gradients, so
``NodalKinematics`` computes F, forces and Hessians per quadrature point unchanged; its
``points_per_cell`` groups an element's points so that the Hessian is scattered once per element.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.kinematics.nodal import NodalKinematics
from tissuesim.mesh.cells.reference import (
    quadrature,
    rest_jacobians,
    shape_functions,
    stiffness_degree,
)
from tissuesim.mesh.mesh import Mesh

__all__ = ["P2Kinematics", "shape_values"]


def shape_values(
    points: np.ndarray, cells: np.ndarray, order: int, degree: int
) -> tuple[np.ndarray, np.ndarray]:
    """N (q, nv) at a rule's points and the weights (m, q) w_q |det J| of every element."""
    d = points.shape[1]
    xi, w = quadrature(d, degree)
    N, dN = shape_functions(d, order, xi)
    return N, w[None, :] * np.abs(np.linalg.det(rest_jacobians(points, cells, dN)))


@dataclass(frozen=True, eq=False)
class P2Kinematics(NodalKinematics):
    """Deformation gradients of a P2 mesh at ``points_per_cell`` quadrature points per element.

    Arrays are per quadrature point, element-major: point e * nq + k is point k of element e.
    """

    mesh: Mesh | None = None

    @classmethod
    def from_mesh(cls, mesh: Mesh) -> P2Kinematics:
        if mesh.cell_fractions is not None:
            from tissuesim.errors import InputError

            raise InputError("a virtual-node cut applies to linear (P1) cells; this is order 2")
        d = mesh.dim
        xi, w = quadrature(d, stiffness_degree(2))
        _, dN = shape_functions(d, 2, xi)  # (nq, nv, d)
        Jac = rest_jacobians(mesh.points, mesh.cells, dN)  # (m, nq, d, d)
        inv = np.linalg.inv(Jac)
        grads = np.einsum("qaj,mqji->mqai", dN, inv)  # dN/dX_i = sum_j dN/dxi_j (J^-1)_ji
        weights = w[None, :] * np.abs(np.linalg.det(Jac))
        m, nq = Jac.shape[:2]
        cells = np.repeat(mesh.cells, nq, axis=0)
        return cls(
            cells=cells,
            stencil=cls.dof_stencil(cells, d),
            weights=weights.reshape(-1),
            grads=grads.reshape(m * nq, -1, d),
            n_nodes=mesh.n_points,
            points_per_cell=nq,
            mesh=mesh,
        )
