"""The contact surface of a cut FEM body (virtual node cut, ``mesh/cutting/virtual_nodes.py``): its
boundary embedded in the element copies, every surface point a fixed weighting of mesh nodes.

The two faces of a fresh cut coincide, and IPC's barrier is infinite at zero distance. So each
side's contact surface follows the level set ``level = gap`` (gap = GAP dhat) of its material
level, the signed distance to the cut's plane where the body was cut, positive in its material
(``Mesh.cell_levels``): a slab of half-width gap around the plane is left out of the contact
surfaces, and the two sides start 2 gap apart, outside each other's barrier. The material
itself is unchanged (mass and elasticity are the copies'); the faces of a cut can overlap by at
most 2 gap before their barrier holds them, like the kerf of a blade that thick. A notch's
slot ends in a cap across its front.

The contact region is the union over cells of cell ∩ {level >= gap} (cells away from the cut:
all of them). Its boundary, per face F of a copy c whose *partners* are the other copies
holding the same face nodes (their material joins c's there):

    exposed(c, F) = F ∩ {level_c >= gap} ∩ (for each partner p) {level_p < gap},

plus, inside each copy its level set crosses, the section {level_c = gap}. Every constraint is
a level set of one plane's distance, so clipped faces have their corners on mesh edges, and a
corner is a node or a point on an edge: corners are merged by (edge, weight), and other
polygons' points on an edge are inserted into the polygon edges along it (no T-junction), which
makes the surface watertight. Faces are clipped all at once (Sutherland-Hodgman over the
corners, vectorised over faces).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from tissuesim.contact.cut.polygon_surface import polygon_surface
from tissuesim.contact.geometry.edges import triangle_edges
from tissuesim.errors import InputError
from tissuesim.mesh.cutting.polygon_clip import clip_polygons
from tissuesim.mesh.rows import unique_rows

__all__ = ["cut_surface", "level_stack"]

#: the cut faces' contact surfaces lie GAP dhat inside each side: the fresh faces start
#: 2 GAP dhat apart, outside each other's barrier, and overlap by at most that when pressed
GAP = 1.0
#: the gap of a body cut by an instrument in contact with it (``add_cut(obstacle, ...)``):
#: the blade moves on the cut's plane, and the faces, at least (BLADE_GAP - SNAP_OUT) dhat =
#: 1.1 dhat from it, leave it outside their barrier
BLADE_GAP = 1.5
#: node levels within SNAP_IN dhat above the level set (into the material) or SNAP_OUT dhat
#: below it are put on it; the sides stay 2 (GAP - SNAP_OUT) dhat = 1.2 dhat apart at least
SNAP_IN, SNAP_OUT = 1.0, 0.4
#: surface points closer than MERGE dhat at rest are one point
MERGE = 1.0
#: outward local faces of a positively oriented tetrahedron
_TET_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
#: the edges of a tetrahedron, and the cyclic order of the four crossings of a 2-2 section
_TET_EDGES = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])
#: weights below this are round-off (a point on an edge has two, a node one)
_ZERO = 1e-12
#: points on one mesh edge closer than this (in weight) are one point
_MERGE = 1e-9


def cut_surface(mesh, dhat: float, gap: float = GAP) -> tuple[sp.csr_matrix, np.ndarray]:
    """(W, triangles): the surface points as rows of node weights W (k, n_points), so that
    V = W @ X for node positions X (n_points, 3), and the outward triangles (t, 3) over them,
    of a cut 3D P1 mesh (``mesh.cell_levels`` set), for a barrier of activation distance
    ``dhat`` (m): the cut faces ``gap`` dhat inside each side (default GAP); node levels
    within SNAP_IN dhat above or SNAP_OUT dhat below that are taken as on it, so the level set
    passes through those nodes instead of making tiny triangles next to them; points closer than
    MERGE dhat (at rest) made one (``contact/cut/polygon_surface.py``). IPC's barrier acts between
    a surface's own primitives closer than dhat, so the surface must have no feature that
    small. Where cuts meet in a cell (any number of them), a surface that merging folded
    through itself at rest is built again merging less (MERGE / 2, / 4, then not at all)."""
    gap = gap * dhat
    if mesh.dim != 3 or mesh.cells.shape[1] != 4:
        raise InputError(
            "contact of a cut body: only 3D P1 tetrahedra are built so far; cut it without "
            "contact, or simulate the cut in 3D"
        )
    cells, levels = mesh.cells, level_stack(mesh)
    snap = (levels >= gap - SNAP_OUT * dhat) & (levels <= gap + SNAP_IN * dhat)
    levels = np.where(snap, gap, levels)
    face_polys = _exposed_faces(cells, levels, gap)
    cap_polys = _sections(mesh.points, cells, levels, gap)
    K = max(face_polys[0].shape[1], cap_polys[0].shape[1])

    def pad(a: np.ndarray) -> np.ndarray:
        return np.concatenate([a, np.zeros((len(a), K - a.shape[1], 4), a.dtype)], axis=1)

    nodes = np.concatenate([pad(face_polys[0]), pad(cap_polys[0])])  # (p, K, 4) corner nodes
    weights = np.concatenate([pad(face_polys[1]), pad(cap_polys[1])])  # (p, K, 4)
    count = np.concatenate([face_polys[2], cap_polys[2]])
    merge = MERGE
    while True:
        W, tri = polygon_surface(mesh.n_points, nodes, weights, count, mesh.points, merge * dhat)
        # where cuts meet, a merged cluster's mean can fold the surface through itself
        # (1 in 40 random triple cuts): merge less there, down to not at all
        if levels.shape[1] == 1 or merge == 0.0 or not _intersecting(W, tri, mesh.points):
            return W, tri
        merge = merge / 2.0 if merge > MERGE / 4.0 else 0.0


def _intersecting(W: sp.csr_matrix, tri: np.ndarray, rest: np.ndarray) -> bool:
    """Whether the surface (W, tri) over the rest positions intersects itself (ipctk's exact
    test)."""
    import ipctk

    V = np.asfortranarray(W @ rest)
    faces = np.asfortranarray(tri.astype(np.int32))
    mesh = ipctk.CollisionMesh(V, triangle_edges(ipctk, faces), faces)
    return bool(ipctk.has_intersections(mesh, V))


def level_stack(mesh) -> np.ndarray:
    """Each cell's levels (m, C, 4): ``cell_levels`` first, then its further ones
    (``cell_more_levels``: cells several cuts bound), +inf padding."""
    first = np.asarray(mesh.cell_levels, dtype=float)
    if mesh.cell_more_levels is None:
        return first[:, None, :]
    rows, more = mesh.cell_more_levels
    order = np.argsort(rows, kind="stable")
    rows, more = rows[order], more[order]
    start = np.searchsorted(rows, rows)  # each row's rank among its cell's
    rank = np.arange(len(rows)) - start
    out = np.full((len(first), 2 + int(rank.max()), first.shape[1]), np.inf)
    out[:, 0] = first
    out[rows, 1 + rank] = more
    return out


def _exposed_faces(cells: np.ndarray, levels: np.ndarray, gap: float):
    """Every copy face's exposed part as polygons: (nodes (p, K, 4), weights (p, K, 4),
    corner counts (p,)) with weights over the face's three nodes (the fourth weight 0);
    ``levels`` (m, C, 4) each copy's levels (+inf: none)."""
    m, C, _ = levels.shape
    fnodes = cells[:, _TET_FACES].reshape(-1, 3)  # (4m, 3), outward order
    order = np.argsort(fnodes, axis=1)
    snodes = np.take_along_axis(fnodes, order, axis=1)  # sorted: partners align node by node
    _, group, size = unique_rows(snodes, return_inverse=True, return_counts=True)
    by_group = np.argsort(group, kind="stable")
    start = np.concatenate([[0], np.cumsum(size)])
    most = int(size.max(initial=1))
    # a copy's levels are finite at all its vertices or at none (+inf: no such level)
    finite = np.repeat(np.isfinite(levels[:, :, 0]), 4, axis=0)  # (4m, C)
    # faces away from every cut (no copy holding them has a level): inside where two copies
    # share them, else whole boundary faces; only the others (``sub``, most faces are not)
    # are looked at below, and their levels gathered alone
    near = np.bincount(group, weights=finite.any(axis=1), minlength=len(size)) > 0
    sub = np.flatnonzero(near[group])
    covered = size[group] >= 2
    covered[sub] = False
    at = np.full(4 * m, -1)
    at[sub] = np.arange(len(sub))
    cell, face = np.divmod(sub, 4)
    s_lev = levels[cell[:, None, None], np.arange(C)[None, :, None], _TET_FACES[face][:, None, :]]
    s_lev = np.take_along_axis(s_lev, order[sub][:, None, :], axis=2)  # (sub, C, 3) sorted
    s_fin, s_group = finite[sub], group[sub]
    # a copy whose level is gap all over a face and lower at the opposite vertex (nodes
    # snapped onto the level set) holds no volume next to it: its face is not exposed, and as
    # a partner it covers nothing (face i of a cell is the one opposite its vertex i)
    opposite = levels[cell, :, face]  # (sub, C)
    s_hollow = np.any(s_fin & np.all(s_lev == gap, axis=2) & (opposite < gap), axis=1)
    hollow = np.zeros(4 * m, dtype=bool)
    hollow[sub] = s_hollow
    # constraints per face near a cut, in the sorted node order: each own level - gap >= 0,
    # and for each partner (a copy holding the same face nodes) gap - level_p >= 0 for its one
    # level that is not also one of the face's own (the others hold wherever the own ones
    # do): its region is left out; a partner with no such level covers the face entirely
    constraints = [s_lev[:, i] - gap for i in range(C)]
    rows = np.arange(len(sub))
    several: dict = {}  # face (row of sub) -> [partner levels - gap (k, 3): its region >= 0]
    for j in range(most):  # the j-th member of each face's group, skipping the face itself
        has = j < size[s_group]
        member = np.where(has, by_group[np.minimum(start[s_group] + j, len(by_group) - 1)], 0)
        other = has & (member != sub) & ~hollow[member]
        plev, pfin = s_lev[np.maximum(at[member], 0)], s_fin[np.maximum(at[member], 0)]
        # partner level a holds on the whole face, or is one of the face's own
        own = np.all(plev >= gap, axis=2)
        for b in range(C):
            both = pfin & s_fin[:, b : b + 1]
            with np.errstate(invalid="ignore"):  # inf - inf where a level is none: not used
                dif = np.where(both[:, :, None], plev - s_lev[:, b : b + 1], np.inf)
            own |= both & np.all(np.abs(dif) <= 1e-9 * (np.abs(plev) + gap), axis=2)
        remaining = pfin & ~own
        n_left = remaining.sum(axis=1)
        covered[sub] |= other & (n_left == 0)
        # a partner that two cuts bound and this face's copy has neither (both cuts end there,
        # as at the apex of a V): what it leaves exposed need not be convex; such faces are
        # cut into convex pieces one by one below (few)
        for r in np.flatnonzero(other & (n_left >= 2)):
            several.setdefault(int(r), []).append(plev[r][remaining[r]] - gap)
        pick = np.argmax(remaining, axis=1)
        lev = np.where((other & (n_left == 1))[:, None], plev[rows, pick], -np.inf)
        constraints.append(gap - lev)  # -inf: no constraint
    empty = np.zeros(4 * m, dtype=bool)
    empty[sub] = np.any(np.all(s_lev - gap < 0.0, axis=2), axis=1)
    live = ~covered & ~empty & ~hollow  # some of it can be exposed
    odd = sub[list(several)]
    live[odd] = False
    idx = np.flatnonzero(live)
    # the face's corners in outward order, as weights over its sorted nodes
    inverse_order = np.argsort(order[idx], axis=1)  # outward corner i is sorted position
    K = 3 + len(constraints)
    W = np.zeros((len(idx), K, 3))
    W[np.arange(len(idx))[:, None], np.arange(3)[None, :], inverse_order] = 1.0
    count = np.full(len(idx), 3)
    # only faces some constraint cuts into are clipped (most faces are whole: away from a cut)
    mine = np.flatnonzero(at[idx] >= 0)  # live faces near a cut
    values = [np.where(np.isfinite(v), v, 1.0) for v in (c[at[idx[mine]]] for c in constraints)]
    cut_into = np.any([np.any(v < 0.0, axis=1) for v in values], axis=0)
    clipped = mine[cut_into]
    Wc, count_c = W[clipped], count[clipped]
    for v in values:  # +inf (no constraint) keeps everything
        Wc, count_c = clip_polygons(Wc, count_c, v[cut_into])
    W[clipped], count[clipped] = Wc, count_c
    if several:
        face_of, W_odd, count_odd = _pieces(
            odd[~covered[odd] & ~empty[odd] & ~hollow[odd]], at, order, constraints, several
        )
        K = max(K, W_odd.shape[1])
        W = np.concatenate([_pad(W, K), _pad(W_odd, K)])
        count = np.concatenate([count, count_odd])
        idx = np.concatenate([idx, face_of])
    keep = count >= 3
    nodes = np.zeros((keep.sum(), K, 4), dtype=np.int64)
    nodes[:, :, :3] = snodes[idx[keep]][:, None, :]
    weights = np.zeros((keep.sum(), K, 4))
    weights[:, :, :3] = W[keep]
    return nodes, weights, count[keep]


def _pad(W: np.ndarray, K: int) -> np.ndarray:
    return np.concatenate([W, np.zeros((len(W), K - W.shape[1], W.shape[2]))], axis=1)


def _pieces(faces, at, order, constraints, several):
    """The exposed part of each face in ``faces`` whose partners include one that several
    cuts bound, as convex pieces: the face clipped by its own constraints and its other
    partners', then less each such partner's region (where all its levels - gap are >= 0):
    a piece P less a region {a_1 >= 0, ..., a_r >= 0} is the pieces P with a_1 < 0, then
    a_1 >= 0 and a_2 < 0, and so on. Returns (the face of each piece, corner weights
    (p, K, 3) over the face's sorted nodes, corner counts)."""
    out_face, out_W, out_count = [], [], []
    K = 3 + len(constraints) + max(sum(map(len, regions)) for regions in several.values())
    for face in faces:
        r = int(at[face])
        start = np.zeros((1, K, 3))
        start[0, np.arange(3), np.argsort(order[face])] = 1.0
        piece_W, piece_n = start, np.array([3])
        for c in constraints:
            v = np.where(np.isfinite(c[r]), c[r], 1.0)[None, :]
            piece_W, piece_n = clip_polygons(piece_W, piece_n, v)
        pieces = [(piece_W, piece_n)] if piece_n[0] >= 3 else []
        for region in several[r]:
            left = []
            for Wp, n in pieces:
                for i in range(len(region)):
                    Q, q = Wp, n
                    for k in range(i):
                        Q, q = clip_polygons(Q, q, region[k][None, :])
                    Q, q = clip_polygons(Q, q, -region[i][None, :])
                    if q[0] >= 3:
                        left.append((Q, q))
            pieces = left
        for Wp, n in pieces:
            out_face.append(face)
            out_W.append(Wp[0])
            out_count.append(int(n[0]))
    if not out_W:
        return np.zeros(0, dtype=np.int64), np.zeros((0, K, 3)), np.zeros(0, dtype=np.int64)
    return np.array(out_face), np.stack(out_W), np.array(out_count)


def _sections(points: np.ndarray, cells: np.ndarray, levels: np.ndarray, gap: float):
    """Inside each copy, the level set {level_i = gap} of each of its levels (m, C, 4) where
    it crosses the copy, clipped to where its other levels are >= gap (where two cuts meet),
    oriented outward: (nodes (p, K, 4), weights (p, K, 4), counts (p,))."""
    m, C, _ = levels.shape
    parts = []
    for i in range(C):
        nodes, W, count, idx = _one_section(points, cells, levels[:, i], gap)
        others = [levels[idx, j] - gap for j in range(C) if j != i]
        if others:
            W = np.concatenate([W, np.zeros((len(W), len(others), 4))], axis=1)
            nodes = np.concatenate([nodes, nodes[:, :1].repeat(len(others), axis=1)], axis=1)
            clip = [np.where(np.isfinite(v), v, 1.0) for v in others]
            todo = np.flatnonzero(np.any([np.any(v < 0.0, axis=1) for v in clip], axis=0))
            Wc, count_c = W[todo], count[todo]
            for v in clip:
                Wc, count_c = clip_polygons(Wc, count_c, v[todo])
            W[todo], count[todo] = Wc, count_c
        keep = count >= 3
        parts.append((nodes[keep], W[keep], count[keep]))
    K = max(p[1].shape[1] for p in parts)

    def pad(a: np.ndarray) -> np.ndarray:
        return np.concatenate([a, np.zeros((len(a), K - a.shape[1], 4), a.dtype)], axis=1)

    return (
        np.concatenate([pad(p[0]) for p in parts]),
        np.concatenate([pad(p[1]) for p in parts]),
        np.concatenate([p[2] for p in parts]),
    )


def _one_section(points: np.ndarray, cells: np.ndarray, levels: np.ndarray, gap: float):
    """The level set {level = gap} inside each cell it crosses, oriented outward (towards
    lower level): (nodes (p, 4, 4), weights (p, 4, 4), counts (p,) 3 or 4, the rows crossed
    (p,))."""
    finite = np.all(np.isfinite(levels), axis=1)
    v = levels - gap
    crossed = finite & (v.max(axis=1) > 0.0) & (v.min(axis=1) < 0.0)
    idx = np.flatnonzero(crossed)
    v = v[idx]
    a, b = _TET_EDGES[:, 0], _TET_EDGES[:, 1]
    va, vb = v[:, a], v[:, b]
    hit = va * vb < 0.0  # (c, 6)
    t = np.where(hit, va / np.where(hit, va - vb, 1.0), 0.0)
    # corner weights over the cell's 4 nodes, one per crossed edge, then the nodes on the
    # level set (snapped there): a section has 3 or 4 of these
    Wedge = np.zeros((len(idx), 10, 4))
    r = np.arange(len(idx))[:, None]
    Wedge[r, np.arange(6)[None, :], a[None, :]] = 1.0 - t
    Wedge[r, np.arange(6)[None, :], b[None, :]] = t
    Wedge[:, 6:, :] = np.eye(4)
    hit = np.concatenate([hit, v == 0.0], axis=1)
    # cyclic order: the crossed edges sorted by angle around their centroid in the plane
    X = points[cells[idx]]  # (c, 4, 3)
    P = np.einsum("cen,cnd->ced", Wedge, X)
    n_hit = hit.sum(axis=1)
    centre = np.einsum("ce,ced->cd", hit, P) / n_hit[:, None]
    grad = _level_gradients(X, levels[idx])  # (c, 3), rest coordinates
    normal = grad / np.linalg.norm(grad, axis=1, keepdims=True)
    e1 = np.cross(normal, np.where(np.abs(normal[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(normal, e1)
    rel = P - centre[:, None, :]
    # angles counter-clockwise about -normal (outward: towards lower level)
    angle = np.arctan2(np.einsum("ced,cd->ce", rel, e1), np.einsum("ced,cd->ce", rel, e2))
    angle = np.where(hit, angle, np.inf)
    order = np.argsort(angle, axis=1)[:, :4]
    W = np.take_along_axis(Wedge, order[:, :, None], axis=1)
    count = n_hit
    # orientation: the fan's normal must point along -grad (out of the region level >= gap)
    Q = np.einsum("ckn,cnd->ckd", W, X)
    fan_normal = np.cross(Q[:, 1] - Q[:, 0], Q[:, 2] - Q[:, 0])
    flip = np.einsum("cd,cd->c", fan_normal, grad) > 0.0
    if flip.any():
        reversed_ = W[flip][:, ::-1]
        # keep the padding (4th slot of triangles) at the end
        tri = count[flip] == 3
        reversed_[tri] = np.roll(reversed_[tri], -1, axis=1)
        W[flip] = reversed_
    nodes = np.broadcast_to(cells[idx][:, None, :], W.shape).copy()
    return nodes, W, count, idx


def _level_gradients(X: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """The gradient (c, 3) of the linear function with vertex values ``levels`` (c, 4) over
    tetrahedra X (c, 4, 3), in their (rest) coordinates."""
    edges = X[:, 1:] - X[:, :1]  # (c, 3, 3)
    rise = levels[:, 1:] - levels[:, :1]  # (c, 3)
    return np.linalg.solve(edges, rise[:, :, None])[:, :, 0]
