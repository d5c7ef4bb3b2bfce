"""Quadratic quadrilateral and hexahedron kinematics: quad8, quad9, hexahedron20 and
hexahedron27, 3^d Gauss points per cell (FEBio's and FElupe's rule for them).

As for Q1 (``kinematics/q1.py``): at Gauss point xi_q the rest map's Jacobian is
J_q = sum_a X^a (dN_a/dxi)^T with the cell's shape functions (``mesh/cells/tensor_quadratic.py``),
dN_a/dX = J_q^{-T} dN_a/dxi and the weight w_q det J_q; F = sum_a x^a (dN_a/dX)^T is linear in
the cell's DOFs, so ``NodalKinematics`` does the rest and ``points_per_cell`` = 3^d groups a
cell's points for the Hessian's scatter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.kinematics.nodal import NodalKinematics
from tissuesim.kinematics.q1 import tensor_kinematics
from tissuesim.mesh.cells import tensor_quadratic as tq
from tissuesim.mesh.cells.tensor import gauss_rule, rest_jacobians
from tissuesim.mesh.mesh import Mesh

__all__ = ["Q2Kinematics", "q2_shape_values"]


def q2_shape_values(points: np.ndarray, cells: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """N (q, nv) at the n^d Gauss points and the weights (m, q) w_q det J of every cell."""
    d = points.shape[1]
    xi, w = gauss_rule(d, n)
    N, dN = tq.shape_functions(tq.CELL_TYPES[d, cells.shape[1]], xi)
    return N, w[None, :] * np.linalg.det(rest_jacobians(points, cells, dN))


@dataclass(frozen=True, eq=False)
class Q2Kinematics(NodalKinematics):
    """Deformation gradients of a quadratic quadrilateral / hexahedral mesh at its 3^d Gauss
    points per cell. Arrays are per Gauss point, cell-major: point e * nq + k is point k of
    cell e."""

    mesh: Mesh | None = None

    @classmethod
    def from_mesh(cls, mesh: Mesh) -> Q2Kinematics:
        if mesh.cell_fractions is not None:
            from tissuesim.errors import InputError

            raise InputError(
                f"a virtual-node cut applies to linear simplices; this mesh is {mesh.cell_type}"
            )
        xi, w = gauss_rule(mesh.dim, tq.STIFFNESS_POINTS)
        _, dN = tq.shape_functions(mesh.cell_type, xi)  # (nq, nv, d)
        return tensor_kinematics(cls, mesh, w, dN)
