"""A step's start clear of a blade's path: the kerf ahead of a blade in contact opened.

A blade in contact with the body it cuts moves in the kerf cut ahead of it
(``mesh/cutting/cut_ahead.py``), whose faces are cut ``BLADE_GAP`` dhat off the blade's plane. A
loaded body closes that kerf ahead of the blade's edge where no blade holds it open (a lobe
hanging from the rest of the organ turns its cut face towards the plane, and the two faces may
even cross it together). The step cannot then start with the blade at its target: the blade
would have to pass through the faces. Without another start the step falls back to pulling the
blade in by a penalty inside Newton (``contact/barrier/kinematic.py``), which took 20-30 iterations
a step on the liver.

The start found here opens the kerf as the blade's wedge will: every surface vertex of the cut
body inside the area the blade sweeps in the step (its projection on the blade's plane within
the swept polygon, plus a margin) and less than ``gap`` on its side of the plane is moved
along the plane's normal to ``gap`` on its side. The side of a vertex is the side of its
element copy's material (virtual nodes: a copy stands for the material on one side of its
cut), found from where the copy's material nodes are now. Vertices are interpolated from the
nodes of their copy with non-negative weights summing to one, so each node is moved by the
largest push any of its vertices needs: every vertex then moves at least as far as it must.
The caller checks the result (the bodies' move with the blade where it is, then the blade's
move to its target, both by exact CCD) and keeps the old fallback when that fails.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["clearance", "MIN_SIDED"]

#: the least weight a vertex's nodes on one side must carry for it to be moved by them alone
MIN_SIDED = 0.25


def clearance(
    nodes: np.ndarray,
    cells: np.ndarray,
    level: np.ndarray,
    weights: sp.spmatrix,
    vertices: np.ndarray,
    blades: list[np.ndarray],
    point: np.ndarray,
    normal: np.ndarray,
    gap: float,
    margin: float,
) -> np.ndarray | None:
    """Node displacements (n, 3) that put every surface vertex in the blade's path at least
    ``gap`` on its side of the blade's plane (``point``, ``normal``), or None when none needs
    it. ``nodes`` (n, 3): where the body's nodes are; ``cells`` (m, k) and ``level`` (m, k):
    the cut cells' copies and each copy's signed distance to its cut times its side at its
    nodes (material where >= 0: ``VirtualNodeMesh.level``); ``weights``
    (vertices, n): each surface vertex's interpolation weights on the nodes; ``vertices``
    (k, 3): where the surface vertices are; ``blades``: the blade's edges or triangles over the
    step (its swept area in the plane); ``margin`` (m): how far around that area counts."""
    normal = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    inside = _in_swept_area(vertices, blades, point, normal, margin)
    if inside is None or not inside.any():
        return None
    node_side = _node_sides(nodes, cells, level, point, normal)
    W = sp.csr_matrix(weights)[np.flatnonzero(inside)]
    W.eliminate_zeros()
    coo = W.tocoo()
    # a vertex's side: the one side every sided node it is interpolated from is on (else
    # none); a node of copies on both sides (where a cut's copies stay joined, at its front)
    # is left where it is, the vertex's other nodes moved further for it
    sides = node_side[coo.col]
    k = W.shape[0]
    total = np.bincount(coo.row, weights=sides, minlength=k)
    count = np.bincount(coo.row, weights=np.abs(sides), minlength=k)
    sided = np.bincount(coo.row, weights=coo.data * np.abs(sides), minlength=k)
    one_side = (count > 0) & (np.abs(total) == count) & (sided >= MIN_SIDED)
    vertex_side = np.where(one_side, np.sign(total), 0.0)
    d = (vertices[inside] - point) @ normal
    need = np.where(one_side, (gap - vertex_side * d) / np.maximum(sided, MIN_SIDED), 0.0)
    if not np.any(need > 0.0):
        return None
    push = np.zeros(len(nodes))
    np.maximum.at(push, coo.col, np.maximum(need, 0.0)[coo.row])
    return (push * node_side)[:, None] * normal


def _in_swept_area(vertices, blades, point, normal, margin) -> np.ndarray | None:
    """Which vertices project onto the blade's plane within ``margin`` of the convex polygon
    its edges or triangles over the step span (None: they span no area)."""
    from tissuesim.mesh.cutting.planar_cut import PlanarCut

    area = PlanarCut.hull(
        np.concatenate([np.asarray(b, dtype=float) for b in blades]), point, normal
    )
    return None if area is None else area.reach(vertices) <= margin


def _node_sides(nodes, cells, level, point, normal) -> np.ndarray:
    """Each node's side of the blade's plane (+1 / -1) from the element copies it belongs to:
    the side where a copy's material nodes lie now (their distances weighted by their level);
    0 for a node of no copy or of copies on both sides."""
    distance = (nodes[cells] - point) @ normal  # (copies, 4)
    copy_side = np.sign((np.maximum(level, 0.0) * distance).sum(axis=1))
    plus = np.zeros(len(nodes))
    minus = np.zeros(len(nodes))
    np.add.at(plus, cells.ravel(), np.repeat(copy_side > 0, cells.shape[1]))
    np.add.at(minus, cells.ravel(), np.repeat(copy_side < 0, cells.shape[1]))
    return np.where((plus > 0) & (minus == 0), 1.0, np.where((minus > 0) & (plus == 0), -1.0, 0.0))
