"""Crumbs: pieces a cut frees that are too small for the mesh to carry as bodies of their own.

Where three cuts meet near one line the virtual node algorithm can free a piece of a few cubic
millimetres made of element parts of fractions 1e-4 (2.3 mm^3 in the liver's lobe, 3e-4 of
the cells it lies in). Its nodes are mostly virtual and held by that much mass and stiffness.
With contact on it is also thinner than the cut faces' kerf (2 dhat): it had no contact
surface of its own, only points (``contact/cut/sliver_points.py``). Squeezed between the pieces
round it, a Newton iteration moved it 0.2 m against their millimetres; CCD then cut each
iteration's step, of the whole system, to a thousandth, and the step failed after six
halvings.

Such a piece stays attached to the piece it was part of before the cut that freed it. In the
cells where both have a part, the crumb's copy takes the other's nodes wherever the two
continue the same node of the mesh before the cut; nothing moves when they join. The crumb's
copies and their fractions stay, so no mass or volume is lost, and the cuts keep their place.
Its parts add no contact faces (it had none) and take none away: a copy whose region at the
kerf's gap is empty covers nothing as a partner (``contact/cut/surface.py``). What changes is
that the crumb no longer moves on its own. A thin slice that is not small (a grazing cut along
the organ's side) is not a crumb: it comes off, with a surface of its own
(``contact/cut/thin_pieces.py``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from tissuesim.mesh.checks import signed_volumes
from tissuesim.mesh.cutting.virtual_nodes import VirtualNodeMesh

__all__ = ["CRUMB", "attach_crumbs", "joined", "small_pieces"]

#: a piece is small when its volume is under this fraction of the mean volume of the cells
#: it lies in (a crumb where cuts meet: 3e-4; a thin slice of one cut: its own fraction)
CRUMB = 0.01


def small_pieces(vn: VirtualNodeMesh, original_points: np.ndarray) -> np.ndarray:
    """(copies,) whether each copy of ``vn`` belongs to a small piece: its volume under CRUMB
    of the mean volume of the original cells its copies lie in. Only pieces of cut copies can
    be (a whole cell is not small next to itself)."""
    cells = vn.cells
    label = vn.point_pieces[cells[:, 0]]
    n = label.max() + 1
    whole = np.zeros(n, dtype=bool)
    whole[label[vn.side == 0]] = True
    candidate = ~whole[label]  # only the copies of pieces without a whole cell are measured
    if not candidate.any():
        return candidate
    part = label[candidate]
    volume = np.abs(signed_volumes(original_points, vn.origin[cells[candidate]]))
    material = np.bincount(part, weights=vn.fraction[candidate] * volume, minlength=n)
    cell_volume = np.bincount(part, weights=volume, minlength=n)
    count = np.bincount(part, minlength=n)
    small = ~whole & (material < CRUMB * cell_volume / np.maximum(count, 1))
    return small[label]


def attach_crumbs(
    vn: VirtualNodeMesh, carry: np.ndarray, crumbs: np.ndarray
) -> tuple[VirtualNodeMesh, np.ndarray, np.ndarray] | None:
    """Attach each piece of the copies ``crumbs`` (copies,) marks to the piece it was part of
    before the cut: (the new mesh, the current node each of its nodes continues, the node of
    the new mesh each node of ``vn`` became), or None when none can be (no piece shares a cell
    with it and continues a node it continues). ``carry`` (points,): the node of the current
    mesh each node of ``vn`` continues."""
    n = len(vn.points)
    piece = vn.point_pieces[vn.cells[:, 0]]
    crumb_pieces = np.unique(piece[crumbs])
    joins = [_pairs(vn, carry, piece, p, crumb_pieces) for p in crumb_pieces]
    joins = [pair for pair in joins if pair is not None]
    if not joins:
        return None
    target = joined(n, np.concatenate([a for a, _ in joins]), np.concatenate([b for _, b in joins]))
    used = np.unique(target)
    index = np.full(n, -1)
    index[used] = np.arange(len(used))
    renamed = index[target]
    glued = replace(vn, points=vn.points[used], cells=renamed[vn.cells], origin=vn.origin[used])
    return glued, carry[used], renamed


def _pairs(vn, carry, piece, p, crumb_pieces) -> tuple[np.ndarray, np.ndarray] | None:
    """The node pairs (crumb's, other piece's) that attach crumb piece ``p``: in the cells it
    shares with one other piece (the one with the most such pairs), its copy's node and that
    piece's copy's node at each vertex where both continue the same current node."""
    mine = np.flatnonzero(piece == p)
    others = np.flatnonzero(np.isin(vn.parent, vn.parent[mine]) & ~np.isin(piece, crumb_pieces))
    if not len(others):
        return None
    # every (crumb copy, other copy) of one cell, in the order of the other copies
    by_cell = mine[np.argsort(vn.parent[mine], kind="stable")]
    start = np.searchsorted(vn.parent[by_cell], vn.parent[others])
    stop = np.searchsorted(vn.parent[by_cell], vn.parent[others], "right")
    count = stop - start
    c = np.repeat(others, count)
    m = by_cell[
        np.repeat(start, count)
        + np.arange(count.sum())
        - np.repeat(np.cumsum(count) - count, count)
    ]
    same = carry[vn.cells[m]] == carry[vn.cells[c]]  # (pairs, k): vertices they both continue
    best = None
    for q in np.unique(piece[others]):  # the few pieces it shares a cell with
        mask = same & (piece[c] == q)[:, None]
        a, b = vn.cells[m][mask], vn.cells[c][mask]
        a, first = np.unique(a, return_index=True)  # a crumb node joins one node only
        b = b[first]
        if len(a) and (best is None or len(a) > len(best[0])):
            best = (a, b)
    return best


def joined(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) each node's node once nodes a[i] and b[i] are made one: the smallest of its class,
    so a node of the original mesh (the first copy of itself, its index below any copy's)
    stays where it was and the points keep the originals first."""
    graph = sp.coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    smallest = np.full(label.max() + 1, n)
    np.minimum.at(smallest, label, np.arange(n))
    return smallest[label]
