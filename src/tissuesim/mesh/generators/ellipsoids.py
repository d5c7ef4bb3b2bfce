"""Tetrahedral meshes of solid ellipsoids: a box's mirrored Kuhn tetrahedra mapped onto the ball,
with the point set and facet set "surface"; order 2 curves the boundary onto the ellipsoid."""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.generators.boxes import _kuhn_cells
from tissuesim.mesh.generators.common import _finish, check_mesh_size
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries.boundary import boundary_facets
from tissuesim.validate import short

__all__ = ["ellipsoid", "OntoEllipsoid"]


@dataclass(frozen=True)
class OntoEllipsoid:
    """Projection of points onto the ellipsoid sum(((x - center) / radii)^2) = 1 along the
    rays from its centre (a class, not a closure, so meshes pickle)."""

    center: np.ndarray
    radii: np.ndarray

    def __call__(self, p: np.ndarray) -> np.ndarray:
        u = (p - self.center) / self.radii
        return self.center + self.radii * u / np.linalg.norm(u, axis=1, keepdims=True)


def _cube_to_ball(p: np.ndarray) -> np.ndarray:
    """Map [-1, 1]^3 onto the unit ball: x' = x sqrt(1 - y^2/2 - z^2/2 + y^2 z^2 / 3), cyclic.

    Smooth and one-to-one; the cube's faces go to the sphere, its centre stays put.
    """
    x2 = p * p
    y2, z2 = np.roll(x2, -1, axis=1), np.roll(x2, -2, axis=1)
    return p * np.sqrt(1.0 - 0.5 * y2 - 0.5 * z2 + y2 * z2 / 3.0)


def ellipsoid(
    center: Sequence[float] = (0.0, 0.0, 0.0),
    radii: Sequence[float] = (1.0, 1.0, 1.0),
    divisions: int = 8,
    order: int = 1,
) -> Mesh:
    """Tetrahedral mesh of the solid ellipsoid sum(((x - center) / radii)^2) <= 1.

    A ``box((-1, -1, -1), (1, 1, 1), (divisions,) * 3)`` grid of hexahedra, each split into 6
    Kuhn tetrahedra mirrored per octant so every main diagonal points away from the centre (this
    keeps the tetrahedra at the cube's corners, which the map flattens most, about 7x fatter
    than with the plain box pattern), mapped onto the unit ball by the smooth cube-to-ball map,
    then scaled by ``radii`` and shifted to ``center``. Boundary vertices lie on the ellipsoid
    (to rounding), so the polyhedron is inscribed: its volume is below 4/3 pi a b c (by about 1.6%
    at divisions 8, 0.7% at 12). Points ((divisions + 1)^3, 3); cells (6 divisions^3, 4),
    positive. Sets: point set and facet set "surface" (the boundary vertices and triangles).
    order 2: 10-node tetrahedra whose boundary midside nodes are moved onto the ellipsoid, so
    the surface is curved (its volume error falls to 0.003 % at divisions 8, measured).
    """
    func = "ellipsoid"
    values = {}
    for arg, v in (("center", center), ("radii", radii)):
        try:
            a = np.asarray(v, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise MeshError(f"{func}: {arg} must be 3 numbers (x, y, z), got {short(v)}") from exc
        if a.shape != (3,) or not np.isfinite(a).all():
            raise MeshError(f"{func}: {arg} must be 3 finite numbers (x, y, z), got {short(v)}")
        values[arg] = a
    c, r = values["center"], values["radii"]
    if not (r > 0).all():
        raise MeshError(
            f"{func}: radii must all be > 0, got {r.tolist()}; give the semi-axes along x, y, z"
        )
    if isinstance(divisions, bool) or not isinstance(divisions, numbers.Integral) or divisions < 1:
        raise MeshError(
            f"{func}: divisions must be an integer >= 1 (hexahedra along each axis of the "
            f"mapped cube), got {short(divisions)}"
        )
    n = int(divisions)
    check_mesh_size(f"ellipsoid with divisions {n}", 6 * n**3, 3)
    source = (
        f"ellipsoid(center={tuple(float(x) for x in c)}, radii={tuple(float(x) for x in r)}, "
        f"divisions={n})"
    )
    gz, gy, gx = (g.ravel() for g in np.mgrid[0 : n + 1, 0 : n + 1, 0 : n + 1])
    grid = np.column_stack([gx, gy, gz])
    points = c + r * _cube_to_ball(2.0 * grid / n - 1.0)
    cells = _kuhn_cells(n, n, n, mirrored=True)
    surface = boundary_facets(cells)
    psets = {"surface": np.unique(surface)}
    fsets = {"surface": surface}

    return _finish(points, cells, source, psets, fsets, order, OntoEllipsoid(c, r))
