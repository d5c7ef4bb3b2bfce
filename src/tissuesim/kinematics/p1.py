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

from tissuesim.kinematics.nodal import NodalKinematics
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
class P1Kinematics(NodalKinematics):
    """Deformation gradients of a P1 mesh; one integration point per element.

    cells:   the mesh's (m, d+1) elements.
    stencil: (m, (d+1)*d) global DOFs of each element, in local order (a, k).
    weights: (m,) rest areas / volumes (integration weights).
    grads:   (m, d+1, d) shape gradients dN^a/dX.
    """

    mesh: Mesh | None = None

    @classmethod
    def from_mesh(cls, mesh: Mesh, rest: tuple | None = None) -> P1Kinematics:
        """The kinematics of ``mesh``; ``rest``: its cells' (shape gradients, rest measures)
        when known (the copies of a cut cell keep their parent's rest shape)."""
        grads, measure = shape_gradients(mesh.points, mesh.cells) if rest is None else rest
        if mesh.cell_fractions is not None:  # virtual-node copies integrate their part only
            measure = measure * mesh.cell_fractions
        return cls(
            cells=mesh.cells,
            stencil=cls.dof_stencil(mesh.cells, mesh.dim),
            weights=measure,
            grads=grads,
            n_nodes=mesh.n_points,
            mesh=mesh,
        )
