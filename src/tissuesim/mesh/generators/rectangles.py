"""Structured meshes of rectangles: triangles (split patterns, order 1 or 2), Q1 quadrilaterals
and quadratic quadrilaterals. Point sets and facet sets are named for the sides.
Coordinates are in the caller's units."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.generators.common import _arguments, _element, _finish, _order, _side_sets
from tissuesim.mesh.generators.quadratic_tensor import QUADRATIC_TENSOR, _quadratic_tensor
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import short

__all__ = ["rectangle", "PATTERNS"]

PATTERNS = ("alternate", "right", "left", "cross")


def rectangle(
    lower: Sequence[float] = (0.0, 0.0),
    upper: Sequence[float] = (1.0, 1.0),
    divisions: Sequence[int] = (10, 10),
    pattern: str = "alternate",
    order: int = 1,
    element: str = "triangle",
) -> Mesh:
    """Triangle mesh of the rectangle [lower, upper] with divisions (nx, ny) quads.

    element: "triangle" (the default) or "quad": the (nx, ny) Q1 quadrilaterals themselves
    (counter-clockwise, VTK's node order; ``pattern`` does not apply, order must be 1);
    "quad8" / "quad9": quadratic quadrilaterals (serendipity / biquadratic, VTK's node order,
    nodes at the midpoints; order is 2 whether given or not; point sets hold the midside
    nodes on their sides, facet sets the edges by their corners).

    pattern: how each quad is split: "right" (diagonal bottom-left to top-right), "left" (the
    other diagonal), "alternate" (the two in a checkerboard, avoiding directional bias), "cross"
    (4 triangles around an added centre vertex). Points (n, 2); cells (m, 3) counter-clockwise.
    Sets: "left", "right", "bottom", "top" and the aliases "xmin", "xmax", "ymin", "ymax".
    order: 1 (3-node triangles) or 2 (6-node triangles, a node at every edge's midpoint; the
    point sets then hold the midside nodes on their sides too).
    """
    lo, hi, (nx, ny) = _arguments("rectangle", lower, upper, divisions, 2)
    element = _element("rectangle", element, ("triangle", "quad", "quad8", "quad9"))
    if element == "quad":
        return _quad_rectangle(lo, hi, nx, ny, order)
    if element in QUADRATIC_TENSOR:
        coords = [np.linspace(lo[k], hi[k], n + 1) for k, n in enumerate((nx, ny))]
        names = (("left", "right"), ("bottom", "top"))
        source = f"rectangle(lower={lo}, upper={hi}, divisions={(nx, ny)})"
        mesh = _quadratic_tensor(
            "rectangle", element, coords, names, 2 if order == 1 else order, source
        )
        psets, fsets = dict(mesh.point_sets), dict(mesh.facet_sets)
        for alias, name in (
            ("xmin", "left"),
            ("xmax", "right"),
            ("ymin", "bottom"),
            ("ymax", "top"),
        ):
            psets[alias], fsets[alias] = psets[name], fsets[name]
        return validate_mesh(
            mesh.points, mesh.cells, source=mesh.source, point_sets=psets, facet_sets=fsets
        )
    if pattern not in PATTERNS:
        raise MeshError(f"rectangle: pattern must be one of {PATTERNS}, got {short(pattern)}")
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
    return _finish(points, cells, source, psets, fsets, order)


def _quad_rectangle(lo, hi, nx: int, ny: int, order) -> Mesh:
    """Q1 quadrilaterals of the rectangle, sets as ``rectangle``'s."""
    if _order(order) != 1:
        raise MeshError("rectangle: element = 'quad' takes order 1 (Q1 quadrilaterals)")
    source = f"rectangle(lower={lo}, upper={hi}, divisions={(nx, ny)}, element='quad')"
    gy, gx = (g.ravel() for g in np.mgrid[0 : ny + 1, 0 : nx + 1])
    points = np.column_stack([lo[0] + (hi[0] - lo[0]) * gx / nx, lo[1] + (hi[1] - lo[1]) * gy / ny])
    qy, qx = (g.ravel() for g in np.mgrid[0:ny, 0:nx])
    v00 = qy * (nx + 1) + qx
    cells = np.stack([v00, v00 + 1, v00 + nx + 2, v00 + nx + 1], axis=1)
    psets, fsets = _side_sets(cells, (gx, gy), (("left", "right"), ("bottom", "top")), True)
    for alias, name in (("xmin", "left"), ("xmax", "right"), ("ymin", "bottom"), ("ymax", "top")):
        psets[alias], fsets[alias] = psets[name], fsets[name]
    return validate_mesh(points, cells, source=source, point_sets=psets, facet_sets=fsets)
