"""Linear wedges (6-node prisms): node order, shape functions, integration rules, facets, and
the tetrahedra geometry uses.

Node order is meshio's and Gmsh's ``wedge`` (Gmsh's prism), which is also FEBio's ``penta6``;
on the reference wedge {r, s >= 0, r + s <= 1} x [-1, 1] (``NODES``):

    0 (0, 0, -1)   1 (1, 0, -1)   2 (0, 1, -1)   3 (0, 0, 1)   4 (1, 0, 1)   5 (0, 1, 1)

the bottom triangle counter-clockwise seen from the top, then the top triangle above it. VTK's
VTK_WEDGE (13) runs the bottom triangle the other way round (its normal points away from the
top); meshio swaps nodes 1 <-> 2 and 4 <-> 5 when it writes and reads VTU / VTK files, so cells
read through meshio are in the order above, and a cell given as arrays in VTK's order is a
mirrored wedge, reoriented with a warning like a mirrored hexahedron (``REORIENT``).

Shape functions N_a = L_i(r, s) (1 -+ t) / 2, L = (1 - r - s, r, s) (FEBio's
``FEPenta6::shape_fnc``): linear on the triangles, linear along the axis. The stiffness is
integrated by FEBio's FEPenta6G6 rule (``stiffness_rule``): the 3-point triangle rule
(1/6, 1/6), (2/3, 1/6), (1/6, 2/3), weights 1/6, times 2 Gauss points t = -+1/sqrt(3), exact
for a right prism's linear stiffness. The mass uses a rule exact for N_a N_b det J of any
wedge (of degree 3 on the triangle and 4 along the axis: ``mass_rule``).

Facets. A wedge has 2 triangles and 3 quadrilaterals. Every facet of a wedge mesh is a row of
4 nodes, so facet sets, selections and tractions are (k, 4) arrays as for hexahedra: a
triangle repeats its last corner, (a, b, c, c), the quadrilateral collapsed at its last edge
(``tensor.WEDGE_FACES``, outward), its corners rotated so that c is the largest of the three
(one row, hence one sorted key, per triangle: neighbours find their shared face). The
bilinear map of a collapsed quadrilateral is the triangle's linear map in Duffy's
coordinates, so the quad rule integrates a traction on it exactly as the linear triangle's
consistent load (``energies/loads.py`` needs no case of its own), its normal
(x1 - x0) x (x3 - x0) is the triangle's, and vertex ids index points safely (no sentinel).
``as_facets`` brings triangles (k, 3) and collapsed rows written otherwise into that form;
``facet_triangles`` turns facets into triangles for contact and pictures.

Geometry (location, contact, pictures, ties) sees each wedge as 3 tetrahedra over its nodes
(``subdivide``): each quadrilateral face is split along the diagonal through its smallest
global node, so neighbours split a shared face alike and the split conforms without glue
tetrahedra; this rule never gives the one cyclic choice of diagonals that a prism cannot be
split along (Dompierre, Labbe, Vallet & Camarero 1999). A boundary quadrilateral shows as the
same 2 triangles in ``facet_triangles``.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from tissuesim.mesh.cells.reference import quadrature
from tissuesim.mesh.cells.tensor import WEDGE_FACES, collapsed_triangles, positively_oriented

__all__ = [
    "NODES",
    "FACES",
    "REORIENT",
    "shape_functions",
    "stiffness_rule",
    "mass_rule",
    "as_facets",
    "is_triangle",
    "facet_triangles",
    "subdivide",
    "from_hexahedra",
]

#: each node's reference coordinates (r, s, t), in node order
NODES = np.array([[0, 0, -1], [1, 0, -1], [0, 1, -1], [0, 0, 1], [1, 0, 1], [0, 1, 1]], dtype=float)
#: the local nodes of each facet, outward for a positive wedge: bottom, top (triangles, their
#: last corner repeated), then the sides s = 0, r + s = 1, r = 0
FACES = WEDGE_FACES
#: the node permutation that mirrors a wedge (its triangles reversed): VTK's order <-> this one
REORIENT = [0, 2, 1, 3, 5, 4]

#: the orientation-preserving renumberings of a wedge: _SYMMETRY[k] makes its node k node 0
_SYMMETRY = np.array(
    [
        [0, 1, 2, 3, 4, 5],
        [1, 2, 0, 4, 5, 3],
        [2, 0, 1, 5, 3, 4],
        [3, 5, 4, 0, 2, 1],
        [4, 3, 5, 1, 0, 2],
        [5, 4, 3, 2, 1, 0],
    ]
)
#: the 3 tetrahedra of a wedge whose node 0 is its smallest, with the side face 1-2-5-4 split
#: along 1-5 (first) or 2-4 (second); the faces through node 0 are split through it
_SPLITS = np.array(
    [
        [[0, 1, 2, 5], [0, 1, 5, 4], [0, 4, 5, 3]],
        [[0, 1, 2, 4], [0, 4, 2, 5], [0, 4, 5, 3]],
    ]
)


def shape_functions(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """N (q, 6) and dN/dxi (q, 6, 3) at reference points xi (q, 3) = (r, s, t)."""
    xi = np.atleast_2d(np.asarray(xi, dtype=float))
    r, s, t = xi[:, 0], xi[:, 1], xi[:, 2]
    L = np.stack([1.0 - r - s, r, s], axis=1)  # (q, 3)
    dL = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])  # dL_i / d(r, s)
    low, high = 0.5 * (1.0 - t), 0.5 * (1.0 + t)
    N = np.concatenate([L * low[:, None], L * high[:, None]], axis=1)
    dN = np.empty((xi.shape[0], 6, 3))
    dN[:, :3, :2] = dL[None] * low[:, None, None]
    dN[:, 3:, :2] = dL[None] * high[:, None, None]
    dN[:, :3, 2] = -0.5 * L
    dN[:, 3:, 2] = 0.5 * L
    return N, dN


def _product(triangle: tuple[np.ndarray, np.ndarray], n: int) -> tuple[np.ndarray, np.ndarray]:
    """The triangle rule times n Gauss-Legendre points along t, the triangle's points fastest."""
    p, w = triangle
    t, wt = np.polynomial.legendre.leggauss(n)
    pts = np.concatenate([np.column_stack([p, np.full(len(p), tk)]) for tk in t])
    return pts, np.concatenate([w * wk for wk in wt])


@cache
def stiffness_rule() -> tuple[np.ndarray, np.ndarray]:
    """FEBio's FEPenta6G6 rule: points (6, 3) and weights (6,) (sum 1, the reference volume),
    in FEBio's order (the triangle's 3 points at t = -1/sqrt 3, then at +1/sqrt 3)."""
    return _product(quadrature(2, 2), 2)


@cache
def mass_rule() -> tuple[np.ndarray, np.ndarray]:
    """A rule exact for N_a N_b det J on any wedge (degree 3 on the triangle, 4 along t)."""
    return _product(quadrature(2, 3), 3)


def as_facets(facets) -> np.ndarray:
    """Facets of a wedge mesh as rows of 4 nodes (k, 4) int64, each triangle in the one form
    the mesh's facet tables use (``tensor.collapsed_triangles``: (a, b, c, c), the same
    orientation, c its largest node): triangles (k, 3), and 4-node rows with one pair of
    cyclically adjacent equal nodes ((a, a, b, c), (a, b, b, c), (c, a, b, c), ...). Other
    rows are returned as they are."""
    f = np.asarray(facets, dtype=np.int64)
    if f.ndim != 2 or f.shape[1] not in (3, 4) or not len(f):
        return f.reshape(0, 4) if f.ndim == 2 and not len(f) else f
    if f.shape[1] == 3:
        return collapsed_triangles(f)
    equal = f == np.roll(f, -1, axis=1)  # node j equals node j + 1 (cyclically)
    collapsed = equal.sum(axis=1) == 1
    j = np.argmax(equal[collapsed], axis=1)  # the other three follow j + 1 in cyclic order
    corners = np.take_along_axis(f[collapsed], (j[:, None] + np.array([1, 2, 3])) % 4, axis=1)
    out = f.copy()
    out[collapsed] = collapsed_triangles(corners)
    return out


def is_triangle(facets: np.ndarray) -> np.ndarray:
    """(k,) True for the triangles among facets (k, 4) in ``as_facets``' form."""
    return facets[:, 2] == facets[:, 3]


def facet_triangles(facets: np.ndarray) -> np.ndarray:
    """Facets (k, 4) of a wedge mesh as triangles (t, 3), outward as the facets, in facet
    order: a triangle as itself, a quadrilateral as 2 split along the diagonal through its
    smallest node (the split ``subdivide`` gives its boundary)."""
    f = as_facets(facets)
    if f.ndim != 2 or f.shape[1] != 4:
        raise ValueError(f"wedge facets must be (k, 3) or (k, 4) vertex indices, not {f.shape}")
    quad = ~is_triangle(f)
    start = np.where(quad, np.argmin(f, axis=1), 0)  # a triangle keeps its order
    f = np.take_along_axis(f, (start[:, None] + np.arange(4)) % 4, axis=1)
    tri = f[:, [[0, 1, 2], [0, 2, 3]]].reshape(-1, 3)
    keep = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])
    return np.ascontiguousarray(tri[keep], dtype=np.int64)


def subdivide(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedra (3m, 4) over the wedges' nodes, positively oriented, and the wedge each
    belongs to (3m,): each wedge renumbered so that its smallest node is node 0, then split
    by the diagonal its side face 1-2-5-4 takes through that face's smallest node."""
    cells = np.asarray(cells, dtype=np.int64)
    m = cells.shape[0]
    c = np.take_along_axis(cells, _SYMMETRY[np.argmin(cells, axis=1)], axis=1)
    second = np.minimum(c[:, 2], c[:, 4]) < np.minimum(c[:, 1], c[:, 5])
    local = _SPLITS[second.astype(np.int64)]  # (m, 3, 4)
    tets = np.take_along_axis(c[:, None, :], local, axis=2).reshape(-1, 4)
    return positively_oriented(points, tets), np.repeat(np.arange(m), 3)


def from_hexahedra(hexes: np.ndarray, across: np.ndarray) -> np.ndarray:
    """Each hexahedron (m, 8) (VTK's order) cut into 2 wedges (2m, 6) by the plane through a
    diagonal of its bottom face and the edges above it: the 0-2 diagonal, or the 1-3 one where
    ``across`` (m,) is True. The wedges' axes run from the bottom face to the top one; positive
    for a positive hexahedron whose vertical edges are straight."""
    along = np.array([[0, 1, 2, 4, 5, 6], [0, 2, 3, 4, 6, 7]])
    other = np.array([[0, 1, 3, 4, 5, 7], [1, 2, 3, 5, 6, 7]])
    local = np.where(np.asarray(across, dtype=bool)[:, None, None], other[None], along[None])
    return np.take_along_axis(np.asarray(hexes)[:, None, :], local, axis=2).reshape(-1, 6)
