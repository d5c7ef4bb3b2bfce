"""Kinematic obstacles: rigid triangle surfaces moved by a prescribed motion (instruments, a
table, a probe). Their vertices are no unknowns: at time t they sit at

    x(t) = c + R(t) (X - c) + u(t),

X the rest vertices, c the rest centroid, u(t) a translation (m) and R(t) the rotation of the
rotation vector r(t) (rad, about the centroid); u and r are callables of t (None: at rest).
Surfaces come from ``frames.sampling`` (``box_surface``, ``ellipsoid_surface``,
``read_surface`` for STL/OBJ/... files) or from the generators here (``plane``, ``sphere``,
``capsule`` for an instrument's shaft or a grasper's jaw, ``cylinder``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from tissuesim.errors import InputError
from tissuesim.frames.sampling import Surface, ellipsoid_surface
from tissuesim.validate import real, short, vector

__all__ = [
    "DrivenMotion",
    "Obstacle",
    "ShapeSurface",
    "capsule",
    "cylinder",
    "plane",
    "sphere",
    "triangle",
]

Motion = Callable[[float], Sequence[float]]


@dataclass(frozen=True, eq=False)
class ShapeSurface(Surface):
    """A Surface that remembers the exact shape it approximates (``kind`` "sphere": params
    center, radius; "plane": point, normal; "capsule": start, end, radius), so a probe's
    indentation depth is measured from its exact shape rather than from facets."""

    kind: str = ""
    params: dict = field(default_factory=dict)


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
    return ShapeSurface(
        corners, np.array([[0, 1, 2], [0, 2, 3]]), "plane", "plane", {"point": p, "normal": n}
    )


def triangle(corners: Sequence[Sequence[float]]) -> Surface:
    """One triangle (three corners, m): a scalpel's flat blade, its front side the one its
    corners turn counter-clockwise about."""
    P = np.asarray(corners, dtype=float) if _numeric(corners) else None
    if P is None or P.shape != (3, 3) or not np.all(np.isfinite(P)):
        raise InputError(
            f"triangle: corners must be three points [[x, y, z], [x, y, z], [x, y, z]] (m), "
            f"not {short(corners)}"
        )
    area = 0.5 * np.linalg.norm(np.cross(P[1] - P[0], P[2] - P[0]))
    size = float(np.linalg.norm(np.ptp(P, axis=0)))
    if not area > 1e-12 * size**2:
        raise InputError("triangle: the corners lie on one line (the triangle has no area)")
    return Surface(P, np.array([[0, 1, 2]]))


def _numeric(value) -> bool:
    try:
        np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return True


def sphere(
    center: Sequence[float],
    radius: float,
    refinement: int = 3,
    cap_angle: float | None = None,
    cap_axis: Sequence[float] = (0.0, 0.0, -1.0),
) -> Surface:
    """An icosphere of ``radius`` (m): 20 * 4^refinement triangles, vertices on the sphere.

    ``cap_angle`` (degrees, 0 < angle <= 180): keep only the triangles within that angle of
    ``cap_axis`` seen from the centre, an open cap: a probe needs fine facets only where it
    touches (refinement 7 has facets of R / 110, and a 30-degree cap keeps 7 % of them)."""
    r = real(radius, "sphere: radius", low=0.0, low_open=True, unit="m")
    s = ellipsoid_surface(center, (r, r, r), refinement)
    c = vector(center, "sphere: center", 3, unit="m")
    points, triangles, source = s.points, s.triangles, s.source
    if cap_angle is not None:
        angle = real(cap_angle, "sphere: cap_angle", low=0.0, high=180.0, low_open=True)
        axis = vector(cap_axis, "sphere: cap_axis", 3)
        if not np.linalg.norm(axis) > 0:
            raise InputError("sphere: cap_axis must not be zero, e.g. [0, 0, -1]")
        axis = axis / np.linalg.norm(axis)
        centroids = points[triangles].mean(axis=1) - c
        cosines = centroids @ axis / np.linalg.norm(centroids, axis=1)
        keep = triangles[cosines >= np.cos(np.radians(angle))]
        if len(keep) == 0:
            raise InputError(
                f"sphere: cap_angle {angle} degrees keeps no triangle at refinement "
                f"{refinement}; give a larger angle or a higher refinement"
            )
        used, local = np.unique(keep, return_inverse=True)
        points, triangles = points[used], local.reshape(-1, 3)
        source += f" cap_angle {angle} cap_axis {axis.tolist()}"
    return ShapeSurface(points, triangles, source, "sphere", {"center": c, "radius": r})


def capsule(
    start: Sequence[float], end: Sequence[float], radius: float, segments: int = 24
) -> Surface:
    """A closed capsule (m): the points within ``radius`` of the segment start-end, a cylinder
    with hemispherical ends; ``segments`` facets around the axis (and segments / 4 rings per
    hemisphere). An instrument's shaft, a retractor's edge, a grasper's jaw."""
    a, b, r, n = _axis("capsule", start, end, radius, segments)
    rings = max(2, n // 4)
    phi = np.linspace(0.0, 0.5 * np.pi, rings + 1)  # from the pole to the equator
    length = float(np.linalg.norm(b - a))
    z = np.concatenate([-r * np.cos(phi), length + r * np.cos(phi[::-1])])
    rho = np.concatenate([r * np.sin(phi), r * np.sin(phi[::-1])])
    surface = _revolve(a, b, z, rho, n, f"capsule {a.tolist()}-{b.tolist()} radius {r:g}")
    params = {"start": a, "end": b, "radius": r}
    return ShapeSurface(surface.points, surface.triangles, surface.source, "capsule", params)


def cylinder(
    start: Sequence[float], end: Sequence[float], radius: float, segments: int = 24
) -> Surface:
    """A closed cylinder (m) of ``radius`` about the segment start-end, with flat ends."""
    a, b, r, n = _axis("cylinder", start, end, radius, segments)
    length = float(np.linalg.norm(b - a))
    z, rho = np.array([0.0, 0.0, length, length]), np.array([0.0, r, r, 0.0])
    return _revolve(a, b, z, rho, n, f"cylinder {a.tolist()}-{b.tolist()} radius {r:g}")


def _axis(what: str, start, end, radius, segments):
    from tissuesim.validate import integer

    a = vector(start, f"{what}: start", 3, unit="m")
    b = vector(end, f"{what}: end", 3, unit="m")
    if not np.linalg.norm(b - a) > 0:
        raise InputError(f"{what}: start and end must differ (they give its axis)")
    r = real(radius, f"{what}: radius", low=0.0, low_open=True, unit="m")
    n = integer(segments, f"{what}: segments", low=6, high=4096)
    return a, b, r, n


def _revolve(a, b, z, rho, segments: int, source: str) -> Surface:
    """The closed surface of revolution about the axis a -> b of the profile (z along the axis
    from a, rho from it; rho = 0 only at the two ends, the poles), outward oriented."""
    k = (b - a) / np.linalg.norm(b - a)
    e1 = np.cross(k, [1.0, 0.0, 0.0] if abs(k[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(k, e1)
    theta = 2 * np.pi * np.arange(segments) / segments
    around = np.cos(theta)[:, None] * e1 + np.sin(theta)[:, None] * e2  # (n, 3)
    points, rows = [], []  # rows: the vertex ids of each profile point (1 at a pole, else n)
    for zi, ri in zip(z, rho, strict=True):
        ring = a + zi * k + (ri * around if ri > 0 else np.zeros((1, 3)))
        start = sum(len(p) for p in points)
        rows.append(start + np.arange(len(ring)))
        points.append(ring)
    j = np.arange(segments)
    triangles = []
    for lower, upper in zip(rows[:-1], rows[1:], strict=True):
        if len(lower) == 1:  # a fan from the first pole
            triangles.append(
                np.column_stack([np.full(segments, lower[0]), upper[(j + 1) % segments], upper[j]])
            )
        elif len(upper) == 1:  # a fan to the last pole
            triangles.append(
                np.column_stack([lower[j], lower[(j + 1) % segments], np.full(segments, upper[0])])
            )
        else:
            nxt = (j + 1) % segments
            triangles.append(np.column_stack([lower[j], lower[nxt], upper[nxt]]))
            triangles.append(np.column_stack([lower[j], upper[nxt], upper[j]]))
    P, T = np.vstack(points), np.vstack(triangles)
    volume = np.einsum("ij,ij->i", P[T[:, 0]], np.cross(P[T[:, 1]], P[T[:, 2]])).sum() / 6
    if volume < 0:
        T = T[:, ::-1]
    return Surface(P, np.ascontiguousarray(T), source)


class DrivenMotion:
    """A motion set live by the caller (a device, the mouse, a script) rather than a function
    of t: ``set(target, t0, t1)`` asks for ``target`` (m, or a rotation vector in rad) at the
    end of the step t0 -> t1, moving on a straight line from where the motion was at t0; it
    stays at the target until set again. Called with t like any motion."""

    def __init__(self, value: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        self.start = np.array(value, dtype=float)
        self.target = self.start.copy()
        self.start_time = self.end_time = 0.0

    def set(self, target: Sequence[float], t0: float, t1: float) -> None:
        self.start = self(t0)
        self.target = vector(target, "driven motion target", 3)
        self.start_time, self.end_time = float(t0), float(t1)

    def __call__(self, t: float) -> np.ndarray:
        if t >= self.end_time or self.end_time <= self.start_time:
            return self.target.copy()
        if t <= self.start_time:
            return self.start.copy()
        s = (t - self.start_time) / (self.end_time - self.start_time)
        return self.start + s * (self.target - self.start)


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
    friction: float | None = None  # Coulomb mu against every body (None: the scene's)

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
        return self._moved(X, t)

    def sphere_center(self, t: float) -> np.ndarray:
        """A sphere obstacle's centre at time t (its exact shape's, not its facets' centroid:
        an open cap's differ)."""
        return self._moved(np.asarray(self.surface.params["center"], float)[None, :], t)[0]

    def _moved(self, points: np.ndarray, t: float) -> np.ndarray:
        c = self.surface.points.mean(axis=0)
        u = np.zeros(3) if self.translation is None else self._vector(self.translation, t, "m")
        if self.rotation is None:
            return points + u
        R = _rotation(self._vector(self.rotation, t, "rad"))
        return c + (points - c) @ R.T + u

    def _rotate(self, v: np.ndarray, t: float) -> np.ndarray:
        return _rotation(self._vector(self.rotation, t, "rad")) @ v

    def _vector(self, motion: Motion, t: float, unit: str) -> np.ndarray:
        return vector(
            np.asarray(motion(t), dtype=float), f"obstacle {self.name!r} motion", 3, unit=unit
        )
