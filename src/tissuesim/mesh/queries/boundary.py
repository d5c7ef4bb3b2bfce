"""Boundary facets of simplicial meshes, with their measures and outward normals.

A facet is an edge (2 vertex ids) of a triangle mesh or a triangle (3 vertex ids) of a tetrahedral
mesh. Boundary facets are oriented so that their normal points out of the domain: in 2D the edge
a -> b has normal (dy, -dx); in 3D the triangle (a, b, c) has normal (b - a) x (c - a).
Lengths are in the units of the points, areas in those units squared.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.rows import row_keys, unique_rows

__all__ = ["boundary_facets", "facet_measures", "facet_normals"]

# Local vertex ids of the facets of a positively oriented simplex, each oriented outward.
_LOCAL_FACETS = {
    2: np.array([[0, 1], [1, 2], [2, 0]]),
    3: np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]]),
}


def all_facets(cells: np.ndarray) -> np.ndarray:
    """Every facet of every cell, outward for its cell: (m, d+1, d) for cells (m, d+1)."""
    cells = np.asarray(cells)
    d = cells.shape[1] - 1
    if d not in _LOCAL_FACETS:
        raise InputError(f"cells must have 3 (triangles) or 4 (tetrahedra) columns, got {d + 1}")
    return cells[:, _LOCAL_FACETS[d]]


def sort_rows(rows: np.ndarray) -> np.ndarray:
    """``np.sort(rows, axis=1)`` for (k, 2) or (k, 3) ints, by a min/max network (faster)."""
    rows = np.asarray(rows)
    if rows.ndim != 2 or rows.shape[1] not in (2, 3):
        return np.sort(rows, axis=1)
    a, b = rows[:, 0], rows[:, 1]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    if rows.shape[1] == 2:
        return np.stack([lo, hi], axis=1)
    c = rows[:, 2]
    mid = np.maximum(lo, np.minimum(hi, c))
    return np.stack([np.minimum(lo, c), mid, np.maximum(hi, c)], axis=1)


def facet_table(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Unique facets of ``cells`` (m, d+1).

    Returns (facets, first, inverse, counts): facets (m*(d+1), d) every cell facet in cell order
    (outward for its cell), first (u,) index into facets of the first occurrence of each unique
    facet, inverse (m*(d+1),) unique id of each facet, counts (u,) how many cells share each.
    """
    facets = all_facets(cells).reshape(-1, np.asarray(cells).shape[1] - 1)
    _, first, inverse, counts = unique_rows(
        sort_rows(facets), return_index=True, return_inverse=True, return_counts=True
    )
    return facets, first, inverse, counts


def boundary_facets(cells: np.ndarray) -> np.ndarray:
    """Facets (k, d) int64 that belong to exactly one of the positively oriented ``cells`` (m, d+1).

    Oriented outward (see the module docstring), in the order of the cells they belong to.
    """
    return boundary_from_table(*facet_table(cells))


def boundary_from_table(facets, first, inverse, counts) -> np.ndarray:
    """Boundary facets (k, d) from the output of ``facet_table``."""
    return np.ascontiguousarray(facets[np.sort(first[counts == 1])], dtype=np.int64)


def match_facets(table: np.ndarray, queries: np.ndarray) -> np.ndarray:
    """First row of ``table`` (t, d) with the vertex set of each query (q, d), else -1: (q,)."""
    queries = sort_rows(np.asarray(queries, dtype=np.int64))
    table = sort_rows(np.asarray(table, dtype=np.int64).reshape(-1, queries.shape[1]))
    keys = row_keys(np.concatenate([table, queries]))
    if keys is None:
        _, keys = np.unique(np.concatenate([table, queries]), axis=0, return_inverse=True)
        keys = keys.reshape(-1)
    tkeys, qkeys = keys[: len(table)], keys[len(table) :]
    if len(table) == 0:
        return np.full(len(qkeys), -1, dtype=np.int64)
    order = np.argsort(tkeys, kind="stable")
    pos = np.minimum(np.searchsorted(tkeys[order], qkeys), len(table) - 1)
    found = tkeys[order[pos]] == qkeys
    return np.where(found, order[pos], -1).astype(np.int64)


def _facet_vectors(points: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Unnormalised normals (k, d): (dy, -dx) in 2D, (b - a) x (c - a) in 3D."""
    points = np.asarray(points, dtype=np.float64)
    facets = np.asarray(facets, dtype=np.int64)
    d = points.shape[1]
    if facets.ndim != 2 or facets.shape[1] != d:
        raise InputError(f"facets must have shape (k, {d}) for {d}D points, got {facets.shape}")
    x = points[facets]
    if d == 2:
        e = x[:, 1] - x[:, 0]
        return np.stack([e[:, 1], -e[:, 0]], axis=1)
    return np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])


def facet_measures(points: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Lengths (2D) or areas (3D) of ``facets`` (k, d) of ``points`` (n, d): (k,) float64."""
    n = _facet_vectors(points, facets)
    length = np.linalg.norm(n, axis=1)
    return length if n.shape[1] == 2 else 0.5 * length


def facet_normals(points: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Unit normals (k, d) of ``facets`` (k, d); outward for facets from ``boundary_facets``."""
    n = _facet_vectors(points, facets)
    return n / np.linalg.norm(n, axis=1, keepdims=True)
