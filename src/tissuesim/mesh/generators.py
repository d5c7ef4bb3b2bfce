"""Structured simplex meshes of rectangles (triangles), boxes and ellipsoids (tetrahedra).

Rectangles and boxes add point sets and facet sets named for their sides, ellipsoids one named
"surface". Coordinates are in the caller's units.
"""

from __future__ import annotations

import itertools
import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.boundary import boundary_facets
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import check_memory, short

__all__ = ["rectangle", "box", "ellipsoid", "PATTERNS"]

PATTERNS = ("alternate", "right", "left", "cross")


def _arguments(name, lower, upper, divisions, d):
    """Validated (lower, upper, divisions) as tuples of d floats, floats, ints."""
    values = {}
    for arg, v in (("lower", lower), ("upper", upper)):
        try:
            a = np.asarray(v, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise MeshError(f"{name}: {arg} must be {d} numbers, got {short(v)}") from exc
        if a.shape != (d,) or not np.isfinite(a).all():
            raise MeshError(f"{name}: {arg} must be {d} finite numbers, got {short(v)}")
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
        raise MeshError(f"{name}: divisions must be {d} integers >= 1, got {short(divisions)}")
    divisions = tuple(int(k) for k in divisions)
    cells = (2 if d == 2 else 6) * math.prod(divisions) * (2 if name == "rectangle" else 1)
    check_mesh_size(f"{name} with divisions {list(divisions)}", cells, d)
    return lo, hi, divisions


#: bytes a generated mesh takes per cell while it is built and checked (measured: 0.49 KB per
#: triangle, 0.72 KB per tetrahedron); a model on it needs more (model.py)
MESH_BYTES_PER_CELL = {2: 400, 3: 600}


def check_mesh_size(what: str, cells: int, d: int) -> None:
    """Refuse a mesh whose cells would not fit in memory, before allocating any of it."""
    check_memory(
        cells * MESH_BYTES_PER_CELL[d], f"{what} ({cells:.3g} cells)", "Use fewer divisions."
    )


def _side_sets(cells, grid_index, names, tensor: bool = False):
    """Point sets from grid indices and the boundary facets whose vertices all lie on each side
    (``tensor``: the cells are Q1 quadrilaterals / hexahedra, facets edges / quad faces)."""
    if tensor:
        from tissuesim.mesh.tensor import boundary_faces

        bf = boundary_faces(cells, len(names))
    else:
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


def _element(name: str, element, allowed: tuple[str, ...]) -> str:
    if not isinstance(element, str) or element not in allowed:
        listing = ", ".join(repr(a) for a in allowed[:-1]) + f" or {allowed[-1]!r}"
        raise MeshError(f"{name}: element must be {listing}, got {short(element)}")
    return element


#: generator element names of the quadratic quadrilaterals / hexahedra -> meshio's cell type
QUADRATIC_TENSOR = {
    "quad8": "quad8",
    "quad9": "quad9",
    "hex20": "hexahedron20",
    "hex27": "hexahedron27",
}


def _quadratic_tensor(name, element, coords, names, order, source) -> Mesh:
    """Quadratic quadrilaterals / hexahedra on the grid of 1D vertex coordinates ``coords``
    (one array per axis): midside (and face, centre) nodes at the midpoints, nodes no cell
    uses (a hexahedron20's face centres) left out; point sets hold every node on their side,
    facet sets the boundary facets by their corners."""
    from tissuesim.mesh import tensor_quadratic as tq

    if _order(order) == 1:
        raise MeshError(f"{name}: element = {element!r} is quadratic; give order 2 or leave it out")
    kind = QUADRATIC_TENSOR[element]
    d = len(coords)
    fine = [np.insert(c, np.arange(1, len(c)), 0.5 * (c[1:] + c[:-1])) for c in coords]
    shape = [len(f) for f in fine]  # 2 n + 1 per axis
    grid = np.meshgrid(*[np.arange(k) for k in shape], indexing="ij")
    index = [g.ravel(order="F") for g in grid]  # x fastest
    points = np.column_stack([f[i] for f, i in zip(fine, index, strict=True)])
    ncell = [(k - 1) // 2 for k in shape]
    base = np.meshgrid(*[2 * np.arange(k) for k in ncell], indexing="ij")
    base = np.stack([b.ravel(order="F") for b in base], axis=1)  # (m, d) fine index of corner 0
    local = (tq.NODES[kind] + 1).astype(np.int64)  # (nv, d) offsets 0, 1, 2
    node = base[:, None, :] + local[None]  # (m, nv, d)
    strides = np.cumprod([1, *shape[:-1]])
    cells = node @ strides
    used = np.unique(cells)
    renumber = np.full(points.shape[0], -1, dtype=np.int64)
    renumber[used] = np.arange(used.size)
    points, cells = points[used], renumber[cells]
    index = [i[used] for i in index]
    from tissuesim.mesh.tensor import boundary_faces

    bf = boundary_faces(cells[:, : 2**d], d)
    psets, fsets = {}, {}
    for axis, (low, high) in enumerate(names):
        for set_name, value in ((low, 0), (high, shape[axis] - 1)):
            ids = np.flatnonzero(index[axis] == value)
            psets[set_name] = ids
            fsets[set_name] = bf[np.isin(bf, ids).all(axis=1)]
    check_mesh_size(name, cells.shape[0], d)
    source = source[:-1] + f", element={element!r})"
    return validate_mesh(points, cells, source=source, point_sets=psets, facet_sets=fsets)


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


def _hex_cells(nx: int, ny: int, nz: int) -> np.ndarray:
    """(nx ny nz, 8) hexahedra of an (nx + 1, ny + 1, nz + 1) vertex grid (x fastest), in VTK's
    node order."""
    qz, qy, qx = (g.ravel() for g in np.mgrid[0:nz, 0:ny, 0:nx])
    v0 = (qz * (ny + 1) + qy) * (nx + 1) + qx
    bottom = np.stack([v0, v0 + 1, v0 + nx + 2, v0 + nx + 1], axis=1)
    return np.concatenate([bottom, bottom + (nx + 1) * (ny + 1)], axis=1)


def _order(order) -> int:
    if isinstance(order, bool) or order not in (1, 2):
        raise MeshError(
            f"order must be 1 (linear elements) or 2 (quadratic elements), got {short(order)}"
        )
    return int(order)


def _finish(points, cells, source, psets, fsets, order, projection=None) -> Mesh:
    """Validate the mesh; for order 2 first add the midside nodes (``projection`` moves those
    on the boundary onto a curved surface) and put those on each facet set's facets into the
    point set of the same name. The mesh keeps ``projection`` (its ``surface_projection``) (a later
    elevation to order 2, e.g. a scene's ``order = 2``, curves it the same way)."""
    order = _order(order)
    if order == 2:
        from tissuesim.mesh.quadratic import EDGES, elevate, midside_lookup

        points, cells = elevate(points, cells, projection)
        lookup = midside_lookup(cells, points.shape[1])
        psets = dict(psets)
        for name, facets in fsets.items():
            mids = lookup(facets[:, EDGES[points.shape[1] - 1]]).ravel()
            psets[name] = np.union1d(psets.get(name, np.zeros(0, np.int64)), mids)
        source = source[:-1] + ", order=2)"
    return validate_mesh(
        points,
        cells,
        source=source,
        point_sets=psets,
        facet_sets=fsets,
        surface_projection=projection,
    )


@dataclass(frozen=True)
class OntoEllipsoid:
    """Projection of points onto the ellipsoid sum(((x - center) / radii)^2) = 1 along the
    rays from its centre (a class, not a closure, so meshes pickle)."""

    center: np.ndarray
    radii: np.ndarray

    def __call__(self, p: np.ndarray) -> np.ndarray:
        u = (p - self.center) / self.radii
        return self.center + self.radii * u / np.linalg.norm(u, axis=1, keepdims=True)


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
    the zmin / zmax triangles as (a, b, c, c) (``mesh/wedge.py``);
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
            from tissuesim.mesh.wedge import from_hexahedra

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
