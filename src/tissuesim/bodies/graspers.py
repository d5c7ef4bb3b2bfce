"""Graspers of a FEM body and the checked vertex selections every prescribed set takes."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tissuesim.energies.vertex_springs import VertexSprings
from tissuesim.errors import InputError
from tissuesim.validate import indices, short

__all__ = ["Grasper", "vertex_indices"]

Motion = Callable[[float], np.ndarray]


def vertex_indices(vertices, n_points: int, what: str, unique: bool = True) -> np.ndarray:
    """Checked vertex indices (sorted and unique, or as given); a boolean mask or floats are
    refused (they would silently select other vertices), and so is an empty selection."""
    v = indices(vertices, what, n_points)
    v = np.unique(v) if unique else v
    if v.size == 0:
        raise InputError(f"{what}: the vertex selection is empty")
    return v


def _vector(value, dim: int, what: str) -> np.ndarray:
    v = np.asarray(value, dtype=float)
    if v.shape != (dim,) or not np.all(np.isfinite(v)):
        raise InputError(f"{what} must be {dim} finite numbers (m), got {short(value)}")
    return v


@dataclass(frozen=True, eq=False)
class Grasper:
    """Moves ``vertices`` of a body rigidly by ``displacement(t)`` (d,) m: prescribed
    (stiffness None) or through zero-length springs of ``stiffness`` N/m per vertex."""

    name: str
    body: str
    vertices: np.ndarray
    displacement: Motion
    stiffness: float | None = None
    release: float | None = None  # s: the time it lets go (None: never)

    def springs(self, rest: np.ndarray) -> VertexSprings:
        X = rest[self.vertices]
        dim = rest.shape[1]
        return VertexSprings(
            self.vertices,
            float(self.stiffness),
            lambda t: X + _vector(self.displacement(t), dim, f"grasper {self.name!r} motion"),
        )
