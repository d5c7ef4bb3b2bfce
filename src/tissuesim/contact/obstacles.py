"""Kinematic obstacles: rigid triangle surfaces moved by a prescribed motion (instruments, a
table, a probe). Their vertices are no unknowns: at time t they sit at

    x(t) = c + R(t) (X - c) + u(t),

X the rest vertices, c the rest centroid, u(t) a translation (m) and R(t) the rotation of the
rotation vector r(t) (rad, about the centroid); u and r are callables of t (None: at rest).
Surfaces come from ``frames.sampling`` (``box_surface``, ``ellipsoid_surface``,
``read_surface`` for STL/OBJ/... files) or from the generators here (``plane``, ``sphere``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError
from tissuesim.frames.sampling import Surface, ellipsoid_surface
from tissuesim.validate import real, vector

__all__ = ["Obstacle", "plane", "sphere"]

Motion = Callable[[float], Sequence[float]]


def plane(point: Sequence[float], normal: Sequence[float], size: float) -> Surface:
    """A square of side ``size`` (m) through ``point``, facing ``normal`` (two triangles whose
    front side, the side contact is expected on, is +normal)."""
    p = vector(point, "plane: point", 3, unit="m")
    n = vector(normal, "plane: normal", 3)
    if not np.linalg.norm(n) > 0:
        raise InputError("plane: normal must not be zero")
    n = n / np.linalg.norm(n)
    half = 0.5 * real(size, "plane: size", low=0.0, low_open=True, unit="m")
    a = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(n, a)
    corners = p + half * np.array([-a - b, a - b, a + b, -a + b])
    return Surface(corners, np.array([[0, 1, 2], [0, 2, 3]]), source="plane")


def sphere(center: Sequence[float], radius: float, refinement: int = 3) -> Surface:
    """An icosphere of ``radius`` (m): 20 * 4^refinement triangles, vertices on the sphere."""
    r = real(radius, "sphere: radius", low=0.0, low_open=True, unit="m")
    return ellipsoid_surface(center, (r, r, r), refinement)


def _rotation(r: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(r))
    if angle == 0.0:
        return np.eye(3)
    k = r / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


@dataclass(frozen=True, eq=False)
class Obstacle:
    """A named rigid surface and its motion; see the module docstring."""

    name: str
    surface: Surface
    translation: Motion | None = None
    rotation: Motion | None = None

    @property
    def rest(self) -> np.ndarray:
        return self.surface.points

    @property
    def triangles(self) -> np.ndarray:
        return self.surface.triangles

    def positions(self, t: float) -> np.ndarray:
        """Vertices (k, 3) at time t."""
        X = self.surface.points
        if self.translation is None and self.rotation is None:
            return X
        c = X.mean(axis=0)
        u = np.zeros(3) if self.translation is None else self._vector(self.translation, t, "m")
        if self.rotation is None:
            return X + u
        R = _rotation(self._vector(self.rotation, t, "rad"))
        return c + (X - c) @ R.T + u

    def _vector(self, motion: Motion, t: float, unit: str) -> np.ndarray:
        return vector(
            np.asarray(motion(t), dtype=float), f"obstacle {self.name!r} motion", 3, unit=unit
        )
