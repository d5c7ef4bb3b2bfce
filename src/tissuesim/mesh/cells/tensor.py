"""Q1 quadrilaterals and hexahedra: node order, shape functions, Gauss rules, faces, and the
simplices geometry uses.

Node order is VTK's (and meshio's ``quad`` / ``hexahedron``): on the reference cell [-1, 1]^d

    quad:       0 (-1,-1)  1 (1,-1)  2 (1,1)  3 (-1,1)              (counter-clockwise)
    hexahedron: the quad's four at z = -1, then the same four at z = +1

Shape functions are the tensor products N_a(xi) = prod_j (1 + s_aj xi_j) / 2 with s_a the
node's signs; the rest map X(xi) = sum_a X^a N_a(xi) is multilinear, so its Jacobian varies
over a distorted cell and every integral uses Gauss-Legendre points (2 per direction for the
stiffness, as FElupe and FEBio do).

Everything geometric that works on simplices (point location, contact surfaces, pictures,
ties) sees these cells through a split into simplices over the same nodes: each quad into 2
triangles (along its 0-2 diagonal), each hexahedron into 6 tetrahedra around its 0-6 diagonal
(Kuhn). A boundary quad face then shows as 2 triangles. Neighbouring hexahedra split their
shared face the same way when they number it alike (every structured mesh, the ``box``
generator); where a file's numbering differs, a flat tetrahedron over the face's 4 nodes is
added so that the split stays closed (its faces are both splits' triangles).

The face tables (``all_faces``, ``face_table``, ``boundary_faces``) also serve linear wedges
(``mesh/cells/wedge.py``), whose facets are (k, 4) rows too (``WEDGE_FACES``).
"""

from __future__ import annotations

from functools import cache

import numpy as np

__all__ = [
    "SIGNS",
    "FACES",
    "WEDGE_FACES",
    "local_faces",
    "collapsed_triangles",
    "shape_functions",
    "gauss_rule",
    "rest_jacobians",
    "boundary_faces",
    "subdivide",
    "positively_oriented",
    "split_faces",
]

#: the reference coordinates (+-1) of each node, in node order
SIGNS = {
    2: np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float),
    3: np.array(
        [
            [-1, -1, -1],
            [1, -1, -1],
            [1, 1, -1],
            [-1, 1, -1],
            [-1, -1, 1],
            [1, -1, 1],
            [1, 1, 1],
            [-1, 1, 1],
        ],
        dtype=float,
    ),
}

#: the local nodes of each facet of a positively oriented cell, ordered so that the facet's
#: normal points out of the cell: edges a -> b with normal (dy, -dx) for quads, faces whose
#: (x1 - x0) x (x3 - x0) points out for hexahedra
FACES = {
    2: np.array([[0, 1], [1, 2], [2, 3], [3, 0]]),
    3: np.array(
        [
            [0, 3, 2, 1],  # z = -1
            [4, 5, 6, 7],  # z = +1
            [0, 1, 5, 4],  # y = -1
            [3, 7, 6, 2],  # y = +1
            [0, 4, 7, 3],  # x = -1
            [1, 2, 6, 5],  # x = +1
        ]
    ),
}

#: the facets of a linear wedge (``mesh/cells/wedge.py``), outward as ``FACES``: the triangles with
#: their last corner repeated, so that a wedge mesh's facets are (k, 4) rows like a
#: hexahedral one's and the face tables below serve both
WEDGE_FACES = np.array(
    [
        [0, 2, 1, 1],  # bottom, t = -1
        [3, 4, 5, 5],  # top, t = +1
        [0, 1, 4, 3],  # s = 0
        [1, 2, 5, 4],  # r + s = 1
        [2, 0, 3, 5],  # r = 0
    ]
)

# simplices of one cell in local node numbers, positively oriented for a positive cell
_SPLIT = {
    2: np.array([[0, 1, 2], [0, 2, 3]]),
    # the 6 Kuhn tetrahedra around the diagonal 0-6: paths 0 -> a -> a+b -> 6 along edges
    3: np.array(
        [[0, 1, 2, 6], [0, 3, 2, 6], [0, 3, 7, 6], [0, 4, 7, 6], [0, 4, 5, 6], [0, 1, 5, 6]]
    ),
}


def shape_functions(dim: int, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """N (q, nv) and dN/dxi (q, nv, d) of the Q1 cell at reference points xi (q, d)."""
    xi = np.atleast_2d(np.asarray(xi, dtype=float))
    s = SIGNS[dim]  # (nv, d)
    factors = 0.5 * (1.0 + xi[:, None, :] * s[None])  # (q, nv, d): (1 + s_j xi_j) / 2
    N = factors.prod(axis=2)
    dN = np.empty(factors.shape)
    for j in range(dim):  # d directions, not a loop over points
        others = np.delete(factors, j, axis=2).prod(axis=2)
        dN[:, :, j] = 0.5 * s[None, :, j] * others
    return N, dN


@cache
def gauss_rule(dim: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Tensor Gauss-Legendre rule on [-1, 1]^dim with n points per direction: points
    (n^dim, dim) and weights (n^dim,), summing to 2^dim; exact for degree 2n - 1 per
    variable. Points run with the first coordinate fastest."""
    x, w = np.polynomial.legendre.leggauss(n)
    grids = np.meshgrid(*([x] * dim), indexing="ij")
    wgrids = np.meshgrid(*([w] * dim), indexing="ij")
    pts = np.stack([g.ravel(order="F") for g in grids], axis=1)
    weights = np.prod([g.ravel(order="F") for g in wgrids], axis=0)
    return pts, weights


def rest_jacobians(points: np.ndarray, cells: np.ndarray, dN: np.ndarray) -> np.ndarray:
    """J (m, q, d, d) of the rest map at reference points with shape gradients dN (q, nv, d)."""
    return np.einsum("mai,qaj->mqij", points[cells], dN)


def local_faces(dim: int, nv: int) -> np.ndarray:
    """The local facets (f, nf) of a cell of nv nodes: ``FACES[dim]`` for quadrilaterals and
    hexahedra (their corners), ``WEDGE_FACES`` for wedges."""
    return WEDGE_FACES if (dim, nv) == (3, 6) else FACES[dim]


def all_faces(cells: np.ndarray, dim: int) -> np.ndarray:
    """Every facet of every cell, outward for its cell: (m, f, nf) (edges or quad faces; a
    wedge's 5 faces, its triangles as collapsed quads, ``collapsed_triangles``)."""
    cells = np.asarray(cells)
    faces = cells[:, local_faces(dim, cells.shape[1])]
    if (dim, cells.shape[1]) == (3, 6):
        faces[:, :2] = collapsed_triangles(faces[:, :2, :3])
    return faces


def collapsed_triangles(triangles: np.ndarray) -> np.ndarray:
    """Triangles (..., 3) as 4-node rows (..., 4) (a, b, c, c): the corners in the same cyclic
    order (the same orientation), rotated so that the repeated one is the largest, so that
    every description of a triangle gives one row and one sorted key."""
    t = np.asarray(triangles)
    k = np.argmax(t, axis=-1)[..., None]
    return np.take_along_axis(t, (k + np.array([1, 2, 0, 0])) % 3, axis=-1)


def face_table(cells: np.ndarray, dim: int):
    """Unique facets of Q1 or wedge ``cells``: (faces (m*f, nf) in cell order, first (u,),
    inverse (m*f,), counts (u,)), as ``boundary.facet_table`` for simplices."""
    faces = all_faces(cells, dim).reshape(-1, FACES[dim].shape[1])
    keys = np.sort(faces, axis=1)
    _, first, inverse, counts = np.unique(
        keys, axis=0, return_index=True, return_inverse=True, return_counts=True
    )
    return faces, first, inverse.reshape(-1), counts


def boundary_faces(cells: np.ndarray, dim: int) -> np.ndarray:
    """Facets (k, nf) int64 of Q1 or wedge cells that belong to one cell only (edges (k, 2) of
    quads, quad faces (k, 4) of hexahedra, quads and collapsed triangles (k, 4) of wedges),
    outward, in the order of the cells they belong to."""
    faces, first, _, counts = face_table(cells, dim)
    return np.ascontiguousarray(faces[np.sort(first[counts == 1])], dtype=np.int64)


def split_faces(faces: np.ndarray) -> np.ndarray:
    """Quad faces (k, 4) as triangles (2k, 3) with the same outward orientation, each split
    along its 0-2 diagonal (the split ``subdivide`` gives a boundary face)."""
    faces = np.asarray(faces, dtype=np.int64)
    return faces[:, [[0, 1, 2], [0, 2, 3]]].reshape(-1, 3)


def subdivide(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Simplices (s, d + 1) over the cells' nodes and the parent cell of each (s,).

    Quads: 2 triangles; hexahedra: 6 tetrahedra, plus a flat tetrahedron over every interior
    face that its two hexahedra split along different diagonals (so the split has no holes:
    its boundary triangles are exactly the boundary faces' halves).
    """
    d = points.shape[1]
    split = _SPLIT[d]
    simplices = cells[:, split].reshape(-1, d + 1)
    parent = np.repeat(np.arange(cells.shape[0]), split.shape[0])
    if d == 3:
        glue, owner = _glue_tets(cells)
        if len(glue):
            simplices = np.concatenate([simplices, glue])
            parent = np.concatenate([parent, owner])
    return positively_oriented(points, simplices), parent


def positively_oriented(points: np.ndarray, simplices: np.ndarray) -> np.ndarray:
    """The simplices (s, d+1) with the first two vertices swapped where their volume is
    negative (a distorted cell can give a simplex of its split the other orientation)."""
    X = points[simplices]
    vol = np.linalg.det(np.swapaxes(X[:, 1:] - X[:, :1], 1, 2))
    flip = vol < 0
    simplices[flip, :2] = simplices[flip, 1::-1]
    return np.ascontiguousarray(simplices, dtype=np.int64)


def _glue_tets(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Flat tetrahedra (g, 4) over interior faces split differently by their two hexahedra,
    and one owning hexahedron each (g,)."""
    faces, first, inverse, counts = face_table(cells, 3)
    # the Kuhn split cuts each face along the diagonal through local node 0 or 6
    local = FACES[3]
    through = np.where((local == 0) | (local == 6), 1, 0).argmax(axis=1)  # (6,) position
    m = cells.shape[0]
    diag = faces.reshape(m, 6, 4)[:, np.arange(6), through]  # (m, 6) the diagonal's end
    opposite = faces.reshape(m, 6, 4)[:, np.arange(6), (through + 2) % 4]
    key = np.minimum(diag, opposite).ravel()  # the diagonal by its lower end
    interior = counts[inverse] == 2
    idx = np.flatnonzero(interior)
    order = np.argsort(inverse[idx], kind="stable")
    pairs = idx[order].reshape(-1, 2)  # the two occurrences of each interior face
    differ = key[pairs[:, 0]] != key[pairs[:, 1]]
    if not differ.any():
        return np.zeros((0, 4), dtype=np.int64), np.zeros(0, dtype=np.int64)
    glue = faces[pairs[differ, 0]]
    return glue.astype(np.int64), pairs[differ, 0] // 6
