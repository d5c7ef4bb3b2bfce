"""Quadratic (P2) simplices: node order, midside nodes, and the linear subdivision.

Node order is VTK's (and meshio's, which converts Gmsh's on reading):

    triangle6: corners 0 1 2, then the midpoints of edges (0,1) (1,2) (2,0)
    tetra10:   corners 0 1 2 3, then edges (0,1) (1,2) (2,0) (0,3) (1,3) (2,3)

Everything geometric that works on simplices (boundary facets, point location, contact surfaces,
pictures, ties, attachments) sees a quadratic mesh through its *linear subdivision*: each
triangle6 split into 4 triangles and each tetra10 into 8 tetrahedra over the same nodes, so
every node keeps its index and a field on the nodes needs no mapping. Only the elasticity,
mass and loads (``kinematics/p2.py``, ``energies/``) use the quadratic shape functions.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "EDGES",
    "elevate",
    "subdivide",
    "midside_lookup",
    "quadratic_facets",
]

#: the local corner pairs of the midside nodes, in node order after the corners
EDGES = {
    1: np.array([[0, 1]]),
    2: np.array([[0, 1], [1, 2], [2, 0]]),
    3: np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]]),
}

# the linear sub-simplices of one quadratic simplex, in local node numbers
_SUB = {
    2: np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]]),
    # four corner tetrahedra, then the inner octahedron split along the (0,1)-(2,3) diagonal
    3: np.array(
        [
            [0, 4, 6, 7],
            [4, 1, 5, 8],
            [6, 5, 2, 9],
            [7, 8, 9, 3],
            [4, 9, 5, 8],
            [4, 9, 8, 7],
            [4, 9, 7, 6],
            [4, 9, 6, 5],
        ]
    ),
}


def subdivide(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear sub-simplices (m*s, d+1) of quadratic cells (m, nv), positively oriented at the
    rest points, and the parent cell of each (m*s,)."""
    d = points.shape[1]
    sub = _SUB[d]
    simplices = cells[:, sub].reshape(-1, d + 1)
    parent = np.repeat(np.arange(cells.shape[0]), sub.shape[0])
    X = points[simplices]
    vol = np.linalg.det(np.swapaxes(X[:, 1:] - X[:, :1], 1, 2))
    flip = vol < 0  # a curved parent can give a sub-simplex the other orientation
    simplices[flip, :2] = simplices[flip, 1::-1]
    return simplices, parent


def elevate(
    points: np.ndarray, cells: np.ndarray, boundary_projection=None
) -> tuple[np.ndarray, np.ndarray]:
    """Quadratic cells from linear ones: one new node at the midpoint of every edge.

    boundary_projection: optional callable (k, d) -> (k, d) applied to the midpoints of
    boundary edges (curved boundaries, e.g. an ellipsoid's surface).
    Returns (points (n + edges, d), cells (m, 6 or 10)); the first n points are unchanged.
    """
    n, d = points.shape
    local = EDGES[d]
    pairs = np.sort(cells[:, local], axis=2).reshape(-1, 2)  # (m * ne, 2)
    edges, inverse = np.unique(pairs, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    mid = 0.5 * (points[edges[:, 0]] + points[edges[:, 1]])
    if boundary_projection is not None:
        on_boundary = _boundary_edge_mask(cells, edges, d)
        if on_boundary.any():
            mid[on_boundary] = boundary_projection(mid[on_boundary])
    new_cells = np.concatenate([cells, n + inverse.reshape(cells.shape[0], -1)], axis=1)
    return np.concatenate([points, mid]), new_cells.astype(np.int64)


def _boundary_edge_mask(cells: np.ndarray, edges: np.ndarray, d: int) -> np.ndarray:
    from tissuesim.mesh.queries.boundary import boundary_facets

    facets = boundary_facets(cells)  # (k, d)
    if d == 2:
        on = np.sort(facets, axis=1)
    else:
        on = np.sort(facets[:, [[0, 1], [1, 2], [2, 0]]], axis=2).reshape(-1, 2)
    key = edges[:, 0] * (edges.max() + 1) + edges[:, 1]
    okey = on[:, 0] * (edges.max() + 1) + on[:, 1]
    return np.isin(key, okey)


def midside_lookup(cells: np.ndarray, dim: int):
    """A function (k, 2) corner pairs -> (k,) midside node indices (-1 where no cell of
    ``cells`` has that edge): expands a linear facet's corners into its quadratic nodes."""
    local = EDGES[dim]
    pairs = np.sort(cells[:, local], axis=2)
    pairs = pairs.reshape(-1, 2).astype(np.int64)
    mids = cells[:, dim + 1 :].reshape(-1).astype(np.int64)
    base = int(cells.max()) + 1
    keys = pairs[:, 0] * base + pairs[:, 1]
    order = np.argsort(keys, kind="stable")
    keys, mids = keys[order], mids[order]

    def lookup(corner_pairs: np.ndarray) -> np.ndarray:
        p = np.sort(np.asarray(corner_pairs, dtype=np.int64), axis=-1)
        want = p[..., 0] * base + p[..., 1]
        pos = np.minimum(np.searchsorted(keys, want), keys.size - 1)
        return np.where(keys[pos] == want, mids[pos], -1)

    return lookup


def quadratic_facets(mesh, facets: np.ndarray) -> np.ndarray:
    """Boundary facets given by corners (k, d) with their midside nodes appended: (k, 3) edges
    [a, b, m_ab] in 2D, (k, 6) triangles [a, b, c, m_ab, m_bc, m_ca] in 3D; for quadratic
    quadrilaterals / hexahedra their edges (k, 3) or quad faces (k, 8 / 9)
    (``tensor_quadratic.full_facets``)."""
    if not mesh.simplicial:
        from tissuesim.mesh.cells.tensor_quadratic import full_facets

        return full_facets(mesh, facets)
    d = mesh.dim
    facets = np.asarray(facets, dtype=np.int64)
    mids = mesh.midside(facets[:, EDGES[d - 1]])  # (k, d(d-1)/2 or 1)
    return np.concatenate([facets, mids.reshape(facets.shape[0], -1)], axis=1)
