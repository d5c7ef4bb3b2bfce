"""Which node slots of a virtual node cut stay one node (``mesh/cutting/virtual_nodes.py``): every
(copy, local node) is a slot, and the slots of two copies that share a face are joined when
their material meets on that face (the face's part on both copies' sides has an area); a face
the cut runs along joins nothing. The groups are the connected components of those joins.

Slots of nodes away from every cut group as in the uncut mesh (its groups are kept with its
interior face table, ``mesh/queries/interior_faces.py``, across the cuts of a body); the others join
here: whole cells across a face at once, and faces next to a cut cell take
their parts in closed form (``plane_split.positive_fraction``), all at once; only faces where
two different cuts meet, or next to a cell several cuts cross, are clipped one by one (these
are few: where cuts meet)."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from tissuesim.mesh.cutting.planar_cut import EMPTY, PLANE_TOLERANCE, PlanarCut
from tissuesim.mesh.cutting.plane_split import positive_fraction
from tissuesim.mesh.cutting.polygon_clip import clip_polygons, polygon_measures
from tissuesim.mesh.cutting.swept_cut import SweptCut
from tissuesim.mesh.queries.interior_faces import InteriorFaces, interior_faces
from tissuesim.mesh.rows import rows_all

__all__ = ["node_groups"]


def node_groups(x3, x_cell, cells, cuts, taken, d_all, parent, side, copy_cut, more) -> np.ndarray:
    """The group (a label) of every node slot (copy, local node), (copies * (d+1),): x3 the
    rest points (n, 3), x_cell (m, d+1, 3) where each original cell's vertices are now,
    ``taken`` (m, cuts) which cuts cut each cell, d_all (cuts, m, d+1) its vertices'
    distances to each cut, ``parent`` / ``side`` / ``copy_cut`` (copies,) each copy's cell,
    side and cut (0 and -1: whole), ``more`` (``virtual_nodes.Constraints``) the further
    cuts of copies of cells several cuts cross."""
    m, k = cells.shape
    faces = interior_faces(cells)
    cell_a, cell_b = faces.cell_a, faces.cell_b
    on_cut = _on_cuts(x_cell, faces, cuts, d_all)
    # a node no cut cell holds and no face on a cut touches has all its cells whole and all its
    # faces plain: its slots group as in the uncut mesh (``uncut_groups``, kept with the faces);
    # only the slots of the nodes near a cut are joined here (groups never span two nodes)
    near = np.zeros(len(x3), dtype=bool)
    near[cells[taken.any(axis=1)]] = True
    near[faces.nodes[on_cut]] = True
    here = near[cells[parent]].ravel()
    uncut = faces.uncut_groups()
    labels = uncut[(parent[:, None] * k + np.arange(k)).ravel()]
    copy_of_whole = np.full(m, -1)
    whole = np.flatnonzero(side == 0)
    copy_of_whole[parent[whole]] = whole
    whole_a, whole_b = copy_of_whole[cell_a], copy_of_whole[cell_b]
    plain = (whole_a >= 0) & (whole_b >= 0) & ~on_cut
    f, i = np.nonzero(near[faces.nodes] & plain[:, None])  # plain faces' joins of such nodes
    rows = [whole_a[f] * k + faces.slot_a[f, i]]
    cols = [whole_b[f] * k + faces.slot_b[f, i]]
    # faces next to a cut cell: every pair (copy of one cell, copy of the other) whose material
    # meets on the face, all at once; a cell has two copies, or more where cuts meet
    todo = np.flatnonzero(~plain & ~on_cut)
    by_parent = np.argsort(parent, kind="stable")
    first = np.searchsorted(parent[by_parent], np.arange(m))
    count = np.bincount(parent, minlength=m)
    most = int(count.max(initial=1))
    fa, ca, cb = [], [], []
    for i in range(most):
        for j in range(most):
            ok = (count[cell_a[todo]] > i) & (count[cell_b[todo]] > j)
            f = todo[ok]
            fa.append(f)
            ca.append(by_parent[first[cell_a[f]] + i])
            cb.append(by_parent[first[cell_b[f]] + j])
    f, ca, cb = np.concatenate(fa), np.concatenate(ca), np.concatenate(cb)
    part = _face_parts(x3, copy_cut, more, d_all, parent, side, faces, f, ca, cb)
    meet = f[part > EMPTY]
    ca, cb = ca[part > EMPTY], cb[part > EMPTY]
    rows.append((ca[:, None] * k + faces.slot_a[meet]).ravel())
    cols.append((cb[:, None] * k + faces.slot_b[meet]).ravel())
    slots = np.flatnonzero(here)
    index = np.full(len(here), -1)
    index[slots] = np.arange(len(slots))
    r, c = index[np.concatenate(rows)], index[np.concatenate(cols)]
    graph = coo_matrix((np.ones(len(r)), (r, c)), shape=(len(slots), len(slots)))
    labels[slots] = len(uncut) + connected_components(graph, directed=False)[1]
    return labels


def _on_cuts(x_cell: np.ndarray, faces: InteriorFaces, cuts: list, d_all) -> np.ndarray:
    """(f,) whether each interior face, where it is now, lies in a cut's plane within its
    polygon (a cut along faces). A face's tolerance is PLANE_TOLERANCE of its own size, below
    twice that of the whole body's, so cell vertices further than that from the plane leave
    their faces off it: that cheap test on every vertex first, the exact one on the few left."""
    on_cut = np.zeros(len(faces.cell_a), dtype=bool)
    if not cuts:
        return on_cut
    extent = [np.ptp(x_cell[..., i]) for i in range(3)]  # per coordinate: a strided ptp is slow
    reach = 2.0 * PLANE_TOLERANCE * float(np.linalg.norm(extent))
    for j, cut in enumerate(cuts):
        # a swept cut's distances cost a search of its triangles: its cut's own (d_all) pick
        # the candidates, the exact test below looks at them where they are now
        d = d_all[j] if isinstance(cut, SweptCut) else cut.distances(x_cell)
        near = np.abs(d) <= reach  # (m, d+1)
        maybe = np.flatnonzero(rows_all(near[faces.cell_a[:, None], faces.slot_a]))
        x_face = x_cell[faces.cell_a[maybe, None], faces.slot_a[maybe]]  # (f', d, 3)
        size = np.linalg.norm(np.ptp(x_face, axis=1), axis=1)
        dist = np.abs(cut.distances(x_face))
        for i in np.flatnonzero(np.all(dist <= PLANE_TOLERANCE * size[:, None], axis=1)):
            on_cut[maybe[i]] = on_cut[maybe[i]] or _face_on_cut(x_face[i], cut)
    return on_cut


def _face_parts(x3, copy_cut, more, d_all, parent, side, faces, f, ca, cb) -> np.ndarray:
    """The fraction (f,) of each face ``faces``[f] where the material of copy ca (of its cell
    a) and of copy cb (of its cell b) both lie: 1 for two whole cells, the face's part on the
    side of the one cut copy, or on the common side of two copies of one cut (none on
    opposite sides); faces between copies of two different cuts, or of a cell several cuts
    cross, are clipped one by one."""

    def face_d(c: np.ndarray, where: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The signed distances (f, d) of the face's nodes to copy c's cut, times its side."""
        e = parent[c]
        cut = np.maximum(copy_cut[c], 0)
        dist = d_all[cut[:, None], e[:, None], where] if len(d_all) else 0.0 * where
        return dist * side[c][:, None], cut

    part = np.ones(len(f))
    if not len(f):
        return part
    da, ka = face_d(ca, faces.slot_a[f])
    db, kb = face_d(cb, faces.slot_b[f])
    cut_a, cut_b = side[ca] != 0, side[cb] != 0
    several = np.zeros(len(parent), dtype=bool)
    several[more.copy] = True
    odd = several[ca] | several[cb]
    only_a, only_b = cut_a & ~cut_b & ~odd, cut_b & ~cut_a & ~odd
    part[only_a] = positive_fraction(da[only_a])
    part[only_b] = positive_fraction(db[only_b])
    same = cut_a & cut_b & (ka == kb) & ~odd
    flat = rows_all(da == 0.0) | rows_all(db == 0.0)
    agree = same & (side[ca] == side[cb]) & ~flat
    pa = positive_fraction(da[agree])
    pb = pa.copy()  # the two copies' distances on the face mostly agree: measured once then
    differ = ~rows_all(da[agree] == db[agree])
    pb[differ] = positive_fraction(db[agree][differ])
    part[agree] = np.minimum(pa, pb)
    part[same & (side[ca] != side[cb]) & ~flat] = 0.0
    meet = np.flatnonzero(odd | (cut_a & cut_b & (~same | flat)))  # where cuts meet
    if meet.size:
        table_cut, table_side = _constraint_table(copy_cut, side, more)
        va = _copy_values(d_all, table_cut[ca[meet]], table_side[ca[meet]], parent[ca[meet]],
                          faces.slot_a[f[meet]])  # fmt: skip
        vb = _copy_values(d_all, table_cut[cb[meet]], table_side[cb[meet]], parent[cb[meet]],
                          faces.slot_b[f[meet]])  # fmt: skip
        part[meet] = _clipped_parts(x3[faces.nodes[f[meet]]], np.concatenate([va, vb], axis=1))
    return part


def _constraint_table(copy_cut, side, more) -> tuple[np.ndarray, np.ndarray]:
    """Each copy's cuts and sides (copies, C), -1 / 0 padding: its first cut, then its
    further ones (``more``)."""
    copies = len(side)
    order = np.argsort(more.copy, kind="stable")
    rows = more.copy[order]
    rank = np.arange(len(rows)) - np.searchsorted(rows, rows)
    C = 1 + (int(rank.max()) + 1 if len(rows) else 0)
    cut = np.full((copies, C), -1)
    sides = np.zeros((copies, C), dtype=np.int64)
    cut[:, 0], sides[:, 0] = np.where(side != 0, copy_cut, -1), side
    cut[rows, 1 + rank], sides[rows, 1 + rank] = more.cut[order], more.side[order]
    return cut, sides


def _copy_values(d_all, cut, sides, cell, slots) -> np.ndarray:
    """The copies' signed levels (p, C, d) at a face's nodes (``slots``: their places in the
    cell), +inf where a copy has no such cut."""
    values = d_all[np.maximum(cut, 0)[:, :, None], cell[:, None, None], slots[:, None, :]]
    return np.where((cut >= 0)[:, :, None], values * sides[:, :, None], np.inf)


def _clipped_parts(face: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The fraction (p,) of each face (p, d, 3) (an edge in 2D) where every linear function
    with node values ``values`` (p, R, d) is >= 0 (+inf: none)."""
    p, d, _ = face.shape
    W = np.zeros((p, d + values.shape[1], d))
    W[:, np.arange(d), np.arange(d)] = 1.0
    count = np.full(p, d)
    for r in range(values.shape[1]):
        v = np.where(np.isfinite(values[:, r]), values[:, r], 1.0)
        W, count = clip_polygons(W, count, v)
    whole = np.zeros_like(W)
    whole[:, np.arange(d), np.arange(d)] = 1.0
    full = polygon_measures(whole, np.full(p, d), face)
    return polygon_measures(W, count, face) / np.maximum(full, 1e-300)


def _face_on_cut(face_now: np.ndarray, cut: PlanarCut) -> bool:
    """Whether a mesh face (3, 3) (2D: an edge), where it is now, lies in the cut's plane
    inside its polygon."""
    size = float(np.linalg.norm(face_now.max(axis=0) - face_now.min(axis=0)))
    if np.any(np.abs(cut.distances(face_now)) > PLANE_TOLERANCE * size):
        return False
    return cut.covers(face_now, 1e-9 * size)
