"""FEBio's quadratic shell (``quad8`` in a ``<ShellDomain>``) as a solid: a 20-node hexahedron
whose four through-the-thickness midside nodes carry nothing (formulation "shell").

FEBio's shell (``FESSIShellDomain``; ``FEShellQuad8G18`` in ``FECore/FEElementTraits.cpp``)
interpolates a point (r, s, t) as sum_a M_a(r, s) [(1 - t)/2 Y_a + (1 + t)/2 X_a]: M_a the
8-node serendipity quadrilateral's functions, X_a the shell's nodes (its front face) and
Y_a = X_a - D_a their back face (the DOFs w), and integrates 3 x 3 Gauss points in the plane
times 2 through the thickness (18). Quadratic in the plane and linear through the thickness,
that map is a 16-node solid; it lies in the 20-node hexahedron's (serendipity) space, so a
hexahedron20 whose bottom face is the back face (its nodes 0-3, 8-11: corners, then midside
nodes), whose top face is the shell's (4-7, 12-15) and whose vertical edges' midside nodes
(16-19) sit halfway is the same rest map. Here the hexahedron20's nodes 16-19 get zero shape
functions: F = sum over the 16 others of x_a (dN_a/dX)^T with N_a = M_a (1 -+ t)/2, on FEBio's
18 points; F is linear in the nodes again, so ``NodalKinematics`` computes F, forces and
Hessians unchanged. The midside nodes carry no energy and no mass, and the model holds them
at rest (``Model``): they only draw the element (the mesh stays a valid hexahedron20 mesh
for files, facets, tractions on the shell's faces and pictures).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.kinematics.nodal import NodalKinematics
from tissuesim.kinematics.q1 import tensor_kinematics
from tissuesim.mesh.cells import tensor_quadratic as tq
from tissuesim.mesh.cells.tensor import rest_jacobians
from tissuesim.mesh.mesh import Mesh

__all__ = ["ShellKinematics", "shell_rule", "shell_shape_functions", "THICKNESS_MIDSIDES"]

#: the hexahedron20's nodes on its vertical edges (VTK's order): no shape function here
THICKNESS_MIDSIDES = np.arange(16, 20)


def shell_rule() -> tuple[np.ndarray, np.ndarray]:
    """FEBio's FEShellQuad8G18: points (18, 3) (r, s in the plane, t through the thickness,
    t = -+1/sqrt(3), r fastest) and weights (18,) (summing to 8)."""
    x3, w3 = np.polynomial.legendre.leggauss(3)
    x2, w2 = np.polynomial.legendre.leggauss(2)
    t, s, r = np.meshgrid(x2, x3, x3, indexing="ij")
    wt, ws, wr = np.meshgrid(w2, w3, w3, indexing="ij")
    points = np.column_stack([r.ravel(), s.ravel(), t.ravel()])
    return points, (wr * ws * wt).ravel()


def shell_shape_functions(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """N (q, 20) and dN/dxi (q, 20, 3) of the shell on a hexahedron20 at points xi (q, 3):
    N = M_a(r, s) (1 - t)/2 for the bottom (back) face's nodes 0-3, 8-11, M_a(r, s) (1 + t)/2
    for the top face's 4-7, 12-15, and 0 for 16-19 (M the quad8's functions, VTK's order)."""
    xi = np.atleast_2d(np.asarray(xi, dtype=np.float64))
    M, dM = tq.shape_functions("quad8", xi[:, :2])  # (q, 8), (q, 8, 2)
    t = xi[:, 2:3]
    below, above = (1.0 - t) / 2.0, (1.0 + t) / 2.0
    q = len(xi)
    N = np.zeros((q, 20))
    dN = np.zeros((q, 20, 3))
    for rows, side, sign in (([0, 1, 2, 3, 8, 9, 10, 11], below, -0.5),
                             ([4, 5, 6, 7, 12, 13, 14, 15], above, 0.5)):  # fmt: skip
        N[:, rows] = M * side
        dN[:, rows, :2] = dM * side[:, :, None]
        dN[:, rows, 2] = sign * M
    return N, dN


@dataclass(frozen=True, eq=False)
class ShellKinematics(NodalKinematics):
    """Deformation gradients of a hexahedron20 mesh read as FEBio's quad8 shells, at FEBio's
    18 points per cell. Arrays are per point, cell-major: point e * 18 + k is point k of cell
    e; the thickness midside nodes' gradients are zero."""

    mesh: Mesh | None = None

    @classmethod
    def from_mesh(cls, mesh: Mesh) -> ShellKinematics:
        """The kinematics of ``mesh`` (hexahedron20 cells, the bottom face the shell's back)."""
        from tissuesim.errors import InputError

        if mesh.cell_type != "hexahedron20":
            raise InputError(
                f"the 'shell' formulation takes hexahedron20 cells (FEBio's quad8 shells), not "
                f"{mesh.cell_type}"
            )
        xi, w = shell_rule()
        _, dN = shell_shape_functions(xi)
        return tensor_kinematics(cls, mesh, w, dN)

    def mass_rule(self) -> tuple[np.ndarray, np.ndarray]:
        """N (18, 20) and weights (m, 18) w_q det J: FEBio's shell mass (its 18 points, exact
        for rho N^a N^b on a flat element of straight edges, degree 4 in r, s and 2 in t)."""
        assert self.mesh is not None
        xi, w = shell_rule()
        N, dN = shell_shape_functions(xi)
        detJ = np.linalg.det(rest_jacobians(self.mesh.points, self.mesh.cells, dN))
        return N, w[None, :] * detJ

    def thickness_midsides(self) -> np.ndarray:
        """(k,) the nodes on the cells' vertical edges, which carry nothing (held at rest)."""
        assert self.mesh is not None
        return np.unique(self.mesh.cells[:, THICKNESS_MIDSIDES])
