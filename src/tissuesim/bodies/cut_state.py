"""What a FEM body keeps of its cuts (virtual node algorithm, ``mesh/cutting/virtual_nodes.py``), so
that it can be cut again, step after step, as a blade advances.

Every cut is recomputed from the body's *original* mesh with all its cuts so far: the nodes of
cells an earlier call cut keep their distance to the cut from then (``prior``), so those cells
keep their cut as it was made and the level stays continuous across cells cut at different
times; other nodes take their distance where the body is now; the node slots are grouped
afresh. Each node of the new mesh continues a node of the current one (``carry``):
its slot's copy in the current mesh (the same parent cell and side, or the parent's whole copy
for a cell cut only now) names it, and positions, velocities, supports and graspers follow.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.cutting.plane_split import section_measures
from tissuesim.mesh.cutting.swept_cut import SweptCut
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, VirtualNodeMesh, virtual_node_cut
from tissuesim.mesh.queries.boundary import facet_measures
from tissuesim.mesh.queries.interior_faces import interior_faces
from tissuesim.mesh.rows import rows_any

__all__ = [
    "CutState",
    "attach_crumbs_in_contact",
    "bare_small_pieces",
    "follow_cells",
    "recut",
]


@dataclass
class CutState:
    """A cut body's ``original`` mesh and its cells' ``density``, the current cut (``vn``)
    and its ``cuts`` by name; ``rest``: the original cells' (shape gradients, rest volumes),
    which every copy of a cell keeps (None: computed anew from the cut mesh)."""

    original: object
    density: np.ndarray
    rest: tuple[np.ndarray, np.ndarray] | None = None
    vn: VirtualNodeMesh | None = None
    cuts: list[PlanarCut] = field(default_factory=list)
    names: list[str] = field(default_factory=list)
    #: (copies,) the copy before the last cut of the same cell and side as each copy, -1 none
    source: np.ndarray | None = field(default=None, repr=False)
    #: rest area of the mesh faces each cut parted (a cut along faces copies no cell)
    face_area: list[float] = field(default_factory=list)
    _parted: np.ndarray | None = field(default=None, repr=False)
    #: per cut, the rest area of its section in each cell (NaN: not cut by it)
    _sections: dict | None = field(default=None, repr=False)

    @classmethod
    def of_model(cls, model) -> CutState:
        """The state of a body not cut yet, from its P1 ``model``: its mesh, its cells'
        densities and the rest geometry its kinematics computed already."""
        k = model.kinematics
        plain = model.mesh.cell_fractions is None and k.points_per_cell == 1
        rest = (k.grads, k.weights) if plain else None  # weights: the rest volumes then
        return cls(model.mesh, np.asarray(model.density, dtype=float), rest)

    def prior(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(which cuts cut each original cell (m, cuts); each cut's node distances (cuts, n),
        NaN for nodes of no cell it cut): what the cuts so far froze (``virtual_node_cut``'s
        prior)."""
        if self.vn is None:
            return None
        taken = np.zeros((len(self.original.cells), len(self.cuts)), dtype=bool)
        frozen = np.full((len(self.cuts), self.original.n_points), np.nan)
        c = self.vn.constraints()
        cell = self.vn.parent[c.copy]
        taken[cell, c.cut] = True
        frozen[c.cut[:, None], self.original.cells[cell]] = c.level * c.side[:, None]
        return taken, frozen

    def cell_positions(self, positions: np.ndarray) -> np.ndarray:
        """Where each original cell's vertices are now (m, k, d): a cut cell's vertex where the
        copy whose material holds it is (its real node), the others their one copy's."""
        if self.vn is None:
            return positions[self.original.cells]
        vn = self.vn
        first = np.unique(vn.parent, return_index=True)[1]
        out = positions[vn.cells[first]]
        copy, vertex = np.nonzero(vn.material_slots & (vn.side != 0)[:, None])
        out[vn.parent[copy], vertex] = positions[vn.cells[copy, vertex]]
        return out

    def area(self, name: str) -> float:
        """The rest area of the cut called ``name`` so far (0 before it has cut anything)."""
        if self.vn is None or name not in self.names:
            return 0.0
        return float(self.areas(self.vn)[self.names.index(name)])

    def areas(self, vn: VirtualNodeMesh) -> np.ndarray:
        """The rest area (2D: length) of each cut's surface in ``vn`` (per cut index). A cut
        cell keeps its level, so its section is measured once (a blade going on measures the
        cells it crossed since)."""
        c = vn.constraints()
        m = len(self.original.cells)
        key = c.cut * m + vn.parent[c.copy]  # each (cut, cell) once, on its + side
        _, once = np.unique(np.where(c.side > 0, key, -1), return_index=True)
        once = once[c.side[once] > 0]
        cut, parent, level = c.cut[once], vn.parent[c.copy[once]], c.level[once]
        if self._sections is None:
            self._sections = {}
        measure = np.empty(len(once))
        for j in np.unique(cut):
            mine = np.flatnonzero(cut == j)
            known = self._sections.setdefault(int(j), np.full(m, np.nan))
            new = mine[np.isnan(known[parent[mine]])]
            known[parent[new]] = section_measures(
                self.original.points, self.original.cells[parent[new]], level[new]
            )
            measure[mine] = known[parent[mine]]
        sections = np.bincount(cut, weights=measure, minlength=len(self.cuts))
        faces = np.zeros(len(self.cuts))
        faces[: len(self.face_area)] = self.face_area
        return sections + faces

    def parted_faces(self, vn: VirtualNodeMesh) -> np.ndarray:
        """(faces,) whether each interior face of the original mesh (``interior_faces``)
        lies between two whole cells that no longer share all its nodes: a cut ran along it.
        Only a face with a node that has copies can be (the others are looked at no more)."""
        faces = interior_faces(self.original.cells)
        n = self.original.n_points
        copied = np.zeros(n, dtype=bool)
        copied[vn.origin[n:]] = True
        maybe = np.flatnonzero(rows_any(copied[faces.nodes]))
        whole = np.full(len(self.original.cells), -1)
        uncut = vn.side == 0
        whole[vn.parent[uncut]] = np.flatnonzero(uncut)
        a, b = whole[faces.cell_a[maybe]], whole[faces.cell_b[maybe]]
        both = (a >= 0) & (b >= 0)
        nodes_a = np.take_along_axis(vn.cells[a], faces.slot_a[maybe], axis=1)
        nodes_b = np.take_along_axis(vn.cells[b], faces.slot_b[maybe], axis=1)
        parted = np.zeros(len(faces.cell_a), dtype=bool)
        parted[maybe] = both & rows_any(nodes_a != nodes_b)
        return parted

    def _count_faces(self, vn: VirtualNodeMesh, index: int) -> None:
        """Credit cut ``index`` with the rest area of the faces this call parted."""
        parted = self.parted_faces(vn)
        new = parted if self._parted is None else parted & ~self._parted
        self._parted = parted
        while len(self.face_area) <= index:
            self.face_area.append(0.0)
        if np.any(new):
            nodes = interior_faces(self.original.cells).nodes[new]
            points = np.asarray(self.original.points, dtype=float)
            self.face_area[index] += float(facet_measures(points, nodes).sum())


def recut(
    state: CutState,
    cut: PlanarCut | SweptCut,
    name: str,
    positions: np.ndarray,
):
    """Cut again: ``cut`` as the cut called ``name`` (a new one, or the same plane with its
    swept polygon grown: a blade advancing; or the surface a blade swept once it left its
    plane), the body's nodes at ``positions`` now. Returns (the new VirtualNodeMesh, the
    current node each new node continues, the cut's index), or None when no new cell is
    cut."""
    cuts = list(state.cuts)
    if name in state.names and isinstance(cut, SweptCut):  # a blade off its plane goes on
        index = state.names.index(name)
        cuts[index] = cut  # the cells cut before keep their levels (prior)
    elif name in state.names:
        index = state.names.index(name)
        old = cuts[index]
        if isinstance(old, SweptCut):
            raise InputError(
                f"cut {name!r}: it follows a swept surface now; give a planar cut its own name"
            )
        same = abs(abs(float(old.normal @ cut.normal)) - 1.0) < 1e-9
        size = float(np.linalg.norm(np.ptp(state.original.points, axis=0)))
        if not same or abs(float((cut.point - old.point) @ old.normal)) > 1e-9 * size:
            raise InputError(
                f"cut {name!r}: a cut keeps its plane as it goes on (it moved out of it); give "
                "a cut in another plane its own name"
            )
        cuts[index] = PlanarCut(old.point, old.normal, cut.polygon)
    else:
        index = len(cuts)
        cuts.append(cut)
    x_cell = state.cell_positions(positions)
    vn = virtual_node_cut(
        state.original.points, state.original.cells, cuts, current=x_cell, prior=state.prior()
    )
    before = 0 if state.vn is None else state.vn.n_cell_cuts
    points = state.original.n_points if state.vn is None else len(state.vn.points)
    if vn.n_cell_cuts == before and len(vn.points) == points:
        return None  # no new element cut, no node parted (a cut along faces parts nodes only)
    carry, state.source = _carry(state.vn, vn)
    state.vn, state.cuts = vn, cuts
    if name not in state.names:
        state.names.append(name)
    state._count_faces(vn, index)
    return vn, carry, index


def attach_crumbs_in_contact(
    state: CutState, vn: VirtualNodeMesh, carry: np.ndarray, dhat: float, blade: bool
) -> tuple[VirtualNodeMesh, np.ndarray]:
    """The cut ``vn`` (and ``carry``) with its crumbs attached (``mesh/cutting/crumbs.py``): small
    pieces that have no contact surface at the barrier's ``dhat`` (``blade``: the gap of a body
    an instrument in contact cuts). Kept as the state's current cut. Unchanged when there is
    none (a contact surface is built to tell only when a small piece exists, and only round
    the small pieces: ``bare_small_pieces``)."""
    from tissuesim.mesh.cutting.crumbs import attach_crumbs, small_pieces

    small = small_pieces(vn, state.original.points)
    if not small.any():
        return vn, carry
    crumbs = bare_small_pieces(state, vn, small, dhat, blade)
    done = attach_crumbs(vn, carry, crumbs) if crumbs.any() else None
    if done is None:
        return vn, carry
    state.vn = done[0]
    return done[0], done[1]


def bare_small_pieces(
    state: CutState, vn: VirtualNodeMesh, small: np.ndarray, dhat: float, blade: bool
) -> np.ndarray:
    """(copies,) which copies of ``vn`` lie in a small piece (``small``) that has no contact
    surface (``contact/sliver_points.bare_pieces``), from the surface of a part of the mesh:
    every copy of the cells that share a node with a small piece's cells. A face's partners
    are copies of its own cell and of the cell across it, all in that part, so a small piece's
    faces and sections are what the whole surface gives them; faces the part leaves open
    belong to copies of other pieces, whose nodes a small piece does not use. The whole
    surface, built on every later cut event that frees the same crumb again, cost 0.04 s at
    1e4 tetrahedra."""
    from tissuesim.contact.cut.sliver_points import bare_pieces
    from tissuesim.contact.cut.thin_pieces import cells_of
    from tissuesim.contact.geometry.surfaces import cut_faces

    cells = state.original.cells
    touched = np.zeros(state.original.n_points, dtype=bool)
    touched[cells[np.unique(vn.parent[small])]] = True
    around = rows_any(touched[cells])  # original cells sharing a node with a small piece's
    part = np.flatnonzero(around[vn.parent])
    mesh = cells_of(vn.to_mesh(state.original), part)
    W, tri = cut_faces(mesh, dhat, blade)
    bare = np.zeros(len(vn.cells), dtype=bool)
    bare[part] = bare_pieces(mesh, W, tri)
    return small & bare


def _carry(old: VirtualNodeMesh | None, new: VirtualNodeMesh) -> tuple[np.ndarray, np.ndarray]:
    """The node of the current mesh each node of the new one continues (new n_points,), and
    the current copy of the same cell and part as each new copy, -1 for none (``source``)."""
    if old is None:
        return new.origin, np.where(new.side == 0, new.parent, -1)
    # the current copy standing for each new copy: same parent and side, else the whole one
    key_old = old.parent * 3 + (old.side + 1)
    order = np.argsort(key_old)
    key_new = new.parent * 3 + (new.side + 1)
    pos = np.minimum(np.searchsorted(key_old[order], key_new), len(order) - 1)
    found = key_old[order][pos] == key_new
    whole = new.parent * 3 + 1
    pos_whole = np.minimum(np.searchsorted(key_old[order], whole), len(order) - 1)
    stand = np.where(found, order[pos], order[pos_whole])
    same = np.where(found, order[pos], -1)
    _carry_parts(old, new, stand, same)
    old_node = old.cells[stand]  # (copies, k): the current node of every new slot
    carry = np.empty(len(new.points), dtype=np.int64)
    carry[new.cells.ravel()] = old_node.ravel()
    return carry, same


def _carry_parts(old: VirtualNodeMesh, new: VirtualNodeMesh, stand, same) -> None:
    """Where several cuts cross a cell (now or before), the current copy each new copy
    continues is the one whose cuts and sides are among the new copy's (a part split further
    continues the part it was split from); ``same`` where they are the same (few cells)."""
    cells = np.union1d(new.parent[new.several], old.parent[old.several])
    if not cells.size:
        return

    def signatures(vn: VirtualNodeMesh, copies: np.ndarray) -> dict:
        c = vn.constraints()
        out = {int(i): {} for i in copies}
        for i, cut, side in zip(c.copy, c.cut, c.side, strict=True):
            if int(i) in out:
                out[int(i)][int(cut)] = int(side)
        return out

    old_copies = np.flatnonzero(np.isin(old.parent, cells))
    new_copies = np.flatnonzero(np.isin(new.parent, cells))
    sig_old, sig_new = signatures(old, old_copies), signatures(new, new_copies)
    for n in new_copies:
        mine = sig_new[int(n)]
        for o in old_copies[old.parent[old_copies] == new.parent[n]]:
            theirs = sig_old[int(o)]
            if all(mine.get(cut) == side for cut, side in theirs.items()):
                stand[n] = o
                same[n] = o if theirs == mine else -1
                break


def follow_cells(
    old: VirtualNodeMesh | None, new: VirtualNodeMesh, cells: np.ndarray, barycentric: np.ndarray
) -> np.ndarray:
    """The cell of the new cut mesh that holds each point given by its cell of the current
    mesh (``old``'s copies; the original cells before any cut) and its barycentric coordinates
    there (unchanged: a copy keeps its element's shape): the whole copy of an uncut cell, or
    the copy of a cut one on whose side of the cut the point lies (something attached to the
    body, e.g. the connective tissue, follows the material it is attached to)."""
    cells = np.asarray(cells, dtype=np.int64)
    original = cells if old is None else old.parent[cells]
    order = np.argsort(new.parent, kind="stable")
    sorted_parent = new.parent[order]
    first = np.searchsorted(sorted_parent, original, side="left")
    count = np.searchsorted(sorted_parent, original, side="right") - first
    a = order[first]
    b = order[np.minimum(first + 1, len(order) - 1)]
    out = a.copy()
    two = count == 2
    if new.extra is not None:  # cells several cuts cross: the part whose levels are highest
        several = np.flatnonzero(np.isin(original, new.parent[new.several]))
        two[several] = False
        out[several] = _holding(new, order, first[several], count[several], barycentric[several])
    if np.any(two) and new.level is not None:
        level_a = np.einsum("sk,sk->s", barycentric[two], new.level[a[two]])
        level_b = np.einsum("sk,sk->s", barycentric[two], new.level[b[two]])
        out[two] = np.where(level_a >= level_b, a[two], b[two])
    return out


def _holding(vn: VirtualNodeMesh, order, first, count, barycentric) -> np.ndarray:
    """For points in cells several cuts cross: the copy of their cell whose least level at
    the point (barycentric) is the highest (the part that holds the point)."""
    c = vn.constraints()
    rows_of: dict = {}
    for r, copy in enumerate(c.copy):
        rows_of.setdefault(int(copy), []).append(r)
    out = np.empty(len(first), dtype=np.int64)
    for i in range(len(first)):
        best, best_level = -1, -np.inf
        for copy in order[first[i] : first[i] + count[i]]:
            lv = min(float(barycentric[i] @ c.level[r]) for r in rows_of.get(int(copy), []))
            if lv > best_level:
                best, best_level = int(copy), lv
        out[i] = best
    return out
