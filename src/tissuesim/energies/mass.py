"""Mass matrices of P1 elements and the inertia energy of Backward Euler.

Consistent mass of a simplex with rest measure V and density rho (notes, eq. 10):
    int N^a N^b = V (1 + delta_ab) / ((d + 1)(d + 2))
i.e. V/12 [2 1 1; 1 2 1; 1 1 2] for triangles and V/20 (1 + delta_ab) for tetrahedra.
Lumped mass: each vertex gets rho V / (d + 1) (the row sums of the consistent matrix).

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
from tissuesim.kinematics.p1 import P1Kinematics
from tissuesim.validate import short

__all__ = ["MassMatrix", "Inertia", "MassKind"]

MassKind = Literal["consistent", "lumped"]


@dataclass(frozen=True, eq=False)
class MassMatrix:
    """M over the model's sparsity pattern: ``data`` (nnz,), ``lumped`` (n_dofs,) row sums."""

    kind: MassKind
    pattern: SparsityPattern
    data: np.ndarray
    lumped: np.ndarray

    @classmethod
    def build(
        cls,
        kinematics: P1Kinematics,
        density: np.ndarray,
        pattern: SparsityPattern,
        kind: MassKind = "consistent",
        stencil_id: int = 0,
    ) -> MassMatrix:
        d = kinematics.dim
        nv = d + 1
        element_mass = density * kinematics.weights  # (m,)
        ref = (np.ones((nv, nv)) + np.eye(nv)) / (nv * (nv + 1))  # sums to 1
        if kind == "lumped":
            ref = np.diag(ref.sum(axis=1))
        elif kind != "consistent":
            raise InputError(f"mass must be 'consistent' or 'lumped', not {short(kind)}")
        local = np.kron(ref, np.eye(d))  # ((a,i),(b,k)) = ref_ab delta_ik
        blocks = element_mass[:, None, None] * local[None]
        data = np.zeros(pattern.nnz)
        pattern.accumulate(data, stencil_id, blocks)
        lumped = np.bincount(
            kinematics.stencil.ravel(),
            weights=blocks.sum(axis=2).ravel(),
            minlength=pattern.n,
        )
        return cls(kind, pattern, data, lumped)

    def matrix(self) -> sp.csr_matrix:
        return self.pattern.matrix(self.data)

    def dot(self, v: np.ndarray) -> np.ndarray:
        return self.matrix() @ v


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
