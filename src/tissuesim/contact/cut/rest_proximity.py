"""Pairs of a cut body's contact surface that touch already at rest, left out of contact.

Where cuts meet, the contact surface of one piece folds round the line between its cut faces
(``contact/cut/surface.py``), and primitives on either side of that crease that share no
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

from tissuesim.contact.geometry.edges import triangle_edges

__all__ = ["REST_GAP", "rest_proximity_filter"]

#: surface pairs of one piece closer than this many dhat at rest do not collide (all those
#: the barrier would push at rest)
REST_GAP = 1.0


def rest_proximity_filter(ipctk, mesh, rest: np.ndarray, near: np.ndarray, dhat: float):
    """A CollisionFilter that leaves out the vertex pairs of primitives closer than
    REST_GAP dhat at ``rest`` (n, d) whose vertices all lie on one connected piece of the
    surface of ``mesh`` (an ipctk CollisionMesh) and are all ``near`` (n,) a cut (vertices of
    a cut body's surface embedded in its cut cells); None when there is no such pair. Only
    the elements round those vertices are searched (the rest of the surface is as it was
    meshed).

    ipctk reports a close pair by its closest features (a point near a triangle's edge as a
    point-edge pair) and lets a pair of primitives collide when any of their vertex pairs may,
    so each side is widened to the elements round it: its vertices against every vertex of
    the elements (triangles, or edges in 2D) that hold the other side's."""
    E, F = mesh.edges, mesh.faces
    elements = F if F.shape[0] else E
    if not near.any() or not elements.shape[0]:
        return None
    touching = elements[near[elements].any(axis=1)]
    if not len(touching):
        return None
    # the pairs within REST_GAP dhat among the elements round the cut, in compiled code
    used, local = np.unique(touching, return_inverse=True)
    local = local.reshape(touching.shape).astype(np.int32)
    V = np.asfortranarray(rest[used], dtype=float)
    if F.shape[0]:
        part = ipctk.CollisionMesh(V, triangle_edges(ipctk, local), local)
    else:
        part = ipctk.CollisionMesh(V, local, np.zeros((0, 3), dtype=np.int32))
    close = ipctk.NormalCollisions()
    close.build(part, V, REST_GAP * dhat)
    if not len(close):
        return None
    n = len(rest)
    ring = np.roll(elements, -1, axis=1)
    graph = sp.coo_matrix((np.ones(elements.size), (elements.ravel(), ring.ravel())), (n, n))
    _, piece = connected_components(graph, directed=False)
    # each close pair's vertices (-1 padding) and where its second side starts: edge-edge two
    # and two, else one first (a point against an edge or a triangle)
    ids = np.full((len(close), 4), -1)
    split = np.ones(len(close), dtype=np.int64)
    for k in range(len(close)):
        v = [i for i in close[k].vertex_ids(part.edges, part.faces) if i >= 0]
        ids[k, : len(v)] = used[v]
        split[k] = 2 if close.is_edge_edge(k) else 1
    real = ids >= 0
    at = np.maximum(ids, 0)
    first = piece[at[:, 0]]
    mine = np.all(~real | (near[at] & (piece[at] == first[:, None])), axis=1)
    ids, real, split = ids[mine], real[mine], split[mine]
    if not len(ids):
        return None
    # each side against every vertex of the elements that hold the other side's vertices
    slot = np.arange(4)[None, :]
    side_a = real & (slot < split[:, None])
    side_b = real & (slot >= split[:, None])

    def incidence(mask: np.ndarray) -> sp.csr_matrix:  # (pairs, n) the vertices in mask
        r, c = np.nonzero(mask)
        return sp.csr_matrix((np.ones(len(r)), (r, ids[r, c])), shape=(len(ids), n))

    e = np.repeat(np.arange(len(elements)), elements.shape[1])
    holds = sp.csr_matrix((np.ones(e.size), (elements.ravel(), e)), (n, len(elements)))
    A, B = incidence(side_a), incidence(side_b)
    around_a = ((A @ holds) @ holds.T).astype(bool).astype(float)  # (pairs, n)
    around_b = ((B @ holds) @ holds.T).astype(bool).astype(float)
    pairs = (A.T @ around_b + B.T @ around_a).tocoo()
    i, j = np.minimum(pairs.row, pairs.col), np.maximum(pairs.row, pairs.col)
    key = np.unique(i[i != j] * n + j[i != j])
    excluded = dict.fromkeys(zip((key // n).tolist(), (key % n).tolist(), strict=True), False)
    return ipctk.make_sparse_filter(excluded, True) if excluded else None
