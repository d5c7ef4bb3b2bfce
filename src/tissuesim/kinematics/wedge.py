"""Linear wedge kinematics: 6-node prisms, 6 integration points per cell (FEBio's FEPenta6G6:
the 3-point triangle rule times 2 Gauss points along the axis, ``mesh/cells/wedge.py``).

As for Q1 (``kinematics/q1.py``): at point xi_q the rest map's Jacobian is
J_q = sum_a X^a (dN_a/dxi)^T, dN_a/dX = J_q^{-T} dN_a/dxi and the weight w_q det J_q;
F = sum_a x^a (dN_a/dX)^T is linear in the cell's DOFs, so ``NodalKinematics`` computes F,
forces and Hessians per point, ``points_per_cell`` = 6 groups a cell's points for the Hessian's
scatter (and for the fused loop and the mean-dilatation patch, one per cell).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.kinematics.nodal import NodalKinematics
from tissuesim.kinematics.q1 import tensor_kinematics
from tissuesim.mesh.cells import wedge
from tissuesim.mesh.cells.tensor import rest_jacobians
from tissuesim.mesh.mesh import Mesh

__all__ = ["WedgeKinematics", "wedge_shape_values"]


def wedge_shape_values(
    points: np.ndarray, cells: np.ndarray, rule: tuple[np.ndarray, np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """N (q, 6) at a rule's points (xi (q, 3), w (q,)) and the weights (m, q) w_q det J of
    every wedge."""
    xi, w = rule
    N, dN = wedge.shape_functions(xi)
    return N, w[None, :] * np.linalg.det(rest_jacobians(points, cells, dN))


@dataclass(frozen=True, eq=False)
class WedgeKinematics(NodalKinematics):
    """Deformation gradients of a wedge mesh at its 6 integration points per cell. Arrays are
    per point, cell-major: point e * 6 + k is point k of cell e."""

    mesh: Mesh | None = None

    @classmethod
    def from_mesh(cls, mesh: Mesh) -> WedgeKinematics:
        """The kinematics of ``mesh`` (6-node wedges) at FEBio's 6 points per cell."""
        if mesh.cell_fractions is not None:
            from tissuesim.errors import InputError

            raise InputError("a virtual-node cut applies to linear simplices; this mesh has wedges")
        xi, w = wedge.stiffness_rule()
        _, dN = wedge.shape_functions(xi)  # (6, 6, 3)
        return tensor_kinematics(cls, mesh, w, dN)
