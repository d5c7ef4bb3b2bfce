"""Read and write mesh files through meshio, and summarise a Mesh.

read_mesh takes tetrahedra (3D) or triangles (2D), linear or quadratic (meshio's tetra10 and
triangle6, e.g. Gmsh second order; meshio converts Gmsh's node order to VTK's, which tissuesim
uses), or hexahedra (3D, tagged quad faces become facet sets) and quadrilaterals (2D), Q1 or
quadratic (meshio's hexahedron20 / hexahedron27 / quad8 / quad9, VTK's node order), or linear
wedges (meshio's ``wedge``, Gmsh's prism order: meshio converts VTK's mirrored one; tagged
triangles and quads both become facets, ``mesh/cells/wedge.py``), and turns tags into named sets:
meshio cell sets and gmsh physical groups ("gmsh:physical" with names from $PhysicalNames). Tagged
facets (lines in 2D, triangles in 3D) become facet sets, tagged volume cells cell sets, tagged
lower-dimensional cells (vertices, edges in 3D) point sets. Everything is then checked by
validate_mesh.
"""

from __future__ import annotations

import contextlib
import io
import os
import threading
import warnings
from collections import defaultdict

import numpy as np

from tissuesim.errors import InputError, MeshError
from tissuesim.mesh.checks import edge_lengths, signed_volumes, validate_mesh
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries.boundary import all_facets, facet_measures, facet_table, match_facets
from tissuesim.mesh.queries.select import _boundary
from tissuesim.validate import short

__all__ = ["read_mesh", "write_mesh", "describe_mesh"]

_VOLUME = {3: "tetra", 2: "triangle"}
_VOLUME2 = {3: "tetra10", 2: "triangle6"}  # quadratic
_FACET = {3: "triangle", 2: "line"}
_FACETS = {3: ("triangle", "triangle6"), 2: ("line", "line3")}
_CELL_DIM = {
    "vertex": 0,
    "line": 1,
    "line3": 1,
    "triangle": 2,
    "triangle6": 2,
    "quad": 2,
    "tetra": 3,
    "tetra10": 3,
    "hexahedron": 3,
    "quad8": 2,
    "quad9": 2,
    "hexahedron20": 3,
    "hexahedron27": 3,
    "wedge": 3,
}
#: quadrilateral / hexahedral volume cells, each dimension's in order of preference
_TENSOR = {
    3: ("hexahedron", "hexahedron20", "hexahedron27", "wedge"),
    2: ("quad", "quad8", "quad9"),
}
#: their facet types that tag their boundary (the first is written; a wedge's facets are
#: written as triangles and quads) and the facets' corners
_TENSOR_FACET = {
    "hexahedron": (("quad",), 4),
    "hexahedron20": (("quad", "quad8"), 4),
    "hexahedron27": (("quad", "quad9"), 4),
    "quad": (("line",), 2),
    "quad8": (("line", "line3"), 2),
    "quad9": (("line", "line3"), 2),
    "wedge": (("quad", "triangle"), 4),
}


def _block_dim(block) -> int:
    return int(getattr(block, "dim", _CELL_DIM.get(block.type, -1)))


def _load(path: str):
    """meshio.read, turning every failure (meshio may even call sys.exit) into MeshError.

    What meshio prints is caught for the message in the main thread only: redirecting
    sys.stdout / sys.stderr swaps them for the whole process, so a read in a worker thread (a
    study on a thread pool, a Dask worker) would swallow the other threads' output, and two
    overlapping reads could leave a stale buffer as sys.stderr for good."""
    import meshio

    captured = io.StringIO()
    main = threading.current_thread() is threading.main_thread()
    out = contextlib.redirect_stdout(captured) if main else contextlib.nullcontext()
    err = contextlib.redirect_stderr(captured) if main else contextlib.nullcontext()
    try:
        with out, err:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return meshio.read(path)
    except (Exception, SystemExit) as exc:
        said = " ".join(captured.getvalue().split())
        if not isinstance(exc, SystemExit):
            said = f"{said}; " * bool(said) + " ".join(f"{type(exc).__name__}: {exc}".split())
        raise MeshError(
            f"{path}: meshio could not read this mesh file ({said or 'no reason given'}); check "
            f"that the file is complete and that its extension matches its format"
        ) from exc


def _choose_cells(path: str, m) -> tuple[np.ndarray, int, str]:
    """(points (n, d), d, volume cell type) for a meshio mesh, or MeshError."""
    found = defaultdict(int)
    for b in m.cells:
        found[b.type] += len(b.data)
    listing = ", ".join(f"{k} ({v})" for k, v in found.items()) or "none"
    points = np.asarray(m.points, dtype=np.float64)
    if found.get("tetra") or found.get("tetra10"):
        d = 3
    elif any(found.get(t) for t in _TENSOR[3]):
        d = 3
    elif found.get("triangle") or found.get("triangle6"):
        d = 2
    elif any(found.get(t) for t in _TENSOR[2]):
        d = 2
    else:
        raise MeshError(
            f"{path}: no tetrahedra, hexahedra, wedges, triangles or quadrilaterals; cell types "
            f"found: {listing}. tissuesim needs 'tetra' / 'tetra10' / 'hexahedron' / "
            f"'hexahedron20' / 'hexahedron27' / 'wedge' (3D) or 'triangle' / 'triangle6' / "
            f"'quad' / 'quad8' / 'quad9' (2D) elements: re-export with element order 1 or 2"
        )
    simplex = found.get(_VOLUME[d]) or found.get(_VOLUME2[d])
    if simplex:
        vtype = _VOLUME2[d] if found.get(_VOLUME2[d]) else _VOLUME[d]
    else:
        vtype = next(t for t in _TENSOR[d] if found.get(t))
    others = sorted({b.type for b in m.cells if b.type != vtype and _block_dim(b) >= d})
    if others:
        raise MeshError(
            f"{path}: mixes {vtype} with other elements of dimension >= {d} ({others}); "
            f"cell types found: {listing}. Remesh with {vtype} only (one element order)"
        )
    if d == 3 and points.shape[1] != 3:
        raise MeshError(f"{path}: {vtype} cells need 3D points, got points of shape {points.shape}")
    if d == 2 and points.shape[1] == 3:
        z = points[:, 2]
        scale = float(np.linalg.norm(np.ptp(points, axis=0))) or 1.0
        if np.ptp(z) > 1e-9 * scale:
            raise MeshError(
                f"{path}: surface mesh (triangles in 3D, z from {z.min():.6g} to {z.max():.6g}) "
                f"and no tetrahedra; a volume mesh (tetrahedra) is needed: tetrahedralise the "
                f"surface (e.g. gmsh -3), or give a 2D mesh with constant z"
            )
        points = points[:, :2]
    return points, d, vtype


def _tagged_sets(m, d: int, vtype: str):
    """Point, facet and cell sets from meshio cell sets and gmsh physical tags."""
    offsets, start = [], 0
    for b in m.cells:
        offsets.append(start)
        start += len(b.data) if b.type == vtype else 0
    names = {}
    for name, value in (m.field_data or {}).items():
        v = np.asarray(value).reshape(-1)
        if v.size >= 2:
            names[(int(v[1]), int(v[0]))] = str(name)
    point_sets, facet_sets, cell_sets = defaultdict(list), defaultdict(list), defaultdict(list)
    facet_types, nf = _FACETS[d], d
    if vtype in _TENSOR_FACET:
        facet_types, nf = _TENSOR_FACET[vtype]

    def add(block_index: int, name: str, rows: np.ndarray) -> None:
        b = m.cells[block_index]
        if b.type == vtype:
            cell_sets[name].append(offsets[block_index] + rows)
        elif b.type in facet_types:  # quadratic facets by their corners
            facets = np.asarray(b.data)[rows][:, :nf]
            if facets.shape[1] < nf:  # a wedge's triangle: (a, b, c, c)
                from tissuesim.mesh.cells.wedge import as_facets

                facets = as_facets(facets)
            facet_sets[name].append(facets)
        elif _block_dim(b) < d - 1 or b.type == "vertex":
            point_sets[name].append(np.asarray(b.data)[rows].reshape(-1))

    for name, per_block in (m.cell_sets or {}).items():
        if name.startswith("gmsh:"):
            continue
        for i, rows in enumerate(per_block):
            if rows is not None and len(rows):
                add(i, name, np.asarray(rows, dtype=np.int64))
    for i, tags in enumerate((m.cell_data or {}).get("gmsh:physical", [])):
        tags = np.asarray(tags).reshape(-1)
        for t in np.unique(tags[tags != 0]):
            name = names.get((_block_dim(m.cells[i]), int(t)), f"tag_{int(t)}")
            add(i, name, np.flatnonzero(tags == t))
    return point_sets, facet_sets, cell_sets


def read_mesh(path: str | os.PathLike[str], *, merge_coincident: bool = False) -> Mesh:
    """Read a tetrahedral (3D) or triangle (2D) mesh file, linear or quadratic (tetra10,
    triangle6: their midside nodes are checked, ``mesh/cells/quadratic_checks.py``); points in the
    file's units.

    Any format meshio reads (.vtu, .msh gmsh 2.2/4.1, .mesh medit, .xdmf, ...). Raises MeshError
    naming the file for a missing, unreadable (a FIFO or device is refused before it is opened),
    surface-only or non-simplex mesh, or one with coincident vertices (an unwelded seam) unless
    ``merge_coincident``; vertices no element uses are dropped (``validate_mesh``).
    """
    from tissuesim.validate import regular_file

    path = os.fspath(path)
    if not os.path.exists(path):
        raise MeshError(f"{path}: no such mesh file; check the path (cwd is {os.getcwd()})")
    try:
        regular_file(path, "mesh file")
    except InputError as exc:
        raise MeshError(str(exc)) from None
    if not isinstance(merge_coincident, bool):
        raise MeshError(f"merge_coincident must be true or false, not {short(merge_coincident)}")
    m = _load(path)
    points, d, vtype = _choose_cells(path, m)
    cells = np.concatenate([np.asarray(b.data) for b in m.cells if b.type == vtype])
    psets, fsets, csets = _tagged_sets(m, d, vtype)
    point_sets = {k: np.concatenate(v) for k, v in psets.items()}
    for name, v in (m.point_sets or {}).items():
        point_sets[name] = np.concatenate([point_sets.get(name, []), np.asarray(v).reshape(-1)])
    facet_sets = {k: np.concatenate(v).astype(np.int64) for k, v in fsets.items()}
    if facet_sets:
        if vtype in _TENSOR_FACET:
            from tissuesim.mesh.cells.tensor import face_table

            facets, first, inverse, counts = face_table(cells, d)
        else:
            facets, first, inverse, counts = facet_table(cells[:, : d + 1])
        boundary = facets[first[counts == 1]]
        for name in list(facet_sets):
            on = match_facets(boundary, facet_sets[name]) >= 0
            if not on.all():
                warnings.warn(
                    f"{path}: facet set {name!r}: dropped {int((~on).sum())} of {on.size} facets "
                    f"that are not on the boundary of the mesh",
                    UserWarning,
                    stacklevel=2,
                )
                facet_sets[name] = facet_sets[name][on]
                if not on.any():
                    del facet_sets[name]
    cell_sets = {k: np.concatenate(v) for k, v in csets.items()}
    return validate_mesh(
        points,
        cells,
        source=path,
        point_sets=point_sets,
        facet_sets=facet_sets,
        cell_sets=cell_sets,
        merge_coincident=merge_coincident,
    )


def write_mesh(mesh: Mesh, path: str | os.PathLike[str], file_format: str | None = None) -> None:
    """Write ``mesh`` with meshio (format from the extension unless ``file_format`` is given).

    Points and cells are always written (2D points padded with z = 0). Named sets are written only
    for gmsh 2.2 (the default for ".msh"): facet, cell and point sets as physical groups (a point
    set with the name of a facet or cell set is left out, since gmsh names must be unique).
    """
    import meshio

    path = os.fspath(path)
    d = mesh.dim
    points = np.column_stack([mesh.points, np.zeros(mesh.n_points)]) if d == 2 else mesh.points
    if file_format is None and path.lower().endswith(".msh"):
        file_format = "gmsh22"
    blocks = [(mesh.cell_type, mesh.cells)]
    facet_type = _TENSOR_FACET[mesh.cell_type][0][0] if not mesh.simplicial else _FACET[d]
    wedges = mesh.cell_type == "wedge"
    kwargs = {}
    if file_format == "gmsh22":
        volume_tags = np.zeros(mesh.n_cells, dtype=np.int32)
        physical, field_data, tag = [], {}, 0
        for name, facets in mesh.facet_sets.items():
            tag += 1
            facets = np.asarray(facets)
            if wedges:  # the triangles (a, b, c, c) as triangles, the quads as quads
                from tissuesim.mesh.cells.wedge import is_triangle

                tri = is_triangle(facets)
                parts = [("triangle", facets[tri, :3]), ("quad", facets[~tri])]
            else:
                parts = [(facet_type, facets)]
            for kind, rows in parts:
                if len(rows) or not wedges:
                    blocks.append((kind, rows))
                    physical.append(np.full(len(rows), tag, dtype=np.int32))
            field_data[name] = np.array([tag, d - 1])
        for name, ids in mesh.point_sets.items():
            if name in mesh.facet_sets or name in mesh.cell_sets:
                continue  # gmsh names are unique; vertices_tagged(name) still finds the vertices
            tag += 1
            blocks.append(("vertex", np.asarray(ids).reshape(-1, 1)))
            physical.append(np.full(len(ids), tag, dtype=np.int32))
            field_data[name] = np.array([tag, 0])
        for name, ids in mesh.cell_sets.items():
            tag += 1
            if (volume_tags[ids] != 0).any() or name in mesh.facet_sets:
                warnings.warn(
                    f"{path}: cell set {name!r} overlaps another set or shares its name with a "
                    f"facet set; not written",
                    UserWarning,
                    stacklevel=2,
                )
                continue
            volume_tags[ids] = tag
            field_data[name] = np.array([tag, d])
        physical = [volume_tags, *physical]
        kwargs = {
            "cell_data": {"gmsh:physical": physical, "gmsh:geometrical": physical},
            "field_data": field_data,
        }
    try:
        meshio.Mesh(points, blocks, **kwargs).write(path, file_format=file_format)
    except Exception as exc:
        raise MeshError(f"{path}: meshio could not write the mesh: {exc}") from exc


def describe_mesh(mesh: Mesh) -> dict:
    """Summary of ``mesh`` as a dict of plain Python values (lengths in the mesh's units).

    quality is the radius ratio d * inradius / circumradius of each element: 1 for the regular
    simplex, tending to 0 as an element degenerates; quality_min is the worst element's.
    """
    p, c, d = mesh.points, mesh.corners, mesh.dim  # quality of the straight-sided simplices
    if mesh.simplicial:
        vol = signed_volumes(p, c)
        edges = edge_lengths(p, c)
        faces = all_facets(c)
        surface = facet_measures(p, faces.reshape(-1, d)).reshape(len(c), d + 1).sum(axis=1)
        inradius = d * vol / surface
        x = p[c]
        e = x[:, 1:] - x[:, :1]  # (m, d, d)
        centre = np.linalg.solve(2.0 * e, (e**2).sum(axis=2)[..., None])[..., 0]
        quality = d * inradius / np.linalg.norm(centre, axis=1)
        measure = "radius ratio d * inradius / circumradius (1 = regular simplex)"
    else:
        from tissuesim.mesh.cells.tensor_checks import tensor_quality

        vol, edges, quality = tensor_quality(p, c)
        measure = "scaled Jacobian: min over nodes of det J / product of edge lengths (1 = box)"
    lo, hi = p.min(axis=0), p.max(axis=0)
    return {
        "source": mesh.source,
        "dim": d,
        "n_points": mesh.n_points,
        "n_cells": mesh.n_cells,
        "order": mesh.order,
        "n_boundary_facets": int(len(_boundary(mesh))),
        "bounding_box": (lo.tolist(), hi.tolist()),
        "total_volume": float(vol.sum()),
        "measure_min": float(vol.min()),
        "measure_max": float(vol.max()),
        "measure_mean": float(vol.mean()),
        "edge_min": float(edges.min()),
        "edge_max": float(edges.max()),
        "quality_measure": measure,
        "quality_min": float(quality.min()),
        "quality_mean": float(quality.mean()),
        "worst_cell": int(np.argmin(quality)),
        "point_sets": {k: int(len(v)) for k, v in mesh.point_sets.items()},
        "facet_sets": {k: int(len(v)) for k, v in mesh.facet_sets.items()},
        "cell_sets": {k: int(len(v)) for k, v in mesh.cell_sets.items()},
    }
