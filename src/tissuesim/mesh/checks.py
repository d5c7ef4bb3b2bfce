"""Validation of raw mesh arrays: every Mesh tissuesim builds goes through ``validate_mesh``."""

from __future__ import annotations

import warnings
from collections.abc import Mapping

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries.boundary import boundary_from_table, facet_table, match_facets

__all__ = ["validate_mesh", "signed_volumes", "edge_lengths"]

_KIND = {2: "triangles", 3: "tetrahedra"}
#: the permutation that swaps the last two corners (and, for quadratic cells, the midside nodes
#: with them): triangle6 (0 2 1 | 20 12 01), tetra10 (0 1 3 2 | 01 13 30 02 12 32)
_REORIENT_LINEAR = {2: [0, 2, 1], 3: [0, 1, 3, 2]}
_REORIENT = {2: [0, 2, 1, 5, 4, 3], 3: [0, 1, 3, 2, 4, 8, 7, 6, 5, 9]}
#: nodes per quadrilateral / hexahedron: Q1, then quadratic (quad8, quad9; hexahedron20, 27);
#: in 3D also the 6-node wedge (checked like them, ``tensor_checks``)
_TENSOR_WIDTHS = {2: (4, 8, 9), 3: (8, 20, 27, 6)}
#: what the facets of a mesh are, by (dimension, nodes per cell; 0: simplices)
_FACET_WORDS = {
    (2, 0): "edges",
    (3, 0): "triangles",
    **{(2, nv): "edges" for nv in (4, 8, 9)},
    **{(3, nv): "quad faces" for nv in (8, 20, 27)},
    (3, 6): "quad faces and triangles (k, 4), a triangle as (a, b, c, c)",
}


def signed_volumes(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Signed areas (2D) or volumes (3D) of ``cells`` (m, d+1) of ``points`` (n, d): (m,) float64.

    det[x1 - x0, ..., xd - x0] / d!; positive for positively oriented (counter-clockwise) cells.
    """
    x = np.asarray(points, dtype=np.float64)[np.asarray(cells)]
    d = x.shape[2]
    return np.linalg.det(x[:, 1:] - x[:, :1]) / (2.0 if d == 2 else 6.0)


def edge_lengths(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Lengths (m, d(d+1)/2) of the edges of each of ``cells`` (m, d+1)."""
    x = np.asarray(points, dtype=np.float64)[np.asarray(cells)]
    i, j = np.triu_indices(x.shape[1], k=1)
    e = x[:, j] - x[:, i]
    return np.sqrt(np.einsum("mki,mki->mk", e, e))


def _first(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


def _index_array(values, source: str, what: str, shape_hint: str) -> np.ndarray:
    try:
        a = np.asarray(values)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{source}: {what} must be an integer array {shape_hint}: {exc}") from exc
    if a.size == 0:
        return a.astype(np.int64)
    if not np.issubdtype(a.dtype, np.integer):
        if not np.issubdtype(a.dtype, np.floating) or not np.all(np.round(a) == a):
            raise MeshError(
                f"{source}: {what} must hold integer indices {shape_hint}, got {a.dtype}"
            )
    return np.array(a, dtype=np.int64)


#: vertices closer than this fraction of the bounding-box diagonal count as one point
COINCIDENT_TOLERANCE = 1e-9


def _weld(pts, c, point_sets, facet_sets, source: str, merge: bool):
    """Find vertices closer than the tolerance; refuse them, or merge each group into its
    lowest index (cells, point and facet sets remapped)."""
    from scipy.spatial import cKDTree

    tol = COINCIDENT_TOLERANCE * float(np.linalg.norm(np.ptp(pts, axis=0)))
    pairs = cKDTree(pts).query_pairs(tol, output_type="ndarray") if len(pts) > 1 else None
    if pairs is None or not len(pairs):
        return pts, c, point_sets, facet_sets
    if not merge:
        i, j = (int(k) for k in pairs[0])
        groups = len(np.unique(pairs.max(axis=1)))
        raise MeshError(
            f"{source}: {groups} vertices coincide with another vertex (within {tol:.3g}, "
            f"{COINCIDENT_TOLERANCE:g} of the mesh size; e.g. vertices {i} and {j} at "
            f"{pts[i].tolist()}): an unwelded seam splits the body. Weld them in the mesher, or "
            "merge them with merge_coincident = true (read_mesh(..., merge_coincident=True))"
        )
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    n = len(pts)
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    first = np.full(label.max() + 1, n)
    np.minimum.at(first, label, np.arange(n))
    target = first[label]  # each vertex -> the lowest index of its group
    merged = int((target != np.arange(n)).sum())
    warnings.warn(
        f"{source}: merged {merged} coincident vertices (within {tol:.3g}) into their "
        "neighbours (merge_coincident)",
        UserWarning,
        stacklevel=4,
    )
    c = target[c]
    point_sets = {k: target[v] for k, v in point_sets.items()}
    facet_sets = {k: target[np.asarray(v, dtype=np.int64)] for k, v in (facet_sets or {}).items()}
    return pts, c, point_sets, facet_sets


def _drop_unused(pts, c, point_sets, facet_sets, source: str):
    """Drop vertices no element uses (a solver would see them as free, massless DOFs)."""
    n = len(pts)
    used = np.bincount(c.ravel(), minlength=n) > 0
    if used.all():
        return pts, c, point_sets, facet_sets
    new = np.cumsum(used) - 1
    dropped = np.flatnonzero(~used)
    warnings.warn(
        f"{source}: dropped {dropped.size} vertices that belong to no element (first: "
        f"{dropped[:5].tolist()}); the indices of later vertices shift down by as many: select "
        "vertices by position or tag rather than by index",
        UserWarning,
        stacklevel=4,
    )
    point_sets = {k: new[v[used[v]]] for k, v in point_sets.items()}
    fsets = {}
    for k, v in (facet_sets or {}).items():
        a = np.asarray(v)
        if a.size and np.issubdtype(a.dtype, np.integer) and a.min() >= 0 and a.max() < n:
            if not used[a].all():
                v = int(a[~used[a]][0])
                raise MeshError(
                    f"{source}: facet set {k!r} uses vertex {v}, which belongs to no element; "
                    "a facet set must list boundary facets of the elements"
                )
            a = new[a]
        fsets[k] = a
    return pts[used], new[c], point_sets, fsets


def validate_mesh(
    points,
    cells,
    *,
    source: str,
    point_sets: Mapping[str, np.ndarray] | None = None,
    facet_sets: Mapping[str, np.ndarray] | None = None,
    cell_sets: Mapping[str, np.ndarray] | None = None,
    merge_coincident: bool = False,
    surface_projection=None,
) -> Mesh:
    """Check raw arrays and build a Mesh; raises MeshError naming ``source`` and the bad element.

    points: (n, d) coordinates, d = 2 or 3, finite. cells: (m, d+1) 0-based vertex indices.
    point_sets: name -> (k,) vertex ids. facet_sets: name -> (k, d) boundary facets (reoriented
    outward; (k, 4) quad faces of hexahedra; for wedges (k, 4) rows, a triangle (k, 3) or
    (a, b, c, c)). cell_sets: name -> (k,) cell ids. Negatively oriented cells are fixed by
    swapping their last two vertices (mirrored hexahedra and wedges: ``tensor_checks``), with a
    UserWarning. Vertices closer than COINCIDENT_TOLERANCE
    times the bounding-box diagonal (an unwelded seam) are refused, or merged with
    ``merge_coincident``; vertices no element uses are dropped (UserWarning; indices after
    them shift down, point sets are remapped).
    """
    try:
        pts = np.array(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{source}: points are not an (n, d) array of numbers: {exc}") from exc
    if pts.ndim != 2 or pts.shape[1] not in (2, 3):
        raise MeshError(
            f"{source}: points have shape {pts.shape}; expected (n, 2) or (n, 3) coordinates"
        )
    n, d = pts.shape
    finite = np.isfinite(pts).all(axis=1)
    if not finite.all():
        i = _first(~finite)
        raise MeshError(
            f"{source}: vertex {i} has non-finite coordinates {pts[i].tolist()} "
            f"({int((~finite).sum())} such vertices); fix or remove them in the mesh file"
        )
    c = _index_array(cells, source, "cells", f"(m, {d + 1})")
    nq = (d + 1) * (d + 2) // 2
    widths = _TENSOR_WIDTHS[d]
    if c.ndim != 2 or c.shape[1] not in (d + 1, nq, *widths):
        raise MeshError(
            f"{source}: cells have shape {c.shape}; {d}D points need (m, {d + 1}) cells "
            f"({_KIND[d]}, one row of {d + 1} vertex indices per element), (m, {nq}) "
            f"quadratic cells (corners, then midside nodes) or "
            f"{'(m, 4 / 8 / 9) quadrilaterals' if d == 2 else '(m, 8 / 20 / 27) hexahedra'}"
            f"{' or (m, 6) wedges' if d == 3 else ''}"
        )
    quadratic = c.shape[1] == nq
    tensor = c.shape[1] in widths
    m = c.shape[0]
    if m == 0:
        raise MeshError(f"{source}: the mesh has no cells; it needs at least one of the {_KIND[d]}")

    bad = (c < 0) | (c >= n)
    if bad.any():
        e = _first(bad.any(axis=1))
        v = int(c[e, _first(bad[e])])
        raise MeshError(
            f"{source}: element {e} refers to vertex {v}, but vertex indices run from 0 to {n - 1} "
            f"({int(bad.any(axis=1).sum())} elements affected); indices must be 0-based and "
            f"every vertex must be listed in the points"
        )
    s = np.sort(c, axis=1)
    repeated = (s[:, 1:] == s[:, :-1]).any(axis=1)
    if repeated.any():
        e = _first(repeated)
        raise MeshError(
            f"{source}: element {e} repeats a vertex {c[e].tolist()} "
            f"({int(repeated.sum())} such elements); remove these collapsed elements"
        )

    if tensor:
        from tissuesim.mesh.cells.tensor_checks import check_tensor_cells, reorient_permutation

        flipped = check_tensor_cells(pts, c, source)
        reorder, how = reorient_permutation(d, c.shape[1]), "mirroring their vertex order"
    else:
        flipped = _check_simplices(pts, c, source, d)
        reorder = _REORIENT[d] if quadratic else _REORIENT_LINEAR[d]
        how = "swapping their last two vertices"
    if flipped.size:
        # swap the last two corners; a quadratic cell's midside nodes follow their edges
        c[flipped] = c[flipped][:, reorder]
        warnings.warn(
            f"{source}: reoriented {flipped.size} negatively oriented element(s) by {how} "
            f"(first: {flipped[:5].tolist()})",
            UserWarning,
            stacklevel=2,
        )
    return _finish_checks(
        pts,
        c,
        d,
        m,
        quadratic,
        tensor,
        source,
        point_sets,
        facet_sets,
        cell_sets,
        merge_coincident,
        surface_projection,
    )


def _check_simplices(pts, c, source: str, d: int) -> np.ndarray:
    """MeshError for a degenerate simplex; the negatively oriented ones' indices."""
    vol = signed_volumes(pts, c[:, : d + 1])
    h = edge_lengths(pts, c[:, : d + 1]).mean(axis=1)
    degenerate = np.abs(vol) <= 1e-12 * h**d
    if degenerate.any():
        e = _first(degenerate)
        raise MeshError(
            f"{source}: element {e} with vertices {c[e].tolist()} is degenerate "
            f"({'area' if d == 2 else 'volume'} {vol[e]:.3g}, mean edge {h[e]:.3g}; "
            f"{int(degenerate.sum())} such elements); its vertices are "
            f"{'collinear' if d == 2 else 'coplanar'}: remesh or remove these elements"
        )
    return np.flatnonzero(vol < 0)


def _finish_checks(
    pts,
    c,
    d,
    m,
    quadratic,
    tensor,
    source,
    point_sets,
    facet_sets,
    cell_sets,
    merge_coincident,
    surface_projection,
) -> Mesh:
    """The checks after the cells' own: sets, coincident and unused vertices, shared facets."""
    n = pts.shape[0]
    point_sets = {
        k: _index_array(v, source, f"point set {k!r}", "(k,)").reshape(-1)
        for k, v in (point_sets or {}).items()
    }
    for name, a in point_sets.items():
        if ((a < 0) | (a >= n)).any():
            raise MeshError(f"{source}: point set {name!r} has vertex ids outside 0..{n - 1}")
    pts, c, point_sets, facet_sets = _weld(pts, c, point_sets, facet_sets, source, merge_coincident)
    s = np.sort(c, axis=1)
    collapsed = (s[:, 1:] == s[:, :-1]).any(axis=1)
    if collapsed.any():
        raise MeshError(
            f"{source}: merging coincident vertices collapses element {_first(collapsed)} "
            f"({int(collapsed.sum())} such elements): the vertices are not a seam but part of "
            "tiny elements; remesh instead of merging"
        )
    pts, c, point_sets, facet_sets = _drop_unused(pts, c, point_sets, facet_sets, source)
    n = pts.shape[0]
    if quadratic:
        from tissuesim.mesh.cells.quadratic_checks import check_quadratic

        check_quadratic(pts, c, source)
    wedges = (d, c.shape[1]) == (3, 6)
    if tensor:
        from tissuesim.mesh.cells.tensor import face_table, local_faces

        table = face_table(c, d)
        nf, per_cell = (4 if d == 3 else 2), len(local_faces(d, c.shape[1]))
        if c.shape[1] != 2**d and not wedges:
            from tissuesim.mesh.cells.tensor_quadratic import check_shared_nodes

            check_shared_nodes(c, d, table, source)
    else:
        table = facet_table(c[:, : d + 1])
        nf, per_cell = d, d + 1
    facets, first, inverse, counts = table
    if (counts > 2).any():
        u = _first(counts > 2)
        owners = (np.flatnonzero(inverse == u) // per_cell).tolist()
        raise MeshError(
            f"{source}: facet {np.sort(facets[first[u]]).tolist()} is shared by elements {owners}; "
            f"a facet belongs to at most 2 elements: remove duplicate or overlapping elements"
        )

    psets = {str(name): np.unique(a) for name, a in point_sets.items()}
    csets = {}
    for name, v in (cell_sets or {}).items():
        a = _index_array(v, source, f"cell set {name!r}", "(k,)").reshape(-1)
        if ((a < 0) | (a >= m)).any():
            raise MeshError(f"{source}: cell set {name!r} has cell ids outside 0..{m - 1}")
        csets[str(name)] = np.unique(a)
    fsets = {}
    boundary = boundary_from_table(*table) if facet_sets else None
    for name, v in (facet_sets or {}).items():
        a = _index_array(v, source, f"facet set {name!r}", f"(k, {nf})")
        if a.size == 0:
            a = a.reshape(0, nf)
        if wedges:  # triangles (k, 3) and collapsed quads as (a, b, c, c)
            from tissuesim.mesh.cells.wedge import as_facets

            a = as_facets(a)
        if a.ndim != 2 or a.shape[1] != nf:
            raise MeshError(f"{source}: facet set {name!r} has shape {a.shape}; expected (k, {nf})")
        row = match_facets(boundary, a)
        if (row < 0).any():
            k = _first(row < 0)
            raise MeshError(
                f"{source}: facet set {name!r} row {k} {a[k].tolist()} is not a boundary facet "
                f"of the mesh; facet sets must list boundary "
                f"{_FACET_WORDS[d, c.shape[1]] if tensor else _FACET_WORDS[d, 0]}"
            )
        fsets[str(name)] = boundary[np.unique(row)]
    return Mesh(
        points=np.ascontiguousarray(pts),
        cells=np.ascontiguousarray(c),
        point_sets=psets,
        facet_sets=fsets,
        cell_sets=csets,
        source=source,
        surface_projection=surface_projection,
    )
