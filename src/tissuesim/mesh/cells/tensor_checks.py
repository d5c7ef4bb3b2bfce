"""Checks of Q1 and quadratic quadrilaterals and hexahedra and of wedges, called by
``validate_mesh``.

A Q1 cell (a quadratic one with its 3^d Gauss points, a wedge with its 6) is usable when its
rest map has a
positive Jacobian at every Gauss point of the stiffness and at every node: a negative one
somewhere means the cell is folded or its nodes are numbered in a twisted order, a tiny one
that it is degenerate. A cell whose Jacobian is negative
at *every* one of those points is a mirrored numbering (e.g. a hexahedron whose bottom face runs
clockwise seen from inside, a wedge in VTK's order) and is reoriented, as simplices are.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.cells.tensor import SIGNS, gauss_rule, rest_jacobians, shape_functions

__all__ = [
    "tensor_jacobians",
    "check_tensor_cells",
    "tensor_quality",
    "REORIENT",
    "reorient_permutation",
]

#: a node permutation that mirrors a Q1 cell (quad: reverse; hexahedron: swap top and bottom)
REORIENT = {2: [0, 3, 2, 1], 3: [4, 5, 6, 7, 0, 1, 2, 3]}

#: a Jacobian below this fraction of the cell's mean |det J| counts as degenerate
DEGENERATE = 1e-8


def _basis(d: int, nv: int):
    """(shape functions xi -> (N, dN), the node coordinates, the stiffness rule (points,
    weights)) of the cell of nv nodes: Q1, quadratic (``tensor_quadratic``) or a wedge."""
    if nv == 2**d:
        return (lambda xi: shape_functions(d, xi)), SIGNS[d], gauss_rule(d, 2)
    if (d, nv) == (3, 6):
        from tissuesim.mesh.cells import wedge

        return wedge.shape_functions, wedge.NODES, wedge.stiffness_rule()
    from tissuesim.mesh.cells import tensor_quadratic as tq

    kind = tq.CELL_TYPES[d, nv]
    rule = gauss_rule(d, tq.STIFFNESS_POINTS)
    return (lambda xi: tq.shape_functions(kind, xi)), tq.NODES[kind], rule


#: each cell's name and node order in words, for the refusal of an inverted one
_KINDS = {
    (2, 4): ("quadrilateral", "VTK's: counter-clockwise"),
    (3, 8): (
        "hexahedron",
        "VTK's: the bottom face counter-clockwise seen from above, then the top face",
    ),
    (3, 6): (
        "wedge",
        "Gmsh's / FEBio's: the bottom triangle counter-clockwise seen from the top, then the "
        "top triangle above it",
    ),
}


def reorient_permutation(d: int, nv: int) -> list[int]:
    """The node permutation that mirrors a cell of nv nodes (``REORIENT`` for Q1)."""
    if nv == 2**d:
        return REORIENT[d]
    if (d, nv) == (3, 6):
        from tissuesim.mesh.cells.wedge import REORIENT as WEDGE

        return WEDGE
    from tissuesim.mesh.cells import tensor_quadratic as tq

    return tq.reorient(tq.CELL_TYPES[d, nv])


def tensor_jacobians(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """det J (m, q) of the rest map at the stiffness's Gauss points and at the nodes of each
    cell."""
    d = points.shape[1]
    shape, nodes, (points_q, _) = _basis(d, cells.shape[1])
    xi = np.concatenate([points_q, nodes])
    _, dN = shape(xi)
    return np.linalg.det(rest_jacobians(points, cells, dN))


def check_tensor_cells(points: np.ndarray, cells: np.ndarray, source: str) -> np.ndarray:
    """Cells with every Jacobian positive; mirrored cells reoriented (returns the cells and
    warns through the caller); MeshError for a folded, twisted or degenerate cell."""
    d = points.shape[1]
    detJ = tensor_jacobians(points, cells)
    scale = np.abs(detJ).mean(axis=1)
    mirrored = (detJ < -DEGENERATE * scale[:, None]).all(axis=1)
    ok = (detJ > DEGENERATE * scale[:, None]).all(axis=1)
    bad = ~(ok | mirrored)
    if bad.any():
        e = int(np.flatnonzero(bad)[0])
        nv = cells.shape[1]
        kind, order = _KINDS.get((d, nv), _KINDS[d, 2**d])
        kind = kind if (d, nv) in _KINDS else f"{nv}-node {kind}"
        raise MeshError(
            f"{source}: {kind} {e} {cells[e].tolist()} is inverted or degenerate (the Jacobian "
            f"of its rest map runs from {detJ[e].min():.3g} to {detJ[e].max():.3g} over its "
            f"Gauss points and nodes; {int(bad.sum())} such cells): check the node order "
            f"({order}) or remesh"
        )
    return np.flatnonzero(mirrored)


def tensor_quality(points: np.ndarray, cells: np.ndarray):
    """(volumes (m,), edge lengths (m, 4, 12 or 9), scaled Jacobian (m,)) of Q1, quadratic or
    wedge cells: the volume by the stiffness's Gauss points (exact for Q1 and wedges), the
    quality min over the nodes of det J / prod |dX/dxi_j| (1 for a rectangle / box and a
    right prism over a right isosceles triangle, 0 for a degenerate corner); the edges are
    corner to corner."""
    from tissuesim.mesh.cells.tensor import local_faces

    d = points.shape[1]
    shape, nodes, (xi, w) = _basis(d, cells.shape[1])
    _, dN = shape(xi)
    volumes = np.linalg.det(rest_jacobians(points, cells, dN)) @ w
    _, dNc = shape(nodes)
    Jc = rest_jacobians(points, cells, dNc)  # (m, nv, d, d)
    scaled = np.linalg.det(Jc) / np.linalg.norm(Jc, axis=2).prod(axis=2)
    faces = local_faces(d, cells.shape[1])
    pairs = np.unique(
        np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], -1).reshape(-1, 2), axis=1), axis=0
    )
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]  # a wedge's triangles repeat a corner
    x = points[cells]
    edges = np.linalg.norm(x[:, pairs[:, 1]] - x[:, pairs[:, 0]], axis=2)
    return volumes, edges, scaled.min(axis=1)
