"""A linear mesh elevated to a quadratic (P2) one, checked like any other mesh: the node
geometry is ``mesh/cells/quadratic.py``'s, the checks ``mesh/checks.py``'s (kept apart so the node
geometry, which the checks use, imports neither)."""

from __future__ import annotations

import numpy as np

from tissuesim.mesh.cells.quadratic import EDGES, elevate
from tissuesim.mesh.checks import validate_mesh

__all__ = ["elevate_mesh"]


def elevate_mesh(mesh):
    """A linear Mesh as a quadratic one: the same vertices first, a midside node per edge (on
    the mesh's exact surface, ``surface_projection``, where a generator gave one, so an
    ellipsoid stays curved; else at the edge's midpoint); a point set gains the midside nodes
    of edges with both ends in it; facet and cell sets are unchanged (facets are named by their
    corners)."""
    if mesh.order == 2:
        return mesh
    points, cells = elevate(mesh.points, mesh.cells, mesh.surface_projection)
    d = mesh.dim
    pairs = np.sort(cells[:, EDGES[d]], axis=2).reshape(-1, 2)
    mids = cells[:, d + 1 :].reshape(-1)
    psets = {}
    for name, ids in mesh.point_sets.items():
        inside = np.isin(pairs, ids).all(axis=1)
        psets[name] = np.union1d(ids, mids[inside])
    return validate_mesh(
        points,
        cells,
        source=f"{mesh.source} (order 2)",
        point_sets=psets,
        facet_sets=dict(mesh.facet_sets),
        cell_sets=dict(mesh.cell_sets),
        surface_projection=mesh.surface_projection,
    )
