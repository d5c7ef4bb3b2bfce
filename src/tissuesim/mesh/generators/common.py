"""What the mesh generators share: their arguments checked, the memory check before a mesh is
built, point and facet sets named for the sides, the element and order checks, and the
finish (midside nodes for order 2, then validation)."""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries.boundary import boundary_facets
from tissuesim.validate import check_memory, short


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
        from tissuesim.mesh.cells.tensor import boundary_faces

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


def _element(name: str, element, allowed: tuple[str, ...]) -> str:
    if not isinstance(element, str) or element not in allowed:
        listing = ", ".join(repr(a) for a in allowed[:-1]) + f" or {allowed[-1]!r}"
        raise MeshError(f"{name}: element must be {listing}, got {short(element)}")
    return element


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
        from tissuesim.mesh.cells.quadratic import EDGES, elevate, midside_lookup

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
