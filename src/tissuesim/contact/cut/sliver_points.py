"""Contact points for the pieces of a cut body too thin for a contact surface.

A cut face's contact surface lies GAP dhat inside its side (``cut_surface.py``), so a piece
thinner than twice that (a sliver: a grazing cut, two cuts close together) has its region
shaved away entirely and no contact surface. Such a piece gets contact points instead: the
corners of each of its element parts (the vertices of the part's region,
``plane_split.region_vertices``: on the piece's outer faces where it meets what it lands on),
those on a cut face lifted into the part (``LIFT``), interpolated from the part's nodes like
a surface point, and thinned to one per MERGE dhat (points of one piece within each other's
barrier would push the piece apart). The points are vertices of the collision mesh without
edges or faces: they meet other bodies' and obstacles' faces, edges and points (and their own
body's), so the piece rests on what it falls onto, though an edge narrower than the points'
spacing (about an element) can pass between them.

IPC's area weighting gives a vertex without faces an area of 1 (m^2); ``weigh_points`` sets
each such collision's weight to the point's own area instead: its share of the piece's cut
area (each part's largest section by a cut: the face it would touch with), so the piece's
barrier is as stiff as a surface of that area. That is a
Python loop over the collisions while a body has such points: 12 ms for 36,581 collisions
against 27-31 ms for building them (``benchmarks/sliver_weights.py``, a 2-core machine).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["bare_pieces", "sliver_points", "weigh_points"]

#: points of one piece are kept at least MERGE dhat apart at rest
MERGE = 1.0
#: points are lifted at least LIFT dhat off the cut faces, into their part (1 - (GAP -
#: SNAP_OUT) of cut_surface.py: then the other side's faces are a dhat away), or half the
#: part's depth where it is thinner
LIFT = 0.4


def bare_pieces(mesh, W: sp.spmatrix, tri: np.ndarray) -> np.ndarray:
    """Which cells (m,) belong to a piece of the cut body with no contact surface: a
    connected component of its cells (sharing nodes) none of whose nodes a surface vertex is
    interpolated from."""
    from tissuesim.mesh.cutting.virtual_nodes import node_pieces

    nodes = sp.csr_matrix(W)[np.unique(tri)].indices  # the nodes a surface vertex uses
    used = np.zeros(mesh.n_points, dtype=bool)
    used[nodes] = True
    if used[mesh.cells].any(axis=1).all():  # a bare piece's cells use none: no such piece
        return np.zeros(len(mesh.cells), dtype=bool)
    label = node_pieces(mesh.cells, mesh.n_points)
    held = np.zeros(label.max() + 1, dtype=bool)
    held[label[nodes]] = True
    return ~held[label[mesh.cells[:, 0]]]


def sliver_points(
    mesh, W: sp.spmatrix, tri: np.ndarray, dhat: float
) -> tuple[sp.csr_matrix, np.ndarray] | None:
    """(weights (p, n_points) of each contact point over the body's nodes, its area (p,)) for
    the pieces without a contact surface (``bare_pieces``), or None when every piece has one."""
    from tissuesim.contact.cut.surface import level_stack
    from tissuesim.mesh.cutting.plane_split import region_vertices, section_measures
    from tissuesim.mesh.cutting.virtual_nodes import node_pieces

    bare = np.flatnonzero(bare_pieces(mesh, W, tri))
    if bare.size == 0:
        return None
    cells = mesh.cells[bare]
    levels = level_stack(mesh)[bare]  # (b, C, k)
    rows, lam = [], []
    for b, vertices in enumerate(region_vertices(levels)):
        if len(vertices):
            rows.append(np.full(len(vertices), b))
            lam.append(_lifted(vertices, levels[b], LIFT * dhat))
    if not rows:
        return None
    rows, lam = np.concatenate(rows), np.concatenate(lam)
    P = sp.csr_matrix(
        (lam.ravel(), (np.repeat(np.arange(len(rows)), cells.shape[1]), cells[rows].ravel())),
        shape=(len(rows), mesh.n_points),
    )
    label = node_pieces(mesh.cells, mesh.n_points)[cells[:, 0]]  # each bare cell's piece
    piece = label[rows]
    keep = _thinned(P @ mesh.points, piece, MERGE * dhat)
    # each piece's cut area (each part's largest section by one of its levels), shared
    # evenly by its points
    area = np.zeros(len(bare))
    for c in range(levels.shape[1]):
        finite = np.isfinite(levels[:, c]).all(axis=1)
        if finite.any():
            section = section_measures(mesh.points, cells[finite], levels[finite, c])
            area[finite] = np.maximum(area[finite], section)
    whole = area == 0.0  # a whole cell in a sliver (elements thinner than 2 dhat)
    if whole.any():
        area[whole] = _measures(mesh.points[cells[whole]]) ** ((mesh.dim - 1) / mesh.dim)
    total = np.bincount(label, weights=area, minlength=label.max() + 1)
    count = np.bincount(piece[keep], minlength=label.max() + 1)
    return sp.csr_matrix(P[keep]), total[piece[keep]] / count[piece[keep]]


def _lifted(vertices: np.ndarray, levels: np.ndarray, lift: float) -> np.ndarray:
    """A part's region vertices (p, k: barycentric) moved towards its deepest one (the
    highest least level) until their least level is at least ``lift`` or half the deepest's:
    a point on a cut face would sit within the barrier of the other side's face (GAP -
    SNAP_OUT dhat off the plane) and push the pieces apart at rest."""
    finite = np.isfinite(levels).all(axis=1)
    if not finite.any():
        return vertices
    least = (vertices @ levels[finite].T).min(axis=1)
    deep = int(np.argmax(least))
    target = min(lift, 0.5 * least[deep])
    span = least[deep] - least
    s = np.where(span > 0.0, np.clip((target - least) / np.where(span > 0, span, 1.0), 0, 1), 0)
    return vertices + s[:, None] * (vertices[deep] - vertices)


def _thinned(points: np.ndarray, piece: np.ndarray, spacing: float) -> np.ndarray:
    """Indices of the points kept, in order, when each drops the later points of its piece
    closer than ``spacing`` to it: no two kept points of a piece within each other's barrier."""
    from scipy.spatial import cKDTree

    if spacing <= 0.0:
        return np.arange(len(points))
    tree = cKDTree(points)
    dropped = np.zeros(len(points), dtype=bool)
    keep = []
    for i in range(len(points)):
        if dropped[i]:
            continue
        keep.append(i)
        near = np.asarray(tree.query_ball_point(points[i], spacing), dtype=int)
        dropped[near[piece[near] == piece[i]]] = True
    return np.array(keep, dtype=int)


def weigh_points(collisions, area: np.ndarray) -> None:
    """Scale the weight of each collision of ``collisions`` (ipctk NormalCollisions, area
    weighted) that involves a contact point by the point's area (``area`` per collision-mesh
    vertex, NaN for the vertices of surfaces): ipctk weighs such a vertex as 1 m^2. A point
    has no edges or faces, so it is the vertex of a vertex-face or vertex-edge collision, or
    either vertex of a vertex-vertex one."""
    points = {int(i): float(area[i]) for i in np.flatnonzero(np.isfinite(area))}
    for group in (collisions.fv_collisions, collisions.ev_collisions):
        for collision in group:
            a = points.get(collision.vertex_id)
            if a is not None:
                collision.weight = collision.weight * a
    for collision in collisions.vv_collisions:
        a = [points[i] for i in (collision.vertex0_id, collision.vertex1_id) if i in points]
        if a:
            collision.weight = collision.weight * min(a)


def _measures(X: np.ndarray) -> np.ndarray:
    """Volumes (areas in 2D) of simplices X (m, d+1, d)."""
    from math import factorial

    d = X.shape[2]
    return np.abs(np.linalg.det(X[:, 1:] - X[:, :1])) / factorial(d)
