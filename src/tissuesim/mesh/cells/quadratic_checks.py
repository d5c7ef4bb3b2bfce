"""Checks of quadratic cells (called by ``validate_mesh`` after the corner checks).

A midside node must be shared by every cell that has its edge and by no other edge, must not be
a corner, and must lie near its edge: within a quarter of the edge length from the edge's
midpoint (the classical bound that keeps a curved edge's map monotone). The rest map of every
cell must keep a positive Jacobian at its quadrature points and corners; otherwise the element
is folded and its stiffness is meaningless.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.cells.quadratic import EDGES
from tissuesim.mesh.cells.reference import (
    quadrature,
    rest_jacobians,
    shape_functions,
    stiffness_degree,
)

__all__ = ["check_quadratic", "MIDSIDE_TOLERANCE"]

#: a midside node may sit this fraction of its edge's length away from the edge's midpoint
MIDSIDE_TOLERANCE = 0.25


def check_quadratic(points: np.ndarray, cells: np.ndarray, source: str) -> None:
    d = points.shape[1]
    corners, mids = cells[:, : d + 1], cells[:, d + 1 :]
    shared = np.intersect1d(corners.ravel(), mids.ravel())
    if shared.size:
        v = int(shared[0])
        e = int(np.flatnonzero((mids == v).any(axis=1))[0])
        raise MeshError(
            f"{source}: vertex {v} is a corner of one element and a midside node of element {e} "
            f"({shared.size} such vertices); check the node order (corners first, then the "
            "midpoints of edges 01 12 20 (03 13 23), as VTK and meshio write them)"
        )
    pairs = np.sort(corners[:, EDGES[d]], axis=2).reshape(-1, 2)
    flat = mids.reshape(-1)
    _, edge_id = np.unique(pairs, axis=0, return_inverse=True)
    edge_id = edge_id.ravel()
    # every edge one midside node, every midside node one edge
    for a, b, what in ((edge_id, flat, "edge"), (flat, edge_id, "midside node")):
        order = np.lexsort((b, a))
        sa, sb = a[order], b[order]
        clash = (sa[1:] == sa[:-1]) & (sb[1:] != sb[:-1])
        if clash.any():
            k = order[int(np.flatnonzero(clash)[0]) + 1]
            e, j = divmod(int(k), mids.shape[1])
            raise MeshError(
                f"{source}: the {what} of element {e}'s midside node {int(flat[k])} (edge "
                f"{pairs[k].tolist()}) is shared with a different "
                f"{'midside node' if what == 'edge' else 'edge'} in another element: the "
                "quadratic mesh is not conforming; export it again from the mesher"
            )
    xa, xb, xm = points[pairs[:, 0]], points[pairs[:, 1]], points[flat]
    length = np.linalg.norm(xb - xa, axis=1)
    off = np.linalg.norm(xm - 0.5 * (xa + xb), axis=1)
    far = off > MIDSIDE_TOLERANCE * length
    if far.any():
        k = int(np.flatnonzero(far)[0])
        e = k // mids.shape[1]
        raise MeshError(
            f"{source}: element {e}'s midside node {int(flat[k])} lies {off[k]:.3g} from the "
            f"midpoint of its edge {pairs[k].tolist()} (length {length[k]:.3g}; at most "
            f"{MIDSIDE_TOLERANCE:g} of it is allowed; {int(far.sum())} such nodes): the node "
            "does not belong to that edge; check the node order or the mesher's curving"
        )
    xi_q, _ = quadrature(d, stiffness_degree(2))
    xi = np.concatenate([xi_q, np.concatenate([np.zeros((1, d)), np.eye(d)])])
    _, dN = shape_functions(d, 2, xi)
    detJ = np.linalg.det(rest_jacobians(points, cells, dN))  # (m, q + d + 1)
    scale = np.linalg.det(rest_jacobians(points, corners, shape_functions(d, 1, xi[:1])[1]))
    folded = (detJ <= 1e-12 * np.abs(scale)[:, None]).any(axis=1)
    if folded.any():
        e = int(np.flatnonzero(folded)[0])
        raise MeshError(
            f"{source}: quadratic element {e} {cells[e].tolist()} is folded (its Jacobian "
            f"{detJ[e].min():.3g} is not positive at a quadrature point or corner; "
            f"{int(folded.sum())} such elements): move its midside nodes towards their edges' "
            "midpoints or remesh with less curving"
        )
