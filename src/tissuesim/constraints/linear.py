"""Linear constraints between displacement components of one FEM body, held by a stiff
penalty: sum_i c_i(t) u_{v_i, a_i} = offset(t) for each constraint (FEBio's
``FELinearConstraint``: a parent DOF equal to a sum of child DOFs times their values plus an
offset, which FEBio eliminates exactly; here the energy k/2 g^2 of the residual g). The
default k (``FemBody.add_linear_constraint``: 1e5 times the shear modulus times the median
boundary edge) leaves g about 1e-5 of the displacements: FEBio's mi04, a hex stretched to
twice its length through three constrained nodes, ends 1.1e-6 from FEBio's norm. A stiffer
k is not more exact: Newton's relative tolerance is taken of the step's starting gradient,
which the penalty dominates when a prescribed node pulls a constrained one, and the rest of
the body stops short (1e8: 1 % off in mi04).

The energy of constraint r is k/2 g_r^2, g_r = sum_i c_i (x_{d_i} - X_{d_i}) - offset; its
gradient k g_r c over its DOFs d_i and its Hessian k c c^T (the pairs of its vertices join
the body's sparsity pattern, as springs' do: ``FemBody.add_linear_constraint``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError

__all__ = ["LinearConstraint", "LinearConstraintEnergy"]

Coefficient = float | Callable[[float], float]


@dataclass(frozen=True, eq=False)
class LinearConstraint:
    """sum_i c_i(t) u[vertices[i], components[i]] = offset(t), by the penalty ``stiffness``
    (N/m); ``dofs`` the flat DOFs, ``rest`` their rest coordinates."""

    vertices: np.ndarray
    components: np.ndarray
    coefficients: tuple
    offset: Coefficient
    stiffness: float
    rest: np.ndarray
    dim: int = 3
    name: str = "linear_constraint"

    @property
    def dofs(self) -> np.ndarray:
        return self.vertices * self.dim + self.components

    def at(self, t: float) -> tuple[np.ndarray, float]:
        """(the coefficients (m,), the offset) at time t."""
        c = np.array([float(v(t)) if callable(v) else float(v) for v in self.coefficients])
        off = float(self.offset(t)) if callable(self.offset) else float(self.offset)
        if not (np.all(np.isfinite(c)) and np.isfinite(off)):
            raise InputError(f"{self.name}: a coefficient or the offset is not finite at t = {t:g}")
        return c, off

    def residual(self, x: np.ndarray, t: float) -> float:
        c, off = self.at(t)
        return float(c @ (x[self.dofs] - self.rest) - off)

    def energy(self, t: float) -> LinearConstraintEnergy:
        c, off = self.at(t)
        return LinearConstraintEnergy(self, c, off)


@dataclass(frozen=True, eq=False)
class LinearConstraintEnergy:
    constraint: LinearConstraint
    coefficients: np.ndarray
    offset: float

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        s = self.constraint
        dofs, c, k = s.dofs, self.coefficients, s.stiffness
        g = float(c @ (x[dofs] - s.rest) - self.offset)
        acc.add_value(s.name, 0.5 * k * g * g)
        if acc.order >= 1:
            np.add.at(acc.gradient, dofs, k * g * c)
        if acc.order >= 2:
            rows = np.repeat(dofs, dofs.size)
            cols = np.tile(dofs, dofs.size)
            positions = acc.pattern.positions(rows, cols)
            np.add.at(acc.hessian, positions, k * np.outer(c, c).ravel())
