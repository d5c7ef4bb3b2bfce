"""The faces two cells of a simplex mesh share, with where each face's nodes sit in both cells:
what the virtual node cut joins node slots across (``mesh/cutting/node_groups.py``) and what a
body's cut state checks for faces a cut parted (``bodies/cut_state.py``). A body cut step after step
asks for its original mesh's faces every time, so the last few meshes' are kept."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from tissuesim.mesh.queries.boundary import all_facets, facet_table

__all__ = ["InteriorFaces", "interior_faces"]


@dataclass(frozen=True, eq=False)
class InteriorFaces:
    """Every face two cells share, once, in the order of ``facet_table``'s unique facets:
    ``cell_a`` / ``cell_b`` (f,) its two cells (a the one listed first), ``nodes`` (f, d) its
    nodes as a's facet lists them (outward for a), ``slot_a`` / ``slot_b`` (f, d) where each
    of those nodes sits in a and in b; ``shape`` the cells' (m, d+1). And every facet of the
    mesh, once: ``unique`` (u, d) its nodes, ``facet_id`` (m (d+1),) which one each cell's
    local facet is (``facet_table``'s inverse, cell-major)."""

    cell_a: np.ndarray
    cell_b: np.ndarray
    nodes: np.ndarray
    slot_a: np.ndarray
    slot_b: np.ndarray
    shape: tuple[int, int]
    unique: np.ndarray
    facet_id: np.ndarray
    _kept: dict = field(default_factory=dict, repr=False)

    def uncut_groups(self) -> np.ndarray:
        """(m (d+1),) the group of every slot (cell, local node) of the mesh uncut: the slots
        of two cells that share a face joined at its nodes (connected components, once)."""
        if "groups" not in self._kept:
            m, k = self.shape
            r = (self.cell_a[:, None] * k + self.slot_a).ravel()
            c = (self.cell_b[:, None] * k + self.slot_b).ravel()
            graph = coo_matrix((np.ones(len(r)), (r, c)), shape=(m * k, m * k))
            self._kept["groups"] = connected_components(graph, directed=False)[1]
        return self._kept["groups"]


def _build(cells: np.ndarray) -> InteriorFaces:
    m, k = cells.shape
    facets, first, inverse, counts = facet_table(cells)  # (m k, k-1), cell-major
    by_facet = np.argsort(inverse, kind="stable")
    shared = counts[inverse[by_facet]] == 2
    pairs = by_facet[shared].reshape(-1, 2)  # the two (cell, local facet) entries of each
    cell_a, cell_b = pairs[:, 0] // k, pairs[:, 1] // k
    nodes = facets[pairs[:, 0]]
    slot_a = all_facets(np.arange(k)[None])[0][pairs[:, 0] % k]  # a's facet: its local slots
    slot_b = np.argmax(cells[cell_b][:, :, None] == nodes[:, None, :], axis=1)
    return InteriorFaces(cell_a, cell_b, nodes, slot_a, slot_b, (m, k), facets[first], inverse)


def interior_faces(cells: np.ndarray) -> InteriorFaces:
    """The interior faces of ``cells`` (m, d+1), kept for the last few meshes asked (bodies
    cut in turn each find theirs)."""
    cells = np.asarray(cells, dtype=np.int64)
    for i, (known, faces) in enumerate(_KEPT):
        if known.shape == cells.shape and np.array_equal(known, cells):
            _KEPT.insert(0, _KEPT.pop(i))
            return faces
    faces = _build(cells)
    _KEPT.insert(0, (cells.copy(), faces))
    del _KEPT[_KEEP:]
    return faces


_KEEP = 4
_KEPT: list[tuple[np.ndarray, InteriorFaces]] = []
