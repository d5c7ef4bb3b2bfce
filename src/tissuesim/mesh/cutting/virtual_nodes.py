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
velocities across the cut). A cell several cuts cross is split into the convex parts between
them (one copy per sign vector holding material): where two cuts meet or cross, or a blade
passes again through a cell cut before.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.cutting.node_groups import node_groups
from tissuesim.mesh.cutting.planar_cut import EMPTY, PLANE_TOLERANCE, PlanarCut
from tissuesim.mesh.cutting.plane_split import positive_fraction, region_fractions
from tissuesim.mesh.cutting.swept_cut import SweptCut
from tissuesim.mesh.rows import row_max, rows_all, rows_any

__all__ = ["PlanarCut", "VirtualNodeMesh", "cut_cells", "virtual_node_cut"]


@dataclass(frozen=True)
class Constraints:
    """Rows of (copy, cut, side, level (r, d+1)): a copy's signed distance to a cut's plane at
    its vertices times its side (its material is where every row of it is >= 0)."""

    copy: np.ndarray
    cut: np.ndarray
    side: np.ndarray
    level: np.ndarray

    def join(self, other: Constraints) -> Constraints:
        return Constraints(
            *(np.concatenate([a, b]) for a, b in zip(self.rows(), other.rows(), strict=True))
        )

    def rows(self) -> tuple[np.ndarray, ...]:
        return self.copy, self.cut, self.side, self.level


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
    #: the further cuts of copies of cells several cuts cross (their first is ``cut``/``side``)
    extra: Constraints | None = None
    #: whole cells next to several cuts, and copies with a node a cut along faces parts (one
    #: that does not cross their cell): their distance to each such
    #: further cut on their side (``level`` holds the first), which the cut faces' contact
    #: surfaces shave them by; never their material
    shave: Constraints | None = None

    def constraints(self) -> Constraints:
        """Every (copy, cut) pair of the cut copies: each copy's first cut, then the further
        cuts of copies of cells several cuts cross; a copy's material is where all its
        levels are >= 0."""
        cut = np.flatnonzero(self.side != 0)
        first = Constraints(cut, self.cut[cut], self.side[cut], self.level[cut])
        return first if self.extra is None else first.join(self.extra)

    @property
    def several(self) -> np.ndarray:
        """(copies,) whether each copy stands for a part of a cell several cuts cross."""
        out = np.zeros(len(self.cells), dtype=bool)
        if self.extra is not None:
            out[self.extra.copy] = True
        return out

    @property
    def n_cell_cuts(self) -> int:
        """How many (cell, cut) pairs there are: each cell a cut has crossed, once per cut."""
        c = self.constraints()
        return len(np.unique(self.parent[c.copy] * max(len(self.cells), 1) + c.cut))

    @property
    def material_slots(self) -> np.ndarray:
        """(copies, d+1) whether each copy's vertex lies in its material (else the copy's
        node there is virtual)."""
        inside = np.ones(self.cells.shape, dtype=bool)
        if self.level is not None:
            inside = self.level >= 0.0
            if self.extra is not None:
                np.logical_and.at(inside, self.extra.copy, self.extra.level >= 0.0)
        return inside

    @property
    def material_nodes(self) -> np.ndarray:
        """(p,) whether each point lies in the material of a cell that uses it (False for a
        virtual node only: a support or a grasper there would hold empty space)."""
        out = np.zeros(len(self.points), dtype=bool)
        out[self.cells[self.material_slots]] = True
        return out

    @cached_property  # the cut's report, its crumbs and every step's report ask for it
    def point_pieces(self) -> np.ndarray:
        """Each point's piece of material (``node_pieces``)."""
        return node_pieces(self.cells, len(self.points))

    @property
    def n_pieces(self) -> int:
        """Connected pieces of material (cells joined through shared points)."""
        return int(np.count_nonzero(np.bincount(self.point_pieces[self.cells[:, 0]])))

    def to_mesh(self, mesh):
        """The cut as a ``Mesh`` of the original ``mesh``: its point sets hold every copy of
        their nodes, its cell sets the copies of their cells, its facet sets the boundary
        facets over copies of their nodes; ``cell_fractions`` weights the copies."""
        from tissuesim.mesh.mesh import Mesh

        point_sets = {
            name: np.flatnonzero(np.isin(self.origin, ids)) for name, ids in mesh.point_sets.items()
        }
        cell_sets = {
            name: np.flatnonzero(np.isin(self.parent, ids)) for name, ids in mesh.cell_sets.items()
        }
        facet_sets = {name: self._facet_set(mesh, ids) for name, ids in mesh.facet_sets.items()}
        return Mesh(
            self.points,
            self.cells,
            point_sets=point_sets,
            facet_sets=facet_sets,
            cell_sets=cell_sets,
            source=f"{mesh.source} (cut)",
            cell_fractions=self.fraction,
            cell_levels=self.level,
            cell_more_levels=self._more_levels(),
        )

    def _more_levels(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The further levels of copies (``extra``) and of cells next to further cuts
        (``shave``), as rows (copy, level), for the mesh's ``cell_more_levels``."""
        rows = [r for r in (self.extra, self.shave) if r is not None]
        if not rows:
            return None
        return (
            np.concatenate([r.copy for r in rows]),
            np.concatenate([r.level for r in rows]),
        )

    def _facet_set(self, mesh, ids: np.ndarray) -> np.ndarray:
        """The boundary facets (k, d) of the cut mesh whose original nodes make a facet of
        ``ids`` (a facet set of the original ``mesh``), outward, in the order of their cells:
        a copy's facet stands for its cell's, so only the copies of the set's facets are
        looked at (two facets with the same nodes have the same original one), and of those
        the ones no other copy shares bound the cut mesh."""
        from tissuesim.mesh.queries.boundary import all_facets, match_facets
        from tissuesim.mesh.queries.interior_faces import interior_faces

        faces = interior_faces(mesh.cells)
        k = self.cells.shape[1]
        in_set = match_facets(np.asarray(ids), faces.unique) >= 0
        original = faces.facet_id[(self.parent[:, None] * k + np.arange(k)).ravel()]
        slot = np.flatnonzero(in_set[original])  # copy c's local facet l: slot c k + l
        local = all_facets(np.arange(k)[None])[0]  # each local facet's slots
        rows = self.cells[slot // k][np.arange(len(slot))[:, None], local[slot % k]]
        same = match_facets(rows, rows)  # the first copy with the same nodes
        return rows[np.bincount(same, minlength=len(rows))[same] == 1]


def _distances(x_cell: np.ndarray, cut: PlanarCut | SweptCut) -> np.ndarray:
    """Signed distances (m, d+1) of the cells' vertices (x_cell (m, d+1, 3), where each cell's
    vertices are) to the cut (its plane; a swept cut's nearest plane), snapped to 0 within
    PLANE_TOLERANCE of the cell's size."""
    d = cut.distances(x_cell)
    e = x_cell - x_cell[:, :1]  # the norm's sums of squares, then one root per cell: its max
    square = e[..., 0] * e[..., 0]
    for i in range(1, e.shape[2]):
        square += e[..., i] * e[..., i]
    size = np.sqrt(row_max(square))
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
    crossed = np.flatnonzero((row_max(d) > 0.0) & (row_max(-d) > 0.0))
    inside = cut.sections_inside(x_cell[crossed], d[crossed])
    return crossed[inside].astype(np.int64)


def _as3d(points: np.ndarray) -> np.ndarray:
    points = np.asarray(points, dtype=float)
    if points.shape[1] == 2:
        return np.column_stack([points, np.zeros(len(points))])
    return points


def node_pieces(cells: np.ndarray, n_points: int) -> np.ndarray:
    """Each point's piece (n_points,): the connected components of the cells joined through
    shared points (a point of no cell is a piece of its own)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m, k = cells.shape  # a cell's points joined to its first
    rows = np.repeat(cells[:, 0], k - 1)
    graph = coo_matrix((np.ones(m * (k - 1)), (rows, cells[:, 1:].ravel())), shape=(n_points,) * 2)
    return connected_components(graph, directed=False)[1]


def _levels(x_cell, cells, cuts, d_all, taken, copy_cut, parent, side, origin) -> np.ndarray:
    """Each copy's material level at its vertices (copies, d+1): a cut copy's signed distance
    to its (first) cut's plane times its side; a whole cell on one side of a cut that shares a
    node with a cell it cuts, or a node it parts on its plane (a cut along faces), its distance
    on that side (the cut faces' contact surfaces shave such cells where they come close to the
    plane: contact/cut/surface.py); +inf else. d_all (cuts, m, d+1): the cells' vertex
    distances; ``taken`` (m, cuts) which cuts cut each cell. Returns the levels and, for whole
    cells next to several cuts and for copies with a node a cut along faces parts, the further
    ones as rows (``VirtualNodeMesh.shave``)."""
    copies, k = len(parent), cells.shape[1]
    level = np.full((copies, k), np.inf)
    shave: list = []
    if not len(d_all):
        return level, None
    copied = side != 0
    level[copied] = d_all[copy_cut[copied], parent[copied]] * side[copied, None]
    whole = np.flatnonzero(~copied)
    n = int(cells.max()) + 1
    x_node = np.zeros((n, 3))
    x_node[cells] = x_cell  # a node's position in (one of) its cells
    parted = np.unique(origin[n:])  # original nodes that have copies
    size = float(np.linalg.norm(np.ptp(x_node, axis=0)))
    for j, cut in enumerate(cuts):  # few cuts
        near = np.zeros(n, dtype=bool)
        near[cells[taken[:, j]]] = True
        on_plane = np.abs(cut.distances(x_node[parted])) <= PLANE_TOLERANCE * size
        near[parted[on_plane]] = True
        e = parent[whole]
        d = d_all[j][e]
        pick = rows_any(near[cells[e]])
        up, down = pick & rows_all(d >= 0.0), pick & rows_all(d <= 0.0)
        side_j = np.where(up, 1, np.where(down, -1, 0))
        more = (side_j != 0) & np.isfinite(level[whole, 0])  # a further cut next to it
        level_j = d * side_j[:, None]
        first = (side_j != 0) & ~more
        level[whole[first]] = level_j[first]
        if more.any():
            shave.append((whole[more], np.full(more.sum(), j), side_j[more], level_j[more]))
        # copies of cells other cuts cross with a node this one parts on its plane (a cut
        # along faces, which copies no cell, crossed by one through cells): shaved by it as
        # a whole cell there is (copies next to the cells a cut crosses are bounded by those
        # cells' own levels, and shaving them too brought faces together where a T ends)
        on_faces = np.zeros(n, dtype=bool)
        on_faces[parted[on_plane]] = True
        cut_copies = np.flatnonzero(copied)
        e = parent[cut_copies]
        d = d_all[j][e]
        pick = rows_any(on_faces[cells[e]]) & ~taken[e, j]
        side_j = np.where(pick & rows_all(d >= 0.0), 1, np.where(pick & rows_all(d <= 0.0), -1, 0))
        nearby = side_j != 0
        if nearby.any():
            shave.append((cut_copies[nearby], np.full(nearby.sum(), j), side_j[nearby],
                          d[nearby] * side_j[nearby, None]))  # fmt: skip
    return level, _rows(shave, k)


def _rows(rows: list, k: int) -> Constraints | None:
    """Lists of (copy, cut, side, level) arrays as one ``Constraints``, None for none."""
    if not rows:
        return None
    return Constraints(*(np.concatenate(part) for part in zip(*rows, strict=True)))


def _taken(prior, m: int, n_cuts: int) -> np.ndarray:
    """(m, n_cuts) which cuts an earlier call cut each cell: ``prior``'s first entry, a cut
    index per cell (-1 none) or such a matrix."""
    taken = np.zeros((m, n_cuts), dtype=bool)
    if prior is None:
        return taken
    before = np.asarray(prior[0])
    if before.ndim == 1:
        rows = np.flatnonzero(before >= 0)
        taken[rows, before[rows]] = True
    else:
        taken[:, : before.shape[1]] = before[:, :n_cuts]
    return taken


def _copies(taken: np.ndarray, d_all: np.ndarray, dim: int):
    """The copies of the cut cells, cell by cell: a cell one cut crosses gets its + then its -
    side; a cell C cuts cross gets one copy per sign vector (bit i of its index: the side of
    its i-th cut, 0 for +), each its convex part of the cell (``plane_split.region_fractions``).
    Returns (parent, side and cut of each copy's first cut, fraction, the further cuts as
    (copy index among these, cut, side) rows); empty parts are dropped."""
    n_by_cell = taken.sum(axis=1)
    cut_ids = np.flatnonzero(n_by_cell > 0)
    count = np.left_shift(1, n_by_cell[cut_ids])  # 2^C copies per cell
    parent = np.repeat(cut_ids, count)
    start = np.cumsum(count) - count
    index = np.arange(len(parent)) - np.repeat(start, count)  # the sign vector, bit by bit
    first = np.argmax(taken[cut_ids], axis=1)  # each cell's first cut
    cut = np.repeat(first, count)
    side = np.where(index & 1, -1, 1)
    fraction = np.zeros(len(parent))
    one = np.repeat(n_by_cell[cut_ids] == 1, count)
    plus = one & (side > 0)
    f_plus = positive_fraction(d_all[cut[plus], parent[plus]]) if plus.any() else np.zeros(0)
    fraction[plus] = f_plus
    fraction[one & (side < 0)] = 1.0 - f_plus
    several = np.flatnonzero(~one)
    extra_rows = []
    if several.size:  # cells where cuts meet: few
        cuts_of = [np.flatnonzero(row) for row in taken[parent[several]]]
        most = max(len(c) for c in cuts_of)
        d = np.full((len(several), most, dim + 1), np.inf)
        for r, (c, cs) in enumerate(zip(several, cuts_of, strict=True)):
            signs = np.where((index[c] >> np.arange(len(cs))) & 1, -1, 1)
            d[r, : len(cs)] = d_all[cs, parent[c]] * signs[:, None]
            extra_rows += [(c, j, sg) for j, sg in zip(cs[1:], signs[1:], strict=True)]
        f = region_fractions(d)
        total = np.bincount(parent[several], weights=f)[parent[several]]
        fraction[several] = f / total  # the parts of a cell add up to it exactly
    keep = fraction > EMPTY
    new_index = np.cumsum(keep) - 1
    extra = np.array([(new_index[c], j, sg) for c, j, sg in extra_rows if keep[c]], dtype=np.int64)
    return parent[keep], side[keep], cut[keep], fraction[keep], extra.reshape(-1, 3)


def virtual_node_cut(
    points: np.ndarray,
    cells: np.ndarray,
    cuts: list[PlanarCut],
    current: np.ndarray | None = None,
    prior: tuple[np.ndarray, np.ndarray] | None = None,
) -> VirtualNodeMesh:
    """Cut a P1 mesh (rest points (n, d), cells (m, d+1), d = 2 or 3) by ``cuts``: every cell
    one of them crosses completely (``cut_cells``) becomes a copy per side holding material, a
    cell several cross one copy per part between them that holds material; nodes are
    duplicated where the material around them separates (see the module docstring).

    ``current``: where the points are now, as node positions (n, d) or per cell vertex
    (m, d+1, d) (default the rest points). The blade cuts the body as it is: a node's side is
    its signed distance to the cut's plane now, which is linear in each element, so each
    cell's cut is the plane in its rest shape where that distance is zero, and the fractions
    and face parts are of rest volume (mass).

    ``prior``: (which cuts an earlier call cut each cell, (m, k) bool, or a cut index (m,)
    with -1 for none; the node distances (k, n) to the first k cuts that call used, NaN for
    nodes it did not): a node keeps its distance to a cut from the first time a cell around it
    was cut (a blade advancing step by step cuts each cell once, where the body was when it
    crossed it, and the level stays one continuous function across cells cut at different
    times); another cut crossing a cell cut before splits its parts further."""
    cells = np.asarray(cells, dtype=np.int64)
    x3 = _as3d(points)
    x_cell = _per_cell(points, cells, current)
    node_d = [_distances(x_cell, cut) for cut in cuts]  # per cut: (m, d+1)
    if prior is not None:
        for j, frozen in enumerate(np.asarray(prior[1], dtype=float)[: len(cuts)]):
            at = frozen[cells]
            node_d[j] = np.where(np.isfinite(at), at, node_d[j])
    dim = np.asarray(points).shape[1]
    if cells.shape[1] != dim + 1:
        raise InputError(
            f"virtual_node_cut takes P1 simplices ({dim + 1} nodes), not {cells.shape[1]}"
        )
    taken = _taken(prior, len(cells), len(cuts))
    for k, cut in enumerate(cuts):
        taken[_crossed(x_cell, node_d[k], cut), k] = True  # a cell cut before stays so
    d_all = np.stack(node_d) if node_d else np.zeros((0, *cells.shape))  # (cuts, m, d+1)
    # the copies: every uncut cell once, then one per part holding material of each cut cell;
    # the distances are linear in the element, so a part's rest-shape fraction is that of
    # the vertex values (in closed form for one cut: plane_split.py)
    whole = np.flatnonzero(~taken.any(axis=1))
    cut_parent, cut_side, cut_first, cut_fraction, extra = _copies(taken, d_all, dim)
    n_whole = len(whole)
    parent = np.concatenate([whole, cut_parent])
    side = np.concatenate([np.zeros(n_whole, dtype=np.int64), cut_side])
    copy_cut = np.concatenate([np.full(n_whole, -1), cut_first])
    fraction = np.concatenate([np.ones(n_whole), cut_fraction])
    extra[:, 0] += n_whole
    copies, k = len(parent), dim + 1
    row_copy, row_cut, row_side = extra.T
    more = Constraints(
        row_copy, row_cut, row_side, d_all[row_cut, parent[row_copy]] * row_side[:, None]
    )
    labels = node_groups(x3, x_cell, cells, cuts, taken, d_all, parent, side, copy_cut, more)
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
    level, shave = _levels(x_cell, cells, cuts, d_all, taken, copy_cut, parent, side, origin)
    return VirtualNodeMesh(
        level=level,
        points=pts,
        cells=new_cells.reshape(copies, k),
        fraction=fraction,
        parent=parent,
        side=side,
        cut=copy_cut,
        origin=origin,
        extra=more if len(extra) else None,
        shave=shave,
    )
