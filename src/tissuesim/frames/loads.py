"""Dead loads on frame-based bodies, as forces over the frame configurations z.

A force f_p on a point carried by the frames does virtual work f_p . dp = f_p . E_p dz, so its
generalised force is E_p^T f_p (the transpose of eq. 3's point map); gravity is this for the
integration points' masses.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["FrameGravity", "PointForces"]


@dataclass(frozen=True, eq=False)
class FrameGravity:
    """Gravity (3,) m/s^2 on the integration points' masses."""

    acceleration: np.ndarray

    def z_forces(self, model, t: float) -> np.ndarray:
        f = model.masses[:, None] * self.acceleration[None, :]
        return model.point_map.matrix.T @ f  # (4 n, 3)


@dataclass(frozen=True, eq=False)
class PointForces:
    """Forces (N) on embedded points: a (k, 3) / (3,) array or a callable t -> (k, 3)."""

    embedding: object  # model.Embedding
    force: np.ndarray | Callable[[float], np.ndarray]

    def z_forces(self, model, t: float) -> np.ndarray:
        f = self.force(t) if callable(self.force) else self.force
        f = np.broadcast_to(np.asarray(f, dtype=float), self.embedding.points.shape)
        return self.embedding.matrix.T @ f
