"""Pairs of a cut body's contact surface that touch already at rest, left out of contact.

Where cuts meet, the contact surface of one piece folds round the line between its cut faces
(``contact/cut_surface.py``), and primitives on either side of that crease that share no
vertex lie within dhat of each other at rest (34 of 40 random crossings had a pair within
0.3 dhat, ``benchmarks/crossing_surfaces.py``). IPC's barrier then pushes them apart from the
first step: a spurious force inside the piece, large at a small distance, which moved a cut
block that nothing loaded and which Newton had to fight in every step (three blades meeting
in the liver took 7-168 iterations a step before the pieces parted, 3-14 without it). Such
pairs are one piece's own surface on either side of its material: they cannot reach each
other without that material collapsing, so their vertex pairs are left out of the collision
mesh (a compiled sparse filter, ``ipctk.make_sparse_filter``). Pairs of different pieces,
contact points without faces (their own pieces) and bodies that are not cut keep theirs.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

__all__ = ["REST_GAP", "rest_proximity_filter"]

#: surface pairs of one piece closer than this many dhat at rest do not collide (all those
#: the barrier would push at rest)
REST_GAP = 1.0


def rest_proximity_filter(ipctk, mesh, rest: np.ndarray, cut: np.ndarray, dhat: float):
    """A CollisionFilter that leaves out the vertex pairs of primitives closer than
    REST_GAP dhat at ``rest`` (n, d) whose vertices all lie on one connected piece of the
    surface of ``mesh`` (an ipctk CollisionMesh) and are all ``cut`` (n,) vertices (of a cut
    body's surface); None when there is no such pair.

    ipctk reports a close pair by its closest features (a point near a triangle's edge as a
    point-edge pair) and lets a pair of primitives collide when any of their vertex pairs may,
    so each side is widened to the elements round it: its vertices against every vertex of
    the elements (triangles, or edges in 2D) that hold the other side's."""
    rest = np.asfortranarray(rest, dtype=float)
    E, F = mesh.edges, mesh.faces
    elements = F if F.shape[0] else E
    if not cut.any() or not elements.shape[0]:
        return None
    n = len(rest)
    ring = np.roll(elements, -1, axis=1)
    graph = sp.coo_matrix((np.ones(elements.size), (elements.ravel(), ring.ravel())), (n, n))
    _, piece = connected_components(graph, directed=False)
    close = ipctk.NormalCollisions()  # the pairs within REST_GAP dhat, found in compiled code
    close.build(mesh, rest, REST_GAP * dhat)
    # vertex -> the vertices of the elements holding it (itself included)
    incidence = sp.csr_matrix(
        (
            np.ones(elements.size),
            (elements.ravel(), np.repeat(np.arange(len(elements)), elements.shape[1])),
        ),
        shape=(n, len(elements)),
    )
    around = (incidence @ incidence.T).tocsr()
    excluded: dict[tuple[int, int], bool] = {}
    for k in range(len(close)):
        ids = np.array([i for i in close[k].vertex_ids(E, F) if i >= 0])
        if not cut[ids].all() or np.any(piece[ids] != piece[ids[0]]):
            continue
        split = 2 if close.is_edge_edge(k) else 1  # edge-edge: two and two, else one first
        a, b = ids[:split], ids[split:]
        for side, other in ((a, b), (b, a)):
            wide = np.unique(around[other].indices)
            for i in side:
                for j in wide:
                    if i != j:
                        excluded[(int(min(i, j)), int(max(i, j)))] = False
    return ipctk.make_sparse_filter(excluded, True) if excluded else None
