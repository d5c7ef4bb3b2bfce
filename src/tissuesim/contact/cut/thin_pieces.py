"""Contact surfaces for the pieces of a cut body too thin for the cut faces' gap.

A cut face's contact surface lies GAP dhat inside its side (``cut_surface.py``), so a piece
thinner than that (a grazing cut, two cuts close together) has its region shaved away and no
surface. Such a piece gets its surface built on its own, as for a barrier SCALES times
smaller: its cut faces sit that much less far in (snapping and merging scaled alike), the
first scale that leaves it a surface. So the piece is a closed surface like the others: it
meets faces, edges and points of everything (no thin edge passes between contact points), and
the exact intersection test sees it. Its faces stay dhat (1 + scale) from the other side's at
rest, outside their barrier. Its own faces, closer than dhat to each other, lie on either side
of its material and are left out of contact as every pair of one piece that touches at rest
near a cut (``contact/cut/rest_proximity.py``). A piece thinner than the smallest scale allows
keeps contact points (``contact/cut/sliver_points.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

__all__ = ["SCALES", "cells_of", "thin_surfaces"]

#: the fractions of dhat at which a thin piece's surface is tried, in turn
SCALES = (0.25, 1.0 / 16.0)


def thin_surfaces(
    mesh,
    W: sp.csr_matrix,
    facets: np.ndarray,
    dhat: float,
    build: Callable[[object, float], tuple[sp.csr_matrix, np.ndarray]],
) -> tuple[sp.csr_matrix, np.ndarray]:
    """(W, facets) of the cut mesh's contact surface with a surface added for each piece that
    had none (``sliver_points.bare_pieces``), built by ``build(mesh, dhat)`` (the cut
    surface's builder, ``surfaces.cut_faces``) at the first of SCALES times ``dhat`` that
    gives it one; pieces none does stay as they were (no surface)."""
    from tissuesim.contact.cut.sliver_points import bare_pieces
    from tissuesim.mesh.cutting.virtual_nodes import node_pieces

    bare = bare_pieces(mesh, W, facets)
    if not bare.any():
        return W, facets
    label = node_pieces(mesh.cells, mesh.n_points)[mesh.cells[:, 0]]
    blocks, pieces = [sp.csr_matrix(W)], [facets]
    rows = W.shape[0]
    for piece in np.unique(label[bare]):
        cells = np.flatnonzero(label == piece)
        for scale in SCALES:
            W_p, f_p = build(cells_of(mesh, cells), scale * dhat)
            if len(f_p):
                used = np.unique(f_p)
                index = np.full(W_p.shape[0], -1)
                index[used] = rows + np.arange(len(used))
                blocks.append(sp.csr_matrix(W_p)[used])
                pieces.append(index[f_p])
                rows += len(used)
                break
    if len(blocks) == 1:
        return W, facets
    return sp.vstack(blocks, format="csr"), np.concatenate(pieces)


def cells_of(mesh, cells: np.ndarray):
    """The mesh with only ``cells`` (all its points kept, so weights stay over its nodes)."""
    more = None
    if mesh.cell_more_levels is not None:
        rows, levels = mesh.cell_more_levels
        new = np.full(mesh.n_cells, -1)
        new[cells] = np.arange(len(cells))
        keep = new[rows] >= 0
        more = (new[rows][keep], levels[keep])
    fractions = None if mesh.cell_fractions is None else mesh.cell_fractions[cells]
    return replace(
        mesh,
        cells=mesh.cells[cells],
        point_sets={},
        facet_sets={},
        cell_sets={},
        cell_fractions=fractions,
        cell_levels=mesh.cell_levels[cells],
        cell_more_levels=more,
    )
