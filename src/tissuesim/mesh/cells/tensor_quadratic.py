"""Quadratic quadrilaterals and hexahedra: quad8 / hexahedron20 (serendipity) and quad9 /
hexahedron27 (Lagrange, bi- / triquadratic): node order, shape functions, facets and the
simplices geometry uses.

Node order is VTK's (VTK_QUADRATIC_QUAD 23, VTK_BIQUADRATIC_QUAD 28,
VTK_QUADRATIC_HEXAHEDRON 25, VTK_TRIQUADRATIC_HEXAHEDRON 29; meshio's and FElupe's ``quad8``,
``quad9``, ``hexahedron20``, ``hexahedron27``), on the reference cell [-1, 1]^d:

    corners as the Q1 cell's (``mesh/cells/tensor.py``), then the midside nodes of the edges
    quad:       (0,1) (1,2) (2,3) (3,0), then (quad9) the centre
    hexahedron: (0,1) (1,2) (2,3) (3,0)  (4,5) (5,6) (6,7) (7,4)  (0,4) (1,5) (2,6) (3,7),
                then (hexahedron27) the face centres x = -1, x = +1, y = -1, y = +1, z = -1,
                z = +1, then the centre

(``NODES`` holds each node's reference coordinates.) The Lagrange shape functions are
products of the 1D quadratics L_-1 = t (t - 1) / 2, L_0 = 1 - t^2, L_1 = t (t + 1) / 2. The
serendipity ones (corner: prod_j (1 + s_j xi_j) / 2^d (sum_j s_j xi_j - d + 1); midside node
with s_k = 0: (1 - xi_k^2) prod_{j != k} (1 + s_j xi_j) / 2^(d-1)) lie in the Lagrange space,
so they are evaluated as N_ser = N_lag T^T with T their values at the Lagrange nodes (exact).

Geometry (location, contact, pictures, ties) sees these cells through a split into simplices
over their own nodes, as for P2: quad9 into 4 sub-quads of 2 triangles, hexahedron27 into 8
sub-hexahedra of 6 Kuhn tetrahedra (``tensor.subdivide``, with its glue tetrahedra); quad8 into
4 corner triangles and its inner quad of midside nodes in 2; hexahedron20 into 8 corner
tetrahedra and its inner cuboctahedron of midside nodes in 14 tetrahedra (a cone from midside
node 8 over the faces that do not hold it). A boundary face is then 4 corner triangles and its
inner square in 2 (quad8), or 8 triangles (quad9). Where two hexahedra20 split their shared
square differently, a flat tetrahedron over it closes the split, as for Q1.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from tissuesim.mesh.cells import tensor

__all__ = [
    "CELL_TYPES",
    "NODES",
    "shape_functions",
    "full_facets",
    "facet_simplices",
    "subdivide",
    "reorient",
    "STIFFNESS_POINTS",
    "HEX_EDGES",
]

#: (dimension, nodes per cell) -> meshio's cell type name
CELL_TYPES = {(2, 8): "quad8", (2, 9): "quad9", (3, 20): "hexahedron20", (3, 27): "hexahedron27"}

#: Gauss points per direction of the stiffness: 3 (FEBio's and FElupe's rule for all four)
STIFFNESS_POINTS = 3


def _nodes(dim: int, lagrange: bool) -> np.ndarray:
    corners = tensor.SIGNS[dim]
    pairs = tensor.FACES[2] if dim == 2 else HEX_EDGES
    mids = 0.5 * (corners[pairs[:, 0]] + corners[pairs[:, 1]])
    rows = [corners, mids]
    if lagrange and dim == 2:
        rows.append(np.zeros((1, 2)))
    elif lagrange:
        faces = np.concatenate([-np.eye(3), np.eye(3)], axis=1).reshape(6, 3)  # -x, +x, -y ...
        rows += [faces, np.zeros((1, 3))]
    return np.concatenate(rows)


#: the corner pairs of a hexahedron's 12 midside nodes, in node order after its corners
HEX_EDGES = np.array(
    [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4], [0, 4], [1, 5], [2, 6], [3, 7]]
)

#: each node's reference coordinates (nv, d), in node order
NODES = {
    "quad8": _nodes(2, False),
    "quad9": _nodes(2, True),
    "hexahedron20": _nodes(3, False),
    "hexahedron27": _nodes(3, True),
}
_LAGRANGE = {"quad8": "quad9", "quad9": "quad9", "hexahedron20": "hexahedron27"}
_LAGRANGE["hexahedron27"] = "hexahedron27"


def cell_type(dim: int, nv: int) -> str:
    """meshio's name of a quadratic tensor cell of ``nv`` nodes in ``dim`` dimensions."""
    return CELL_TYPES[dim, nv]


def _lagrange(s: np.ndarray, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values and derivatives (q, nv, d) of the 1D quadratics L_s(xi_j) per node and axis."""
    t = xi[:, None, :]
    s = s[None]
    val = np.where(s == 0, 1.0 - t**2, 0.5 * t * (t + s))
    der = np.where(s == 0, -2.0 * t, t + 0.5 * s)
    return val, der


def _serendipity_values(s: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """The serendipity shape functions (q, nv) at points xi (q, d) (values only)."""
    d = xi.shape[1]
    t = xi[:, None, :] * s[None]  # (q, nv, d): s_j xi_j
    lin = np.where(s[None] == 0, 1.0, 0.5 * (1.0 + t)).prod(axis=2)
    corner = lin * (t.sum(axis=2) - d + 1)
    bubble = np.where(s[None] == 0, 1.0 - xi[:, None, :] ** 2, 1.0).prod(axis=2)
    return np.where((s != 0).all(axis=1)[None], corner, lin * bubble)


@cache
def _transfer(kind: str) -> np.ndarray:
    """T (nv, nl): the serendipity functions' values at the Lagrange nodes (identity for
    Lagrange cells)."""
    lag = NODES[_LAGRANGE[kind]]
    if kind == _LAGRANGE[kind]:
        return np.eye(len(lag))
    return _serendipity_values(NODES[kind], lag).T


def shape_functions(kind: str, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """N (q, nv) and dN/dxi (q, nv, d) of cell type ``kind`` at reference points xi (q, d)."""
    xi = np.atleast_2d(np.asarray(xi, dtype=float))
    s = NODES[_LAGRANGE[kind]]
    val, der = _lagrange(s, xi)
    N = val.prod(axis=2)
    dN = np.empty(val.shape)
    for j in range(xi.shape[1]):  # d directions, not a loop over points
        dN[:, :, j] = np.delete(val, j, axis=2).prod(axis=2) * der[:, :, j]
    T = _transfer(kind)
    return N @ T.T, np.einsum("qbj,ab->qaj", dN, T)


@cache
def local_facets(kind: str) -> np.ndarray:
    """Local nodes (2d, nf) of each facet, outward, in ``tensor.FACES`` order: the corners,
    then the midside nodes of the facet's edges (c0,c1) (c1,c2) ... and (quad9 faces) its
    centre; edges [a, b, mid] in 2D."""
    X = NODES[kind]
    d = X.shape[1]
    out = []
    for face in tensor.FACES[d]:
        c = X[face]
        want = [0.5 * (c[k] + c[(k + 1) % len(c)]) for k in range(len(c))] if d == 3 else []
        if d == 2:
            want = [0.5 * (c[0] + c[1])]
        if kind == "hexahedron27":
            want.append(c.mean(axis=0))
        ids = [int(np.flatnonzero((np.abs(X - w) < 1e-12).all(axis=1))[0]) for w in want]
        out.append([*face, *ids])
    return np.array(out)


def _facet_lookup(cells: np.ndarray, d: int, facets: np.ndarray) -> np.ndarray:
    """(k,) index into cells.ravel-of-faces (cell * 2d + local face) of each corner facet."""
    from tissuesim.mesh.queries.boundary import match_facets

    corner_faces = np.asarray(cells)[:, tensor.FACES[d]].reshape(-1, tensor.FACES[d].shape[1])
    return match_facets(corner_faces, np.asarray(facets, dtype=np.int64))


def full_facets(mesh, facets: np.ndarray) -> np.ndarray:
    """Facets given by their corners (k, 2) / (k, 4) with all their nodes (k, 3 / 8 / 9) in
    ``local_facets`` order, starting at the corner the cell's own facet starts at (the same
    vertex set, outward); rows of -1 where no cell has that facet."""
    d = mesh.dim
    facets = np.asarray(facets, dtype=np.int64).reshape(-1, 2 ** (d - 1))
    where = _facet_lookup(mesh.cells, d, facets)
    loc = local_facets(mesh.cell_type)
    cell, face = where // (2 * d), where % (2 * d)
    out = np.take_along_axis(mesh.cells[cell], loc[face], axis=1)
    out[where < 0] = -1
    return out


@cache
def facet_templates(kind: str) -> np.ndarray:
    """(2d, t, d) the simplices (triangles / segments) each facet shows in ``subdivide``,
    outward, in local cell nodes; found by splitting the reference cell itself."""
    from tissuesim.mesh.queries.boundary import boundary_facets

    X = NODES[kind]
    simplices, _ = subdivide(X, np.arange(len(X))[None])
    bf = boundary_facets(simplices)
    centre = X[bf].mean(axis=1)  # (b, d)
    loc = local_facets(kind)
    out = []
    for face in loc:  # 2d facets
        normal_axis = int(np.flatnonzero(np.ptp(X[face], axis=0) < 1e-12)[0])
        value = X[face[0], normal_axis]
        on = np.abs(centre[:, normal_axis] - value) < 1e-12
        out.append(bf[on])
    return np.array(out)


def facet_simplices(mesh, facets: np.ndarray) -> np.ndarray:
    """Boundary facets given by corners (k, 2^(d-1)) as the simplices (k t, d) the mesh's
    split shows them as (2 segments per edge, 6 or 8 triangles per face), outward."""
    d = mesh.dim
    where = _facet_lookup(mesh.cells, d, facets)
    if (where < 0).any():
        from tissuesim.errors import InputError

        bad = np.asarray(facets)[where < 0][0]
        raise InputError(
            f"facet {bad.tolist()} is not a facet of the {mesh.cell_type} cells of {mesh.source}; "
            "give boundary facets by their corner vertices (mesh.facet_sets, facets_where)"
        )
    tpl = facet_templates(mesh.cell_type)  # (2d, t, d)
    cell, face = where // (2 * d), where % (2 * d)
    local = tpl[face]  # (k, t, d)
    rows = mesh.cells[cell]  # (k, nv)
    return np.take_along_axis(rows[:, None, :], local, axis=2).reshape(-1, d)


# -- the split into simplices ------------------------------------------------------------------

# hexahedron20: the inner cuboctahedron's squares not through node 8, with their diagonals
# (first, third) chosen so that translated neighbours split their shared square alike
_H20_CONE_SQUARES = np.array(
    [[10, 19, 14, 18], [12, 13, 14, 15], [11, 16, 15, 19], [9, 18, 13, 17]]
)


def _local_split(kind: str) -> np.ndarray:
    """Simplices of one cell in local node numbers (before orientation fixes)."""
    X = NODES[kind]
    d = X.shape[1]
    if kind in ("quad9", "hexahedron27"):
        # a sub-cell of corner c spans [min(c, 0), max(c, 0)] per axis, its Q1 corners at
        # (lo + hi)/2 + s (hi - lo)/2 for the Q1 signs s
        lo = np.minimum(tensor.SIGNS[d], 0.0)
        hi = np.maximum(tensor.SIGNS[d], 0.0)
        corners = (lo + hi)[:, None, :] / 2 + tensor.SIGNS[d][None] * (hi - lo)[:, None, :] / 2
        ids = _ids(X, corners.reshape(-1, d)).reshape(len(lo), -1)
        return ids  # sub-cells (2^d, 2^d): split further by ``tensor.subdivide``
    corner_simplices = []
    for a, c in enumerate(tensor.SIGNS[d]):
        nbrs = [c * np.where(np.arange(d) == j, 0.0, 1.0) for j in range(d)]
        corner_simplices.append([a, *_ids(X, np.array(nbrs))])
    if d == 2:
        return np.array([*corner_simplices, [4, 5, 6], [4, 6, 7]])
    cone = [[8, *row[1:]] for row in corner_simplices[2:]]
    for sq in _H20_CONE_SQUARES:
        cone += [[8, sq[0], sq[1], sq[2]], [8, sq[0], sq[2], sq[3]]]
    return np.array([*corner_simplices, *cone])


def _ids(X: np.ndarray, want: np.ndarray) -> np.ndarray:
    """Local ids of the nodes at reference coordinates ``want`` (k, d)."""
    match = (np.abs(X[None] - want[:, None]) < 1e-12).all(axis=2)
    return match.argmax(axis=1)


def subdivide(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Simplices (s, d + 1) over the nodes of quadratic tensor cells (m, nv) and the parent
    cell of each (s,), positively oriented at the rest points (flat glue tetrahedra aside)."""
    d = points.shape[1]
    cells = np.asarray(cells, dtype=np.int64)
    kind = CELL_TYPES[d, cells.shape[1]]
    split = _local_split(kind)
    if kind in ("quad9", "hexahedron27"):
        subcells = cells[:, split].reshape(-1, 2**d)
        simplices, sub_parent = tensor.subdivide(points, subcells)
        return simplices, sub_parent // 2**d
    simplices = cells[:, split].reshape(-1, d + 1)
    parent = np.repeat(np.arange(cells.shape[0]), split.shape[0])
    if d == 3:
        glue, owner = _glue_squares(cells)
        if len(glue):
            simplices = np.concatenate([simplices, glue])
            parent = np.concatenate([parent, owner])
    return tensor.positively_oriented(points, simplices), parent


@cache
def _h20_square_diagonals() -> tuple[np.ndarray, np.ndarray]:
    """Per face of a hexahedron20 (``tensor.FACES`` order): its inner square's 4 nodes and the
    ends of the diagonal the local split uses."""
    split = _local_split("hexahedron20")
    pairs = [(t[i], t[j]) for t in split for i in range(4) for j in range(i)]
    edges = {tuple(sorted(e)) for e in pairs}
    loc = local_facets("hexahedron20")[:, 4:]  # (6, 4) the squares
    ends = []
    for sq in loc:
        first = (sq[0], sq[2]) if tuple(sorted((sq[0], sq[2]))) in edges else (sq[1], sq[3])
        ends.append(first)
    return loc, np.array(ends)


def _glue_squares(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Flat tetrahedra (g, 4) over interior squares two hexahedra20 split differently, and one
    owning cell each (g,)."""
    squares, ends = _h20_square_diagonals()
    sq = cells[:, squares].reshape(-1, 4)  # (m*6, 4)
    diag = cells[:, ends].reshape(-1, 2)
    keys = np.sort(sq, axis=1)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    interior = np.flatnonzero(counts[inverse] == 2)
    order = np.argsort(inverse[interior], kind="stable")
    pairs = interior[order].reshape(-1, 2)
    low = diag.min(axis=1)
    differ = low[pairs[:, 0]] != low[pairs[:, 1]]
    if not differ.any():
        return np.zeros((0, 4), dtype=np.int64), np.zeros(0, dtype=np.int64)
    return sq[pairs[differ, 0]].astype(np.int64), pairs[differ, 0] // 6


def reorient(kind: str) -> list[int]:
    """The node permutation that mirrors a cell (quad: reverse its corners; hexahedron: swap
    top and bottom), midside and face nodes following their edges and faces."""
    X = NODES[kind]
    d = X.shape[1]
    Y = X.copy()
    if d == 2:
        Y[:, [0, 1]] = X[:, [1, 0]]  # mirror about the diagonal: reverses the corners
    else:
        Y[:, 2] = -X[:, 2]
    return _ids(X, Y).tolist()


def check_shared_nodes(cells: np.ndarray, d: int, table, source: str) -> None:
    """MeshError where two cells share a facet's corners but not its midside (or centre)
    nodes: the cells would not be connected there. ``table`` is ``tensor.face_table``'s."""
    from tissuesim.errors import MeshError

    _, _, inverse, counts = table
    kind = CELL_TYPES[d, cells.shape[1]]
    full = np.sort(cells[:, local_facets(kind)].reshape(-1, local_facets(kind).shape[1]), axis=1)
    interior = np.flatnonzero(counts[inverse] == 2)
    order = np.argsort(inverse[interior], kind="stable")
    pairs = interior[order].reshape(-1, 2)
    differ = (full[pairs[:, 0]] != full[pairs[:, 1]]).any(axis=1)
    if differ.any():
        a, b = pairs[np.flatnonzero(differ)[0]]
        raise MeshError(
            f"{source}: {kind} cells {a // (2 * d)} and {b // (2 * d)} share the corners of a "
            f"facet but not its other nodes ({full[a].tolist()} against {full[b].tolist()}; "
            f"{int(differ.sum())} such facets): give the shared midside nodes once (VTK's node "
            "order), or remesh"
        )
