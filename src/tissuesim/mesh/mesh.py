"""The Mesh: rest positions and simplices, plus named vertex, facet and cell sets."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Mesh"]


@dataclass(frozen=True, eq=False)
class Mesh:
    """A simplicial mesh in its rest configuration.

    points: (n, d) float64 rest positions, d = 2 (triangles) or 3 (tetrahedra).
    cells: (m, d + 1) int64 vertex indices, positively oriented (det of edge vectors > 0).
    point_sets: name -> (k,) vertex indices.
    facet_sets: name -> (k, d) boundary facets (edges in 2D, triangles in 3D) as vertex indices.
    cell_sets: name -> (k,) cell indices.
    source: where the mesh came from (a file path or a generator), used in error messages.

    Build meshes with the generators in ``tissuesim.mesh`` or ``read_mesh``; both validate.
    """

    points: np.ndarray
    cells: np.ndarray
    point_sets: Mapping[str, np.ndarray] = field(default_factory=dict)
    facet_sets: Mapping[str, np.ndarray] = field(default_factory=dict)
    cell_sets: Mapping[str, np.ndarray] = field(default_factory=dict)
    source: str = "<arrays>"

    def __repr__(self) -> str:
        kind = {2: "triangles", 3: "tetrahedra"}.get(self.dim, "cells")
        lo, hi = self.points.min(axis=0), self.points.max(axis=0)
        sets = f", sets {sorted({*self.point_sets, *self.facet_sets, *self.cell_sets})}"
        return (
            f"Mesh({self.n_points} vertices, {self.n_cells} {kind}, {self.dim}D, "
            f"box {np.round(lo, 6).tolist()}..{np.round(hi, 6).tolist()}"
            f"{sets if self.point_sets or self.facet_sets or self.cell_sets else ''}, "
            f"source {self.source!r})"
        )

    @property
    def dim(self) -> int:
        return int(self.points.shape[1])

    @property
    def n_points(self) -> int:
        return int(self.points.shape[0])

    @property
    def n_cells(self) -> int:
        return int(self.cells.shape[0])
