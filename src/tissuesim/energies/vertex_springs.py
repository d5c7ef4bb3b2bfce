"""Zero-length springs from mesh vertices to moving targets: a grasper that holds a vertex set
through a stiffness instead of prescribing it (a soft grip)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError

__all__ = ["VertexSprings", "VertexSpringEnergy"]


@dataclass(frozen=True, eq=False)
class VertexSprings:
    """1/2 k |x_a - target_a(t)|^2 over ``vertices`` (k,); ``target(t)`` -> (k, 3) or (3,)
    positions in m; stiffness k in N/m per vertex."""

    vertices: np.ndarray
    stiffness: float
    target: Callable[[float], np.ndarray]

    def targets(self, t: float) -> np.ndarray:
        y = np.asarray(self.target(t), dtype=float)
        y = np.broadcast_to(y, (self.vertices.size, 3))
        if not np.all(np.isfinite(y)):
            raise InputError(f"grasper target is not finite at t = {t:g} s")
        return y

    def energy(self, t: float) -> VertexSpringEnergy:
        return VertexSpringEnergy(self, self.targets(t))

    def force(self, x: np.ndarray, t: float) -> np.ndarray:
        """Total force (3,) N the springs apply to the body at positions x (flat)."""
        X = x.reshape(-1, 3)[self.vertices]
        return self.stiffness * (self.targets(t) - X).sum(axis=0)


@dataclass(frozen=True, eq=False)
class VertexSpringEnergy:
    springs: VertexSprings
    targets: np.ndarray

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        s = self.springs
        dofs = (s.vertices[:, None] * 3 + np.arange(3)).ravel()
        r = x[dofs] - self.targets.ravel()
        acc.add_value("grasper", 0.5 * s.stiffness * float(r @ r))
        if acc.order >= 1:
            np.add.at(acc.gradient, dofs, s.stiffness * r)
        if acc.order >= 2:
            np.add.at(acc.hessian, acc.pattern.diagonal[dofs], s.stiffness)
