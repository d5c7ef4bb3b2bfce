"""Structured simplex meshes of rectangles (triangles) and boxes (tetrahedra).

Both add point sets and facet sets named for their sides. Coordinates are in the caller's units.
"""

from __future__ import annotations

import itertools
import numbers
from collections.abc import Sequence

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.boundary import boundary_facets
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.mesh import Mesh

__all__ = ["rectangle", "box", "PATTERNS"]

PATTERNS = ("alternate", "right", "left", "cross")


def _arguments(name, lower, upper, divisions, d):
    """Validated (lower, upper, divisions) as tuples of d floats, floats, ints."""
    values = {}
    for arg, v in (("lower", lower), ("upper", upper)):
        try:
            a = np.asarray(v, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise MeshError(f"{name}: {arg} must be {d} numbers, got {v!r}") from exc
        if a.shape != (d,) or not np.isfinite(a).all():
            raise MeshError(f"{name}: {arg} must be {d} finite numbers, got {v!r}")
        values[arg] = tuple(float(x) for x in a)
    lo, hi = values["lower"], values["upper"]
    for i in range(d):
        if not hi[i] > lo[i]:
            raise MeshError(
                f"{name}: upper[{i}] = {hi[i]} must be greater than lower[{i}] = {lo[i]}"
            )
    if (
        not isinstance(divisions, Sequence | np.ndarray)
        or len(divisions) != d
        or not all(isinstance(k, numbers.Integral) and not isinstance(k, bool) for k in divisions)
        or min(divisions) < 1
    ):
        raise MeshError(f"{name}: divisions must be {d} integers >= 1, got {divisions!r}")
    return lo, hi, tuple(int(k) for k in divisions)


def _side_sets(cells, grid_index, names):
    """Point sets from grid indices and the boundary facets whose vertices all lie on each side."""
    bf = boundary_facets(cells)
    point_sets, facet_sets = {}, {}
    for axis, (low_name, high_name) in enumerate(names):
        for name, k in ((low_name, 0), (high_name, -1)):
            ids = np.flatnonzero(grid_index[axis] == (0 if k == 0 else grid_index[axis].max()))
            point_sets[name] = ids
            facet_sets[name] = bf[np.isin(bf, ids).all(axis=1)]
    return point_sets, facet_sets


def rectangle(
    lower: Sequence[float] = (0.0, 0.0),
    upper: Sequence[float] = (1.0, 1.0),
    divisions: Sequence[int] = (10, 10),
    pattern: str = "alternate",
) -> Mesh:
    """Triangle mesh of the rectangle [lower, upper] with divisions (nx, ny) quads.

    pattern: how each quad is split: "right" (diagonal bottom-left to top-right), "left" (the
    other diagonal), "alternate" (the two in a checkerboard, avoiding directional bias), "cross"
    (4 triangles around an added centre vertex). Points (n, 2); cells (m, 3) counter-clockwise.
    Sets: "left", "right", "bottom", "top" and the aliases "xmin", "xmax", "ymin", "ymax".
    """
    lo, hi, (nx, ny) = _arguments("rectangle", lower, upper, divisions, 2)
    if pattern not in PATTERNS:
        raise MeshError(f"rectangle: pattern must be one of {PATTERNS}, got {pattern!r}")
    source = f"rectangle(lower={lo}, upper={hi}, divisions={(nx, ny)}, pattern={pattern!r})"
    gy, gx = np.mgrid[0 : ny + 1, 0 : nx + 1]
    gx, gy = gx.ravel(), gy.ravel()
    points = np.column_stack([lo[0] + (hi[0] - lo[0]) * gx / nx, lo[1] + (hi[1] - lo[1]) * gy / ny])
    qy, qx = np.mgrid[0:ny, 0:nx]
    qx, qy = qx.ravel(), qy.ravel()
    v00 = qy * (nx + 1) + qx
    v10, v01 = v00 + 1, v00 + nx + 1
    v11 = v01 + 1
    if pattern == "cross":
        vc = len(points) + np.arange(nx * ny)
        centres = np.column_stack([points[v00], points[v11]]).reshape(-1, 2, 2).mean(axis=1)
        points = np.concatenate([points, centres])
        tris = np.stack(
            [
                np.stack([v00, v10, vc], 1),
                np.stack([v10, v11, vc], 1),
                np.stack([v11, v01, vc], 1),
                np.stack([v01, v00, vc], 1),
            ],
            axis=1,
        )
        gx = np.concatenate([gx, qx + 0.5])
        gy = np.concatenate([gy, qy + 0.5])
    else:
        right = np.stack([np.stack([v00, v10, v11], 1), np.stack([v00, v11, v01], 1)], axis=1)
        left = np.stack([np.stack([v00, v10, v01], 1), np.stack([v10, v11, v01], 1)], axis=1)
        if pattern == "right":
            tris = right
        elif pattern == "left":
            tris = left
        else:
            tris = np.where(((qx + qy) % 2 == 0)[:, None, None], right, left)
    cells = tris.reshape(-1, 3)
    names = (("left", "right"), ("bottom", "top"))
    psets, fsets = _side_sets(cells, (gx, gy), names)
    for alias, name in (("xmin", "left"), ("xmax", "right"), ("ymin", "bottom"), ("ymax", "top")):
        psets[alias], fsets[alias] = psets[name], fsets[name]
    return validate_mesh(points, cells, source=source, point_sets=psets, facet_sets=fsets)


def _kuhn_template() -> np.ndarray:
    """(6, 4) corner ids (bit 0: +x, bit 1: +y, bit 2: +z) of 6 positive tets filling a cube."""
    tets = []
    for p in itertools.permutations(range(3)):
        a, b = 1 << p[0], 1 << p[1]
        tets.append([0, a, a | b, 7])
    tets = np.array(tets)
    corners = np.array([[(c >> k) & 1 for k in range(3)] for c in range(8)], dtype=float)
    x = corners[tets]
    negative = np.linalg.det(x[:, 1:] - x[:, :1]) < 0
    tets[negative, 2:] = tets[negative, :1:-1]
    return tets


def box(
    lower: Sequence[float] = (0.0, 0.0, 0.0),
    upper: Sequence[float] = (1.0, 1.0, 1.0),
    divisions: Sequence[int] = (4, 4, 4),
) -> Mesh:
    """Tetrahedral mesh of the box [lower, upper] with divisions (nx, ny, nz) hexahedra.

    Each hexahedron is split into 6 tetrahedra around its main diagonal (Kuhn/Freudenthal), the
    same way in every hexahedron, so faces conform. Points (n, 3); cells (6 nx ny nz, 4) positive.
    Sets: "xmin", "xmax", "ymin", "ymax", "zmin", "zmax".
    """
    lo, hi, (nx, ny, nz) = _arguments("box", lower, upper, divisions, 3)
    source = f"box(lower={lo}, upper={hi}, divisions={(nx, ny, nz)})"
    gz, gy, gx = (g.ravel() for g in np.mgrid[0 : nz + 1, 0 : ny + 1, 0 : nx + 1])
    n = np.array([nx, ny, nz])
    points = np.asarray(lo) + (np.asarray(hi) - np.asarray(lo)) * np.column_stack([gx, gy, gz]) / n
    qz, qy, qx = (g.ravel() for g in np.mgrid[0:nz, 0:ny, 0:nx])
    base = (qz * (ny + 1) + qy) * (nx + 1) + qx
    offset = np.array(
        [
            ((c >> 2) & 1) * (ny + 1) * (nx + 1) + ((c >> 1) & 1) * (nx + 1) + (c & 1)
            for c in range(8)
        ]
    )
    cells = (base[:, None, None] + offset[_kuhn_template()]).reshape(-1, 4)
    names = (("xmin", "xmax"), ("ymin", "ymax"), ("zmin", "zmax"))
    psets, fsets = _side_sets(cells, (gx, gy, gz), names)
    return validate_mesh(points, cells, source=source, point_sets=psets, facet_sets=fsets)
