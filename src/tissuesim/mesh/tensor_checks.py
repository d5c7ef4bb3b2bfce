"""Checks of Q1 cells (quadrilaterals, hexahedra), called by ``validate_mesh``.

A Q1 cell is usable when its rest map has a positive Jacobian at every Gauss point of the
stiffness and at every node: a negative one somewhere means the cell is folded or its nodes are
numbered in a twisted order, a tiny one that it is degenerate. A cell whose Jacobian is negative
at *every* one of those points is a mirrored numbering (e.g. a hexahedron whose bottom face runs
clockwise seen from inside) and is reoriented, as simplices are.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.tensor import SIGNS, gauss_rule, rest_jacobians, shape_functions

__all__ = ["tensor_jacobians", "check_tensor_cells", "tensor_quality", "REORIENT"]

#: a node permutation that mirrors a Q1 cell (quad: reverse; hexahedron: swap top and bottom)
REORIENT = {2: [0, 3, 2, 1], 3: [4, 5, 6, 7, 0, 1, 2, 3]}

#: a Jacobian below this fraction of the cell's mean |det J| counts as degenerate
DEGENERATE = 1e-8


def tensor_jacobians(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """det J (m, q) of the rest map at the 2^d Gauss points and the 2^d nodes of each cell."""
    d = points.shape[1]
    xi = np.concatenate([gauss_rule(d, 2)[0], SIGNS[d]])
    _, dN = shape_functions(d, xi)
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
        kind = "quadrilateral" if d == 2 else "hexahedron"
        raise MeshError(
            f"{source}: {kind} {e} {cells[e].tolist()} is inverted or degenerate (the Jacobian "
            f"of its rest map runs from {detJ[e].min():.3g} to {detJ[e].max():.3g} over its "
            f"Gauss points and nodes; {int(bad.sum())} such cells): check the node order "
            "(VTK's: the bottom face counter-clockwise seen from above, then the top face) or "
            "remesh"
        )
    return np.flatnonzero(mirrored)


def tensor_quality(points: np.ndarray, cells: np.ndarray):
    """(volumes (m,), edge lengths (m, 4 or 12), scaled Jacobian (m,)) of Q1 cells: the volume
    by 2^d Gauss points (exact), the quality min over the nodes of det J / prod |dX/dxi_j|
    (1 for a rectangle / box, 0 for a degenerate corner)."""
    from tissuesim.mesh.tensor import FACES

    d = points.shape[1]
    xi, w = gauss_rule(d, 2)
    _, dN = shape_functions(d, xi)
    volumes = np.linalg.det(rest_jacobians(points, cells, dN)) @ w
    _, dNc = shape_functions(d, SIGNS[d])
    Jc = rest_jacobians(points, cells, dNc)  # (m, nv, d, d)
    scaled = np.linalg.det(Jc) / np.linalg.norm(Jc, axis=2).prod(axis=2)
    faces = FACES[d]
    pairs = np.unique(
        np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], -1).reshape(-1, 2), axis=1), axis=0
    )
    x = points[cells]
    edges = np.linalg.norm(x[:, pairs[:, 1]] - x[:, pairs[:, 0]], axis=2)
    return volumes, edges, scaled.min(axis=1)
