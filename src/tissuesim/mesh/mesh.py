"""The Mesh: rest positions and simplices, plus named vertex, facet and cell sets."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

__all__ = ["Mesh"]


@dataclass(frozen=True, eq=False)
class Mesh:
    """A simplicial mesh in its rest configuration.

    points: (n, d) float64 rest positions, d = 2 (triangles) or 3 (tetrahedra).
    cells: (m, d + 1) int64 vertex indices, positively oriented (det of edge vectors > 0);
        quadratic meshes (order 2): (m, 6) triangles or (m, 10) tetrahedra, the corners first,
        then the midside nodes (``mesh/quadratic.py``).
    point_sets: name -> (k,) vertex indices.
    facet_sets: name -> (k, d) boundary facets (edges in 2D, triangles in 3D) as corner indices.
    cell_sets: name -> (k,) cell indices.
    source: where the mesh came from (a file path or a generator), used in error messages.
    cell_fractions: (m,) the part of each cell's volume that is material (a virtual-node cut's
        copies, ``mesh/virtual_nodes.py``), weighting its energy, mass and body loads; None: 1.
    surface_projection: the exact curved surface the boundary approximates, as a projection
        of points onto it ((k, d) -> (k, d)), when a generator knows it (``ellipsoid``);
        elevating the mesh to order 2 puts the boundary's midside nodes on it. None (files,
        boxes): edges stay straight.

    Build meshes with the generators in ``tissuesim.mesh`` or ``read_mesh``; both validate.
    """

    points: np.ndarray
    cells: np.ndarray
    point_sets: Mapping[str, np.ndarray] = field(default_factory=dict)
    facet_sets: Mapping[str, np.ndarray] = field(default_factory=dict)
    cell_sets: Mapping[str, np.ndarray] = field(default_factory=dict)
    source: str = "<arrays>"
    surface_projection: Callable[[np.ndarray], np.ndarray] | None = None
    # the fraction of each cell's volume that holds material (m,): cells copied by a
    # virtual-node cut (``mesh/virtual_nodes.py``) stand for their side only; None: all of it
    cell_fractions: np.ndarray | None = None

    def __repr__(self) -> str:
        kind = {2: "triangles", 3: "tetrahedra"}.get(self.dim, "cells")
        if self.order == 2:
            kind = f"quadratic {kind}"
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
        """The space dimension, 2 (triangles) or 3 (tetrahedra)."""
        return int(self.points.shape[1])

    @property
    def n_points(self) -> int:
        """The number of nodes (vertices, and midside nodes of a quadratic mesh)."""
        return int(self.points.shape[0])

    @property
    def n_cells(self) -> int:
        """The number of elements (triangles or tetrahedra)."""
        return int(self.cells.shape[0])

    @property
    def order(self) -> int:
        """1 for linear simplices, 2 for 6-node triangles / 10-node tetrahedra."""
        return 1 if self.cells.shape[1] == self.dim + 1 else 2

    @property
    def corners(self) -> np.ndarray:
        """(m, d + 1) the corner vertices of every cell."""
        return self.cells[:, : self.dim + 1]

    @cached_property
    def _subdivision(self) -> tuple[np.ndarray, np.ndarray]:
        if self.order == 1:
            return self.cells, np.arange(self.n_cells)
        from tissuesim.mesh.quadratic import subdivide

        return subdivide(self.points, self.cells)

    @property
    def simplices(self) -> np.ndarray:
        """Linear simplices (k, d + 1) over all nodes: the cells themselves for order 1, the
        linear subdivision of each quadratic cell (4 triangles, 8 tetrahedra) for order 2.
        Geometry (boundary, location, contact, pictures) works on these."""
        return self._subdivision[0]

    @property
    def simplex_parent(self) -> np.ndarray:
        """(k,) the cell each of ``simplices`` belongs to."""
        return self._subdivision[1]

    @cached_property
    def linear_view(self) -> Mesh:
        """This mesh as linear simplices (``simplices``) on the same points; itself for order 1.
        Its cells are the sub-simplices, so per-cell values map through ``simplex_parent``."""
        if self.order == 1:
            return self
        return Mesh(self.points, self.simplices, source=f"{self.source} (linear subdivision)")

    def per_simplex(self, cell_values: np.ndarray) -> np.ndarray:
        """Per-cell values (m, ...) repeated onto ``simplices`` (k, ...)."""
        return cell_values if self.order == 1 else cell_values[self.simplex_parent]

    @cached_property
    def midside(self):
        """Corner pairs (k, 2) -> their midside nodes (k,) (-1 where none); order 2 only."""
        from tissuesim.mesh.quadratic import midside_lookup

        return midside_lookup(self.cells, self.dim)
