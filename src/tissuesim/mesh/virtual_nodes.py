"""Cutting a simplex mesh along a surface with the virtual node algorithm (Molino, Bao & Fedkiw,
SIGGRAPH 2004): the geometric and topological core, before any physics is attached.

An element the cut crosses completely is replaced by one *copy* per side of the cut that holds
material; each copy keeps the element's shape and its P1 interpolation but stands for the
material on its side only, its *volume fraction* f (the element's volume on that side over its
volume). Nodes are duplicated where the material around them is no longer connected: every
(copy, local node) is a node slot, and the slots of two copies that share a face are merged when
their material meets on that face (the face's part on both copies' sides has an area), so two
sides of a through-cut end up with their own nodes and fall apart, while a notch keeps them
joined beyond its end. A node of a copy may lie outside the copy's material: that is the
*virtual* node, which carries the copy's interpolation there.

Why this method (the alternatives are element removal, as SOFA's carving and most GPU dissection
do, which loses mass and follows the mesh, not the blade; element splitting, which conforms the
mesh to the blade but makes slivers where the blade passes near a vertex; XFEM with Heaviside
enrichment, which is equivalent to virtual nodes for complete cuts): the cut follows the blade
exactly (it is the embedded plane in each element, not a mesh face), every element copy integrates
exactly its part of the volume, so mass and volume are conserved to round-off, and no new, small
element exists. A copy's stiffness and mass both scale with f (psi(F) f V and the element's
lumped mass times f), so the ratio that sets the explicit stability limit is the element's own.

Here: a cut is planar within each element (``PlanarCut``: a plane bounded by a convex polygon,
e.g. the area a straight blade sweeps in a step); an element is cut when the plane separates its
vertices and the plane's section of it lies inside the polygon (the blade has crossed it
completely; an element the blade's edge is still inside stays whole until a later step crosses
it). ``virtual_node_cut`` returns the new mesh (points duplicated, copies of the cut cells), each
copy's fraction and cut, and each new node's original node (for carrying positions and
velocities across the cut). An element cut once is not cut again (refused).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.planar_cut import PlanarCut
from tissuesim.mesh.plane_split import positive_fraction, sections_inside

__all__ = ["PlanarCut", "VirtualNodeMesh", "cut_cells", "virtual_node_cut"]

#: a vertex this close to the plane, relative to the element's size, counts as on it
PLANE_TOLERANCE = 1e-9
#: a face part (or a side's volume) below this fraction of the whole counts as empty
EMPTY = 1e-12


@dataclass(frozen=True)
class VirtualNodeMesh:
    """A cut mesh: ``points`` (p, d) (original points, then duplicates), ``cells`` (m, d+1)
    (uncut cells, then the copies of cut cells), ``fraction`` (m,) each cell's volume
    fraction (1 for uncut ones), ``parent`` (m,) the original cell of each, ``side`` (m,)
    0 uncut, +1 / -1 the side of its cut, ``cut`` (m,) the index of its cut (-1 uncut), and
    ``origin`` (p,) the original node of each point; ``level`` (m, d+1) each copy's signed
    distance to its cut's plane at its vertices times its side (material where >= 0); whole
    cells next to a cut carry their distance on their side, others +inf (``_levels``)."""

    points: np.ndarray
    cells: np.ndarray
    fraction: np.ndarray
    parent: np.ndarray
    side: np.ndarray
    cut: np.ndarray
    origin: np.ndarray
    level: np.ndarray | None = None

    @property
    def material_nodes(self) -> np.ndarray:
        """(p,) whether each point lies in the material of a cell that uses it (False for a
        virtual node only: a support or a grasper there would hold empty space)."""
        inside = np.ones(self.cells.shape, dtype=bool)
        if self.level is not None:
            inside = self.level >= 0.0
        out = np.zeros(len(self.points), dtype=bool)
        out[self.cells[inside]] = True
        return out

    @property
    def n_pieces(self) -> int:
        """Connected pieces of material (cells joined through shared points)."""
        return _components(self.cells, len(self.points))

    def to_mesh(self, mesh):
        """The cut as a ``Mesh`` of the original ``mesh``: its point sets hold every copy of
        their nodes, its cell sets the copies of their cells, its facet sets the boundary
        facets over copies of their nodes; ``cell_fractions`` weights the copies."""
        from tissuesim.mesh.boundary import boundary_facets, match_facets
        from tissuesim.mesh.mesh import Mesh

        point_sets = {
            name: np.flatnonzero(np.isin(self.origin, ids)) for name, ids in mesh.point_sets.items()
        }
        cell_sets = {
            name: np.flatnonzero(np.isin(self.parent, ids)) for name, ids in mesh.cell_sets.items()
        }
        facets = boundary_facets(self.cells)
        facet_sets = {  # the boundary facets whose original nodes make a facet of the set
            name: facets[match_facets(np.asarray(ids), self.origin[facets]) >= 0]
            for name, ids in mesh.facet_sets.items()
        }
        return Mesh(
            self.points,
            self.cells,
            point_sets=point_sets,
            facet_sets=facet_sets,
            cell_sets=cell_sets,
            source=f"{mesh.source} (cut)",
            cell_fractions=self.fraction,
            cell_levels=self.level,
        )


def _distances(x_cell: np.ndarray, cut: PlanarCut) -> np.ndarray:
    """Signed distances (m, d+1) of the cells' vertices (x_cell (m, d+1, 3), where each cell's
    vertices are) to the cut's plane, snapped to 0 within PLANE_TOLERANCE of the cell's size."""
    d = (x_cell - cut.point) @ cut.normal
    size = np.linalg.norm(x_cell - x_cell[:, :1], axis=2).max(axis=1)
    d[np.abs(d) <= PLANE_TOLERANCE * size[:, None]] = 0.0
    return d


def _per_cell(points: np.ndarray, cells: np.ndarray, current: np.ndarray | None) -> np.ndarray:
    """Where each cell's vertices are now, (m, d+1, 3): ``current`` as node positions (n, d)
    or per cell vertex (m, d+1, d) (a body already cut: each cell's own copies of its nodes),
    default the rest ``points``."""
    if current is None:
        return _as3d(points)[cells]
    current = np.asarray(current, dtype=float)
    if current.ndim == 3:
        if current.shape[2] == 2:
            current = np.concatenate([current, np.zeros(current.shape[:2] + (1,))], axis=2)
        return current
    return _as3d(current)[cells]


def cut_cells(
    points: np.ndarray, cells: np.ndarray, cut: PlanarCut, current: np.ndarray | None = None
) -> np.ndarray:
    """Indices of the cells the cut crosses completely: its plane has vertices strictly on
    both sides and its section of the cell lies inside the cut's polygon. ``current``: where
    the points are now, as node positions (n, d) or per cell vertex (m, d+1, d) (default
    ``points``): the blade cuts the body as it is."""
    x_cell = _per_cell(points, cells, current)
    return _crossed(x_cell, _distances(x_cell, cut), cut)


def _crossed(x_cell: np.ndarray, d: np.ndarray, cut: PlanarCut) -> np.ndarray:
    """The cells (indices) whose vertex distances d (m, d+1) to the cut's plane have both
    signs and whose section lies in its polygon (x_cell: where their vertices are)."""
    crossed = np.flatnonzero((d.max(axis=1) > 0.0) & (d.min(axis=1) < 0.0))
    inside = sections_inside(x_cell[crossed], d[crossed], cut.polygon, cut.normal)
    return crossed[inside].astype(np.int64)


def _inside_polygon(q: np.ndarray, cut: PlanarCut, tol: float) -> bool:
    """Whether points q (k, 3) in the cut's plane lie in its convex polygon (within tol)."""
    poly = cut.polygon
    n = cut.normal
    centre = poly.mean(axis=0)
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        inward = np.cross(n, b - a)
        if inward @ (centre - a) < 0.0:
            inward = -inward
        inward = inward / np.linalg.norm(inward)
        if np.any((q - a) @ inward < -tol):
            return False
    return True


def _as3d(points: np.ndarray) -> np.ndarray:
    points = np.asarray(points, dtype=float)
    if points.shape[1] == 2:
        return np.column_stack([points, np.zeros(len(points))])
    return points


def _measure(points: np.ndarray) -> float:
    """Volume (3D) or area (2D, points in a plane) of the convex hull of ``points``."""
    from scipy.spatial import ConvexHull, QhullError

    if len(points) < 3:
        return 0.0
    centred = points - points.mean(axis=0)
    # the points' own dimension: drop the directions they do not span (a 2D mesh's z)
    _, s, vt = np.linalg.svd(centred, full_matrices=False)
    rank = int(np.sum(s > 1e-12 * max(s[0], 1e-300)))
    if rank < 2 or len(points) <= rank:
        return 0.0
    try:
        return float(ConvexHull(centred @ vt[:rank].T).volume)
    except QhullError:  # flat within round-off
        return 0.0


def _clip(poly: np.ndarray, d: np.ndarray, side: int) -> tuple[np.ndarray, np.ndarray]:
    """A convex polygon (k, 3) with signed distances d (k,) clipped to ``side`` of the plane
    (Sutherland-Hodgman); returns the polygon and its points' distances (0 on the plane)."""
    out, dist = [], []
    k = len(poly)
    for i in range(k):
        p, q, dp, dq = poly[i], poly[(i + 1) % k], side * d[i], side * d[(i + 1) % k]
        if dp >= 0.0:
            out.append(p)
            dist.append(d[i])
        if dp * dq < 0.0:
            t = dp / (dp - dq)
            out.append(p + t * (q - p))
            dist.append(0.0)
    return np.array(out).reshape(-1, poly.shape[1]), np.array(dist)


def _face_part(face: np.ndarray, constraints: list) -> float:
    """Area of a face (3, 3) (2D: the length of an edge (2, 3)) where every constraint
    (distances of its points to a cut (3,), side) holds; the distances are linear on the face."""
    poly = face
    dists = [np.asarray(d, dtype=float) for d, _ in constraints]
    for k, (_, side) in enumerate(constraints):
        carried = np.column_stack([poly, *[dd[:, None] for dd in dists]])
        clipped, _ = _clip(carried, dists[k], side)
        if len(clipped) == 0:
            return 0.0
        poly = clipped[:, :3]
        dists = [clipped[:, 3 + j] for j in range(len(dists))]
    if face.shape[0] == 2:  # an edge of a triangle mesh: the length of what is left
        if len(poly) < 2:
            return 0.0
        return float(np.linalg.norm(poly.max(axis=0) - poly.min(axis=0)))
    return _measure(poly)


def _face_on_cut(face_now: np.ndarray, cut: PlanarCut) -> bool:
    """Whether a mesh face (3, 3) (2D: an edge), where it is now, lies in the cut's plane
    inside its polygon."""
    size = float(np.linalg.norm(face_now.max(axis=0) - face_now.min(axis=0)))
    if np.any(np.abs((face_now - cut.point) @ cut.normal) > PLANE_TOLERANCE * size):
        return False
    return _inside_polygon(face_now, cut, 1e-9 * size)


def _components(cells: np.ndarray, n_points: int) -> int:
    """Connected components of cells joined through shared points."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m, k = cells.shape
    rows = np.repeat(np.arange(m), k)
    graph = coo_matrix((np.ones(m * k), (rows, m + cells.ravel())), shape=(m + n_points,) * 2)
    _, labels = connected_components(graph, directed=False)
    return len(np.unique(labels[:m]))


def _face_parts(x3, cells, cuts, owner, node_d, parent, side, nodes, ca, cb) -> np.ndarray:
    """The fraction (f,) of each face (its global ``nodes`` (f, d)) where the material of copy
    ca and of copy cb both lie: 1 for two whole cells, the face's part on the side of the one
    cut copy, or on the common side of two copies of one cut (none on opposite sides); faces
    between copies of two different cuts are clipped one by one (a cell is cut once, so these
    are few)."""

    def face_d(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The signed distances (f, d) of the face's nodes to copy c's cut, times its side."""
        e = parent[c]
        where = np.argmax(cells[e][:, :, None] == nodes[:, None, :], axis=1)
        cut = np.maximum(owner[e], 0)
        dist = np.stack(node_d)[cut[:, None], e[:, None], where] if node_d else 0.0 * where
        return dist * side[c][:, None], cut

    part = np.ones(len(nodes))
    if not len(nodes):
        return part
    da, ka = face_d(ca)
    db, kb = face_d(cb)
    cut_a, cut_b = side[ca] != 0, side[cb] != 0
    only_a, only_b = cut_a & ~cut_b, cut_b & ~cut_a
    part[only_a] = positive_fraction(da[only_a])
    part[only_b] = positive_fraction(db[only_b])
    same = cut_a & cut_b & (ka == kb)
    flat = np.all(da == 0.0, axis=1) | np.all(db == 0.0, axis=1)
    agree = same & (side[ca] == side[cb]) & ~flat
    part[agree] = np.minimum(positive_fraction(da[agree]), positive_fraction(db[agree]))
    part[same & (side[ca] != side[cb]) & ~flat] = 0.0
    for i in np.flatnonzero(cut_a & cut_b & (~same | flat)):  # two cuts meet on this face
        face = x3[nodes[i]]
        constraints = []
        for c in (ca[i], cb[i]):
            e = int(parent[c])
            where = [int(np.flatnonzero(cells[e] == v)[0]) for v in nodes[i]]
            constraints.append((node_d[owner[e]][e][where], int(side[c])))
        part[i] = _face_part(face, constraints) / max(_face_part(face, []), 1e-300)
    return part


def _facet_table(cells: np.ndarray):
    """``mesh.boundary.facet_table`` of ``cells``, kept for the last mesh asked (a body cut step
    after step asks for its original mesh's every time)."""
    from tissuesim.mesh.boundary import facet_table

    cached = _FACETS.get("last")
    if cached is not None and cached[0].shape == cells.shape and np.array_equal(cached[0], cells):
        return cached[1]
    table = facet_table(cells)
    _FACETS["last"] = (cells.copy(), table)
    return table


_FACETS: dict = {}


def _node_groups(x3, x_cell, cells, cuts, owner, node_d, parent, side) -> np.ndarray:
    """The group (a label) of every node slot (copy, local node), (copies * (d+1),): slots of
    two copies sharing a face are joined when their material meets on it; a face the cut runs
    along joins nothing. Whole cells on both sides of a face join at once; faces next to a cut
    cell are looked at one by one (there are few)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m, k = cells.shape
    copies = len(parent)
    facets, _, inverse, counts = _facet_table(cells)
    # the two (cell, local facet) entries of every interior facet
    by_facet = np.argsort(inverse, kind="stable")
    shared = counts[inverse[by_facet]] == 2
    pairs = by_facet[shared].reshape(-1, 2)
    cell_a, cell_b = pairs[:, 0] // k, pairs[:, 1] // k
    face_nodes = facets[pairs[:, 0]]  # (f, d) global nodes of each interior facet
    # faces a cut runs along: every vertex on its plane (where the body is now), in its polygon
    on_cut = np.zeros(len(pairs), dtype=bool)
    where_a = np.argmax(cells[cell_a][:, :, None] == face_nodes[:, None, :], axis=1)
    x_face = x_cell[cell_a[:, None], where_a]  # (f, d, 3) where cell a's face is now
    size = np.linalg.norm(np.ptp(x_face, axis=1), axis=1)
    for cut in cuts:  # a vectorised plane test first: few faces lie in the plane
        dist = np.abs((x_face - cut.point) @ cut.normal)
        for f in np.flatnonzero(np.all(dist <= PLANE_TOLERANCE * size[:, None], axis=1)):
            on_cut[f] = on_cut[f] or _face_on_cut(x_face[f], cut)
    copy_of_whole = np.full(m, -1)
    whole = np.flatnonzero(side == 0)
    copy_of_whole[parent[whole]] = whole
    rows, cols = [], []

    def slots(c: np.ndarray, e: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """Slot ids (f, d) of ``nodes`` (f, d) in copies c (f,) of cells e (f,)."""
        where = np.argmax(cells[e][:, :, None] == nodes[:, None, :], axis=1)  # (f, d)
        return c[:, None] * k + where

    plain = (copy_of_whole[cell_a] >= 0) & (copy_of_whole[cell_b] >= 0) & ~on_cut
    if plain.any():
        rows.append(slots(copy_of_whole[cell_a[plain]], cell_a[plain], face_nodes[plain]).ravel())
        cols.append(slots(copy_of_whole[cell_b[plain]], cell_b[plain], face_nodes[plain]).ravel())
    # faces next to a cut cell: every pair (copy of one cell, copy of the other) whose material
    # meets on the face, all at once; the copies of a cell are consecutive in ``parent``
    todo = np.flatnonzero(~plain & ~on_cut)
    by_parent = np.argsort(parent, kind="stable")
    first = np.searchsorted(parent[by_parent], np.arange(m))
    count = np.bincount(parent, minlength=m)
    fa, ca, cb = [], [], []
    for i in range(2):  # at most two copies per cell
        for j in range(2):
            ok = (count[cell_a[todo]] > i) & (count[cell_b[todo]] > j)
            f = todo[ok]
            fa.append(f)
            ca.append(by_parent[first[cell_a[f]] + i])
            cb.append(by_parent[first[cell_b[f]] + j])
    f, ca, cb = np.concatenate(fa), np.concatenate(ca), np.concatenate(cb)
    part = _face_parts(x3, cells, cuts, owner, node_d, parent, side, face_nodes[f], ca, cb)
    meet = part > EMPTY
    rows.append(slots(ca[meet], cell_a[f[meet]], face_nodes[f[meet]]).ravel())
    cols.append(slots(cb[meet], cell_b[f[meet]], face_nodes[f[meet]]).ravel())
    n = copies * k
    r = np.concatenate([np.zeros(0, dtype=np.int64), *rows])
    c = np.concatenate([np.zeros(0, dtype=np.int64), *cols])
    graph = coo_matrix((np.ones(len(r)), (r, c)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def _levels(x_cell, cells, cuts, node_d, owner, parent, side, origin) -> np.ndarray:
    """Each copy's material level at its vertices (copies, d+1): a cut copy's signed distance
    to its cut's plane times its side; a whole cell on one side of a cut that shares a node with
    a cell it cuts, or a node it parts on its plane (a cut along faces), its distance on that
    side (the cut faces' contact surfaces shave such cells where they come close to the plane:
    contact/cut_surface.py); +inf else."""
    copies, k = len(parent), cells.shape[1]
    level = np.full((copies, k), np.inf)
    if not node_d:
        return level
    d_all = np.stack(node_d)  # (cuts, m, k)
    copied = side != 0
    level[copied] = d_all[owner[parent[copied]], parent[copied]] * side[copied, None]
    whole = np.flatnonzero(~copied)
    n = int(cells.max()) + 1
    x_node = np.zeros((n, 3))
    x_node[cells] = x_cell  # a node's position in (one of) its cells
    parted = np.unique(origin[n:])  # original nodes that have copies
    size = float(np.linalg.norm(np.ptp(x_node, axis=0)))
    for j, cut in enumerate(cuts):  # few cuts
        near = np.zeros(n, dtype=bool)
        near[cells[owner == j]] = True
        on_plane = np.abs((x_node[parted] - cut.point) @ cut.normal) <= PLANE_TOLERANCE * size
        near[parted[on_plane]] = True
        e = parent[whole]
        d = d_all[j][e]
        pick = near[cells[e]].any(axis=1) & np.isinf(level[whole, 0])
        up, down = pick & np.all(d >= 0.0, axis=1), pick & np.all(d <= 0.0, axis=1)
        level[whole[up]] = d[up]
        level[whole[down]] = -d[down]
    return level


def virtual_node_cut(
    points: np.ndarray,
    cells: np.ndarray,
    cuts: list[PlanarCut],
    current: np.ndarray | None = None,
    prior: tuple[np.ndarray, np.ndarray] | None = None,
) -> VirtualNodeMesh:
    """Cut a P1 mesh (rest points (n, d), cells (m, d+1), d = 2 or 3) by ``cuts``: every cell
    one of them crosses completely (``cut_cells``) becomes a copy per side holding material;
    nodes are duplicated where the material around them separates (see the module docstring).

    ``current``: where the points are now, as node positions (n, d) or per cell vertex
    (m, d+1, d) (default the rest points). The blade cuts the body as it is: a node's side is
    its signed distance to the cut's plane now, which is linear in each element, so each
    cell's cut is the plane in its rest shape where that distance is zero, and the fractions
    and face parts are of rest volume (mass).

    ``prior``: (cut index (m,), -1 for none, of the cells an earlier call cut; the node
    distances (k, n) to the first k cuts that call used, NaN for nodes it did not): a node
    keeps its distance to a cut from the first time a cell around it was cut (a blade
    advancing step by step cuts each cell once, where the body was when it crossed it, and the
    level stays one continuous function across cells cut at different times), and a cell an
    earlier cut took that another cut crosses now is refused."""
    cells = np.asarray(cells, dtype=np.int64)
    x3 = _as3d(points)
    x_cell = _per_cell(points, cells, current)
    node_d = [_distances(x_cell, cut) for cut in cuts]  # per cut: (m, d+1)
    prior_owner = np.full(len(cells), -1) if prior is None else np.asarray(prior[0])
    if prior is not None:
        for j, frozen in enumerate(np.asarray(prior[1], dtype=float)[: len(cuts)]):
            at = frozen[cells]
            node_d[j] = np.where(np.isfinite(at), at, node_d[j])
    dim = np.asarray(points).shape[1]
    if cells.shape[1] != dim + 1:
        raise InputError(
            f"virtual_node_cut takes P1 simplices ({dim + 1} nodes), not {cells.shape[1]}"
        )
    owner = prior_owner.copy()
    for k, cut in enumerate(cuts):
        hit = _crossed(x_cell, node_d[k], cut)  # frozen node distances where there are
        hit = hit[owner[hit] != k]  # cut by this cut before: kept as it was
        twice = hit[owner[hit] >= 0]
        if twice.size:
            raise InputError(
                f"cell {int(twice[0])} is crossed by two cuts; the virtual node algorithm here "
                "cuts a cell once: keep cuts apart by an element or merge them into one plane"
            )
        owner[hit] = k
    # the copies: every uncut cell once, then one per side holding material of each cut cell
    cut_ids = np.flatnonzero(owner >= 0)
    parent = [np.flatnonzero(owner < 0)]
    # each cut cell's fraction on the + side, in closed form (plane_split.py): the distances
    # are linear in the element, so the rest-shape fraction is that of the vertex values
    d_cut = np.stack(node_d)[owner[cut_ids], cut_ids] if len(cut_ids) else np.zeros((0, dim + 1))
    f_plus = positive_fraction(d_cut) if len(cut_ids) else np.zeros(0)
    f_both = np.column_stack([f_plus, 1.0 - f_plus]).ravel()  # + then - per cell
    keep = f_both > EMPTY
    n_whole = len(parent[0])
    parent = np.concatenate([parent[0], np.repeat(cut_ids, 2)[keep]])
    side = np.concatenate(
        [np.zeros(n_whole, dtype=np.int64), np.tile(np.array([1, -1]), len(cut_ids))[keep]]
    )
    fraction = np.concatenate([np.ones(n_whole), f_both[keep]])
    copies, k = len(parent), dim + 1
    labels = _node_groups(x3, x_cell, cells, cuts, owner, node_d, parent, side)
    # a slot's node: the original node for its first group, a new (duplicate) node after
    slot_node = cells[parent].ravel()
    # unique (node, group) pairs by one int64 key (a row-wise unique sorts far slower)
    span = int(labels.max(initial=0)) + 1
    keys, first, group = np.unique(
        slot_node.astype(np.int64) * span + labels, return_index=True, return_inverse=True
    )
    pairs = np.column_stack([keys // span, keys % span])
    order = np.lexsort((first, pairs[:, 0]))  # by node, then by where the group first appears
    is_first = np.ones(len(pairs), dtype=bool)
    is_first[order[1:]] = pairs[order[1:], 0] != pairs[order[:-1], 0]
    node = np.empty(len(pairs), dtype=np.int64)
    node[is_first] = pairs[is_first, 0]
    dup = order[~is_first[order]]
    node[dup] = len(x3) + np.arange(len(dup))
    origin = np.concatenate([np.arange(len(x3)), pairs[dup, 0]])
    new_cells = node[group.reshape(-1)]
    pts = np.asarray(points, dtype=float)[origin]
    level = _levels(x_cell, cells, cuts, node_d, owner, parent, side, origin)
    return VirtualNodeMesh(
        level=level,
        points=pts,
        cells=new_cells.reshape(copies, k),
        fraction=fraction,
        parent=parent,
        side=side,
        cut=np.where(side == 0, -1, owner[parent]),
        origin=origin,
    )
