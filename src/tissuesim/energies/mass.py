"""Mass matrices of P1 elements and the inertia energy of Backward Euler.

Consistent mass of a simplex with rest measure V and density rho (notes, eq. 10):
    int N^a N^b = V (1 + delta_ab) / ((d + 1)(d + 2))
i.e. V/12 [2 1 1; 1 2 1; 1 1 2] for triangles and V/20 (1 + delta_ab) for tetrahedra.
Lumped mass: each vertex gets rho V / (d + 1) (the row sums of the consistent matrix).

P2 elements integrate rho N^a N^b with a degree-4 rule over the (possibly curved) element. Their
consistent row sums are not all positive (a 10-node tetrahedron's corners get -V/20), so the
lumped mass is HRZ's (Hinton, Rock & Zienkiewicz 1976): the consistent diagonal scaled to the
element's mass, positive for every node; for P1 it equals the row sums. Q1 quadrilaterals and
hexahedra integrate with 3 Gauss points per direction; their row sums are positive, so their
lumped mass is the row sums. The quadratic ones (quad8, quad9, hexahedron20, hexahedron27)
integrate with 4 per direction; a serendipity cell's row sums are negative at its corners
(a hexahedron20's -V/8 each, its midside nodes V/6; a quad8's -A/12, A/3), so, as for P2,
their lumped mass is HRZ's (the consistent diagonal scaled to the cell's mass: positive at
every node). Linear wedges integrate with a rule exact for N^a N^b det J (``mesh/cells/wedge.py``);
their shape functions are non-negative, so their row sums are positive and, as for Q1, the
lumped mass is the row sums: they keep the element's mass and its first moments exactly
(sum_a m_a X_a = int rho X, the mass centre) and are the consistent nodal loads of a uniform
body force, so gravity is the same with either mass; HRZ keeps only the total (it equals the
row sums on a right prism, differs on a distorted wedge).
Gravity uses the consistent row sums (``row_sums``), which are exact for every element.

Inertia energy of Backward Euler with x_pred = x_n + h v_n (Gast et al. 2015):
    E(x) = 1/(2 h^2) (x - x_pred)^T M (x - x_pred).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.sparse as sp

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError
from tissuesim.kinematics.nodal import NodalKinematics
from tissuesim.kinematics.p2 import shape_values
from tissuesim.validate import short

__all__ = ["MassMatrix", "Inertia", "MassKind"]

MassKind = Literal["consistent", "lumped", "element_rule"]
#: the kinds: "consistent" (rho N^a N^b integrated exactly), "lumped" (its row sums, or HRZ),
#: "element_rule" (consistent, integrated by the element's own stiffness rule where that is
#: not exact: 2 Gauss points per direction on Q1 cells, as FEBio's hex8 mass; the exact rule
#: elsewhere)
MASS_KINDS = ("consistent", "lumped", "element_rule")


@dataclass(frozen=True, eq=False)
class MassMatrix:
    """M over the model's sparsity pattern: ``data`` (nnz,), ``lumped`` (n_dofs,) the diagonal
    mass (P1: row sums; P2: HRZ), ``row_sums`` (n_dofs,) the consistent matrix's row sums."""

    kind: MassKind
    pattern: SparsityPattern
    data: np.ndarray
    lumped: np.ndarray
    row_sums: np.ndarray
    dim: int | None = None  # FEM: DOFs per vertex (``dot``'s scalar blocks); frames: None

    @classmethod
    def build(
        cls,
        kinematics: NodalKinematics,
        density: np.ndarray,
        pattern: SparsityPattern,
        kind: MassKind = "consistent",
        stencil_id: int = 0,
    ) -> MassMatrix:
        if kind not in MASS_KINDS:
            raise InputError(
                f"mass must be 'consistent', 'lumped' or 'element_rule', not {short(kind)}"
            )
        d = kinematics.dim
        stencil = kinematics.cell_stencil
        nv = stencil.shape[1] // d
        if nv == d + 1:
            element_mass = density * kinematics.cell_weights  # (m,)
            ref = (np.ones((nv, nv)) + np.eye(nv)) / (nv * (nv + 1))  # sums to 1
            scalar = element_mass[:, None, None] * ref[None]
        else:  # P2 / Q1: rho N^a N^b by a rule exact on the element's rest map (or its own)
            rule = getattr(kinematics, "mass_rule", None)
            if rule is not None:  # a shell's (kinematics/shell.py)
                N, w = rule()
            else:  # (q, nv), (m, q)
                N, w = _element_rule(kinematics.mesh, kind == "element_rule")
            scalar = np.einsum("mq,qa,qb->mab", density[:, None] * w, N, N)
        if nv == d + 1:  # (m, nv) consistent row sums, column by column: numpy's own sums
            row = scalar[:, :, 0].copy()  # below 8 terms, without its loop over rows of nv
            for b in range(1, nv):
                row += scalar[:, :, b]
        else:  # pairwise from 8 terms on: numpy's sum as it was
            row = scalar.sum(axis=2)
        diag = np.einsum("maa->ma", scalar)
        positive = nv == 2**d or (d, nv) == (3, 6)  # Q1 and wedges: N^a >= 0
        if nv == d + 1 or positive and not kinematics.mesh.simplicial:  # row sums positive
            diagonal = row
        else:  # HRZ: positive, the same total
            diagonal = diag * (row.sum(axis=1) / diag.sum(axis=1))[:, None]
        if kind == "lumped":
            scalar = diagonal[:, :, None] * np.eye(nv)[None]
        blocks = pattern.blocks
        if blocks is not None and blocks.d == d and stencil_id < len(blocks.scatters):
            data = blocks.scalar_blocks(stencil_id, scalar, pattern.nnz)  # node by node
        else:
            local = np.zeros((len(scalar), nv, d, nv, d))
            for i in range(d):  # the scalar block on each component (einsum with I: 3x slower)
                local[:, :, i, :, i] = scalar
            local = local.reshape(-1, nv * d, nv * d)
            data = np.zeros(pattern.nnz)
            pattern.accumulate(data, stencil_id, local)

        def per_dof(values: np.ndarray) -> np.ndarray:  # (m, nv) -> (n_dofs,)
            return np.bincount(
                stencil.ravel(), weights=np.repeat(values, d, axis=1).ravel(), minlength=pattern.n
            )

        return cls(kind, pattern, data, per_dof(diagonal), per_dof(row), d)

    def matrix(self) -> sp.csr_matrix:
        """M as a CSR matrix over the model's pattern (sharing ``data``; made once)."""
        cached = self.__dict__.get("_matrix")
        if cached is None:
            cached = self.pattern.matrix(self.data)
            object.__setattr__(self, "_matrix", cached)
        return cached

    def dot(self, v: np.ndarray) -> np.ndarray:
        """M v. A vertex-major FEM mass is I_d (x) M_s, one scalar block per pair of
        vertices on each component: it is applied as M_s on the (n, d) array, which skips
        the pattern's zero entries between components (a third of the work in 3D) and adds
        the same terms in the same order (the same bits)."""
        scalar = self.__dict__.get("_scalar")
        if scalar is None:
            scalar = _scalar_blocks(self.matrix(), self.dim)
            object.__setattr__(self, "_scalar", scalar)
        if scalar is False or v.ndim != 1:
            return self.matrix() @ v
        return (scalar @ v.reshape(-1, self.dim)).reshape(-1)


def _scalar_blocks(M: sp.csr_matrix, d: int | None) -> sp.csr_matrix | bool:
    """M_s with M = M_s (x) I_d exactly (the rows and columns of component 0), or False when
    M is not of that form (frames' generalised mass, a pattern without d-blocks)."""
    if not d or d < 2 or M.shape[0] % d:
        return False
    scalar = M[0::d, 0::d].tocsr()
    scalar.sort_indices()
    if (sp.kron(scalar, sp.identity(d), format="csr") != M).nnz:
        return False
    return scalar


def _element_rule(mesh, stiffness_rule: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """N (q, nv) and weights (m, q) integrating N^a N^b exactly: a degree-4 rule for P2; for Q1
    3 Gauss points per direction (N^a N^b det J is of degree 4 in each variable); for the
    quadratic quadrilaterals and hexahedra 4 (degree 7: N^a N^b of degree 4 times det J of a
    cell with straight edges, degree 2 in 3D); for wedges a rule of degree 3 on the triangle
    and 4 along the axis (``wedge.mass_rule``). ``stiffness_rule``: Q1 cells by their own 2
    points per direction (FEBio's hex8 mass, exact only on parallelepipeds)."""
    if mesh.cell_type == "wedge":
        from tissuesim.kinematics.wedge import wedge_shape_values
        from tissuesim.mesh.cells.wedge import mass_rule

        return wedge_shape_values(mesh.points, mesh.cells, mass_rule())
    if not mesh.simplicial and mesh.order == 2:
        from tissuesim.kinematics.q2 import q2_shape_values

        return q2_shape_values(mesh.points, mesh.cells, 4)
    if not mesh.simplicial:
        from tissuesim.kinematics.q1 import q1_shape_values

        return q1_shape_values(mesh.points, mesh.cells, 2 if stiffness_rule else 3)
    return shape_values(mesh.points, mesh.cells, 2, 4)


@dataclass(frozen=True, eq=False)
class Inertia:
    """1/(2 h^2) (x - x_pred)^T M (x - x_pred) for one Backward Euler step."""

    mass: MassMatrix
    x_pred: np.ndarray
    time_step: float

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        s = 1.0 / self.time_step**2
        dx = x - self.x_pred
        Mdx = self.mass.dot(dx)
        acc.add_value("inertia", 0.5 * s * float(dx @ Mdx))
        if acc.order >= 1:
            acc.gradient += s * Mdx
        if acc.order >= 2:
            acc.hessian += s * self.mass.data
