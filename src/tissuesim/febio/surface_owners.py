"""Which body a FEBio surface's facet belongs to, where it lies in several (``scene.py``).

FEBio applies a surface load once per facet, along the facet's own normal (its node order).
A facet whose nodes all belong to two bodies (a shell's quad under a rigid block glued on it:
sh60) would otherwise be loaded in both, and tissuesim orients a body's pressure facets
outward from that body: a pressure on the shell's top pushing down and the same pressure on
the block's bottom pushing up, which cancel. Such a facet goes to the first body that has it
as a face pointing the facet's way (its cell lies behind the facet's normal), else to the
first body that has it.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["facet_owners"]


def facet_owners(points: np.ndarray, facets: np.ndarray, bodies: list[np.ndarray]) -> np.ndarray:
    """The index of the body (in ``bodies``, each its cells (m, k) of node ids) each facet
    (f, 3 or 4 node ids) belongs to, -1 for none: a body holds a facet when it uses all the
    facet's nodes (see the module docstring for a facet several bodies hold)."""
    facets = np.asarray(facets, dtype=np.int64)
    inside = np.zeros((len(bodies), len(facets)), dtype=bool)
    for b, cells in enumerate(bodies):
        used = np.zeros(len(points), dtype=bool)
        used[np.asarray(cells, dtype=np.int64).ravel()] = True
        inside[b] = used[facets].all(axis=1)
    owner = np.where(inside.any(axis=0), inside.argmax(axis=0), -1)
    shared = np.flatnonzero(inside.sum(axis=0) > 1)
    if not shared.size:
        return owner
    f = facets[shared]
    corners = points[f]
    if f.shape[1] == 3:
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    else:  # a quad's diagonals
        normal = np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    centre = corners.mean(axis=1)
    facing = np.full(len(shared), -1)
    for b, cells in enumerate(bodies):
        rows = _contains(np.asarray(cells, dtype=np.int64), f, len(points))
        found = np.flatnonzero((rows >= 0) & inside[b, shared] & (facing < 0))
        if not found.size:
            continue
        centroid = points[np.asarray(cells)[rows[found]]].mean(axis=1)
        behind = np.einsum("ij,ij->i", centroid - centre[found], normal[found]) < 0
        facing[found[behind]] = b  # the cell lies behind the facet's normal
    owner[shared] = np.where(facing >= 0, facing, owner[shared])
    return owner


def _contains(cells: np.ndarray, facets: np.ndarray, n_points: int) -> np.ndarray:
    """A cell (row) of ``cells`` holding all of each facet's nodes, -1 for none."""
    m, k = cells.shape
    incidence = sp.csr_matrix(
        (np.ones(m * k), (np.repeat(np.arange(m), k), cells.ravel())), shape=(m, n_points)
    )
    incidence.sum_duplicates()
    incidence.data[:] = 1.0  # a node repeated in a cell (a wedge as a hex) counts once
    unique = [np.unique(r) for r in facets]
    wanted = np.array([len(u) for u in unique])
    rows = np.repeat(np.arange(len(facets)), wanted)
    chooser = sp.csr_matrix(
        (np.ones(len(rows)), (rows, np.concatenate(unique))), shape=(len(facets), n_points)
    )
    counts = (chooser @ incidence.T).tocsr()  # (f, m): the nodes each cell shares
    out = np.full(len(facets), -1, dtype=np.int64)
    for i in range(len(facets)):
        lo, hi = counts.indptr[i], counts.indptr[i + 1]
        full = counts.indices[lo:hi][counts.data[lo:hi] >= wanted[i]]
        if full.size:
            out[i] = full[0]
    return out
