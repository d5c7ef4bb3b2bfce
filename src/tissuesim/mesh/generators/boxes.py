"""Structured meshes of boxes: Kuhn tetrahedra (mirrored or uniform, graded, order 1 or 2), Q1
hexahedra, linear wedges and quadratic hexahedra. Point sets and facet sets are named for the
sides. Coordinates are in the caller's units."""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.generators.common import _arguments, _element, _finish, _order, _side_sets
from tissuesim.mesh.generators.quadratic_tensor import QUADRATIC_TENSOR, _quadratic_tensor
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import short

__all__ = ["box"]


def _hex_cells(nx: int, ny: int, nz: int) -> np.ndarray:
    """(nx ny nz, 8) hexahedra of an (nx + 1, ny + 1, nz + 1) vertex grid (x fastest), in VTK's
    node order."""
    qz, qy, qx = (g.ravel() for g in np.mgrid[0:nz, 0:ny, 0:nx])
    v0 = (qz * (ny + 1) + qy) * (nx + 1) + qx
    bottom = np.stack([v0, v0 + 1, v0 + nx + 2, v0 + nx + 1], axis=1)
    return np.concatenate([bottom, bottom + (nx + 1) * (ny + 1)], axis=1)


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


def _kuhn_cells(nx: int, ny: int, nz: int, mirrored: bool = False) -> np.ndarray:
    """(6 nx ny nz, 4) tets of an (nx + 1, ny + 1, nz + 1) vertex grid (x fastest), positive.

    mirrored: reflect the Kuhn pattern in each octant about the grid centre, so that every
    hexahedron's main diagonal points away from the centre (faces still conform, since the two
    hexahedra on either side of a mirror plane see the same pattern on their shared face).
    """
    qz, qy, qx = (g.ravel() for g in np.mgrid[0:nz, 0:ny, 0:nx])
    base = (qz * (ny + 1) + qy) * (nx + 1) + qx
    corner = np.broadcast_to(_kuhn_template(), (len(base), 6, 4))
    if mirrored:
        # bit k of a corner id is +1 along axis k; flipping it mirrors the hexahedron's pattern
        below = (2 * np.column_stack([qx, qy, qz]) + 1) < np.array([nx, ny, nz])
        flip = below @ np.array([1, 2, 4])
        corner = corner ^ flip[:, None, None]
    offset = (
        ((corner >> 2) & 1) * (ny + 1) * (nx + 1) + ((corner >> 1) & 1) * (nx + 1) + (corner & 1)
    )
    cells = (base[:, None, None] + offset).reshape(-1, 4)
    if mirrored:
        # an odd number of reflections reverses orientation: swap the last two vertices
        odd = np.repeat(np.array([0, 1, 1, 0, 1, 0, 0, 1], dtype=bool)[flip], 6)
        cells[odd, 2:] = cells[odd, :1:-1]
    return cells


def box(
    lower: Sequence[float] = (0.0, 0.0, 0.0),
    upper: Sequence[float] = (1.0, 1.0, 1.0),
    divisions: Sequence[int] = (4, 4, 4),
    grading: Sequence[float] = (1.0, 1.0, 1.0),
    order: int = 1,
    pattern: str = "mirrored",
    element: str = "tet",
) -> Mesh:
    """Tetrahedral mesh of the box [lower, upper] with divisions (nx, ny, nz) hexahedra.

    element: "tet" (the default) or "hex": the (nx, ny, nz) Q1 hexahedra themselves (VTK's node
    order; ``pattern`` does not apply, order must be 1; facet sets hold quad faces (k, 4));
    "wedge": each hexahedron cut into 2 linear wedges (6-node prisms, Gmsh's node order, their
    axes along z) by a vertical plane through a diagonal of its bottom face, mirrored about the
    vertical mid-planes like the tetrahedra (``pattern`` "uniform": the same diagonal
    everywhere); order must be 1; facet sets hold (k, 4) rows, the sides' quadrilaterals and
    the zmin / zmax triangles as (a, b, c, c) (``mesh/cells/wedge.py``);
    "hex20" / "hex27": quadratic hexahedra (serendipity / triquadratic, VTK's node order, nodes
    at the midpoints of the graded grid's edges, faces and cells; order is 2 whether given or
    not; point sets hold every node on their side, facet sets the faces by their corners).

    Each hexahedron is split into 6 tetrahedra around a main diagonal (Kuhn/Freudenthal); faces
    conform. Points (n, 3); cells (6 nx ny nz, 4) positive.
    pattern: "mirrored" (the default) reflects the split about the box's mid-planes (every main
    diagonal points away from the centre), so the mesh is mirror-symmetric about them when the
    divisions are even (odd: all but the middle layer of hexahedra) and a centred press meets no
    mesh-made lateral force; "uniform" splits every hexahedron the same way (a one-way bias: a
    centred vertical press of a sphere reports a lateral force of several % of the normal one).
    Sets: "xmin", "xmax", "ymin", "ymax", "zmin", "zmax".
    grading (gx, gy, gz): per axis, 1 uniform; p > 1 places the grid planes at s^p of the way
    (cells shrink towards ``lower``); -p at 1 - (1 - s)^p (finer
    towards ``upper``), e.g. to resolve a contact on a face. Cells stay positive (each hexahedron
    maps to a box).
    order: 1 (4-node tetrahedra) or 2 (10-node tetrahedra, midside nodes in the side sets).
    """
    lo, hi, (nx, ny, nz) = _arguments("box", lower, upper, divisions, 3)
    exponents = _grading(grading)
    source = f"box(lower={lo}, upper={hi}, divisions={(nx, ny, nz)})"
    if exponents != (1.0, 1.0, 1.0):
        source = source[:-1] + f", grading={exponents})"
    gz, gy, gx = (g.ravel() for g in np.mgrid[0 : nz + 1, 0 : ny + 1, 0 : nx + 1])
    n = np.array([nx, ny, nz])
    s = np.column_stack([gx, gy, gz]) / n
    for axis, p in enumerate(exponents):
        if p > 1.0:
            s[:, axis] = s[:, axis] ** p
        elif p < -1.0:
            s[:, axis] = 1.0 - (1.0 - s[:, axis]) ** (-p)
    points = np.asarray(lo) + (np.asarray(hi) - np.asarray(lo)) * s
    if pattern not in ("mirrored", "uniform"):
        raise MeshError(f"box: pattern must be 'mirrored' or 'uniform', got {short(pattern)}")
    if pattern != "mirrored":
        source = source[:-1] + f", pattern={pattern!r})"
    names = (("xmin", "xmax"), ("ymin", "ymax"), ("zmin", "zmax"))
    element = _element("box", element, ("tet", "hex", "wedge", "hex20", "hex27"))
    if element in QUADRATIC_TENSOR:
        n = np.array([nx, ny, nz])
        coords = [points[np.arange(k + 1) * int(np.prod(n[:a] + 1)), a] for a, k in enumerate(n)]
        return _quadratic_tensor("box", element, coords, names, 2 if order == 1 else order, source)
    if element in ("hex", "wedge"):
        kind = "Q1 hexahedra" if element == "hex" else "linear wedges"
        if _order(order) != 1:
            raise MeshError(f"box: element = {element!r} takes order 1 ({kind})")
        if element == "hex":
            cells = _hex_cells(nx, ny, nz)
        else:  # each cut along a bottom diagonal (0-2; 1-3 where mirrored: x < centre xor y <)
            from tissuesim.mesh.cells.wedge import from_hexahedra

            qz, qy, qx = (g.ravel() for g in np.mgrid[0:nz, 0:ny, 0:nx])
            across = (((2 * qx + 1) < nx) ^ ((2 * qy + 1) < ny)) & (pattern == "mirrored")
            cells = from_hexahedra(_hex_cells(nx, ny, nz), across)
        psets, fsets = _side_sets(cells, (gx, gy, gz), names, tensor=True)
        source = source[:-1] + f", element={element!r})"
        return validate_mesh(points, cells, source=source, point_sets=psets, facet_sets=fsets)
    cells = _kuhn_cells(nx, ny, nz, mirrored=pattern == "mirrored")
    psets, fsets = _side_sets(cells, (gx, gy, gz), names)
    return _finish(points, cells, source, psets, fsets, order)


def _grading(grading) -> tuple[float, float, float]:
    from tissuesim.validate import vector

    g = vector(grading, "box: grading", 3)
    if np.any(np.abs(g) < 1.0):
        raise MeshError(
            f"box: grading must be 1 (uniform), p >= 1 (finer towards lower) or -p <= -1 (finer "
            f"towards upper) per axis, got {g.tolist()}"
        )
    return tuple(float(x) for x in g)
