"""The Mesh: rest positions and cells (simplices, quadrilaterals, hexahedra or wedges), plus
named vertex, facet and cell sets."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

__all__ = ["Mesh", "CELL_TYPES"]

#: (dimension, nodes per cell) -> meshio's cell type name (VTK node order for every one)
CELL_TYPES = {
    (2, 3): "triangle",
    (3, 4): "tetra",
    (2, 6): "triangle6",
    (3, 10): "tetra10",
    (2, 4): "quad",
    (3, 8): "hexahedron",
    (2, 8): "quad8",
    (2, 9): "quad9",
    (3, 20): "hexahedron20",
    (3, 27): "hexahedron27",
    (3, 6): "wedge",  # meshio's and Gmsh's order (VTK's mirrored; meshio converts)
}
#: nodes per quadratic quadrilateral (quad8, quad9) and hexahedron (hexahedron20, 27)
_QUADRATIC_TENSOR = {2: (8, 9), 3: (20, 27)}


@dataclass(frozen=True, eq=False)
class Mesh:
    """A mesh in its rest configuration.

    points: (n, d) float64 rest positions, d = 2 (triangles, quadrilaterals) or 3 (tetrahedra,
        hexahedra).
    cells: (m, d + 1) int64 vertex indices, positively oriented (det of edge vectors > 0);
        quadratic meshes (order 2): (m, 6) triangles or (m, 10) tetrahedra, the corners first,
        then the midside nodes (``mesh/cells/quadratic.py``); Q1 quadrilaterals (m, 4) in 2D and
        hexahedra (m, 8) in 3D in VTK's node order, with a positive rest Jacobian at every
        Gauss point (``mesh/cells/tensor.py``); quadratic quadrilaterals (m, 8) / (m, 9) and
        hexahedra (m, 20) / (m, 27) in VTK's node order (``mesh/cells/tensor_quadratic.py``);
        linear wedges (m, 6) in meshio's / Gmsh's / FEBio's node order (``mesh/cells/wedge.py``).
    point_sets: name -> (k,) vertex indices.
    facet_sets: name -> (k, d) boundary facets (edges in 2D, triangles in 3D) as corner indices;
        (k, 4) quad faces for hexahedra (``facet_nodes``), and for wedges their quads and
        triangles, a triangle as (a, b, c, c) (``mesh/cells/wedge.py``); quadratic cells' facets by
        their corners, as for P2.
    cell_sets: name -> (k,) cell indices.
    source: where the mesh came from (a file path or a generator), used in error messages.
    cell_fractions: (m,) the part of each cell's volume that is material (a virtual-node cut's
        copies, ``mesh/cutting/virtual_nodes.py``), weighting its energy, mass and body loads;
        None: 1.
    cell_levels: (m, d + 1) with ``cell_fractions``: each copy's material level at its
        vertices (material where its linear interpolation is >= 0); whole cells next to the
        cut carry their distance to its plane on their side, the others +inf.
    cell_more_levels: (rows (r,), levels (r, d + 1)) with ``cell_levels``: further levels of
        the cells several cuts bound (a copy's material is where all of its levels are >= 0).
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
    # virtual-node cut (``mesh/cutting/virtual_nodes.py``) stand for their side only;
    # None: all of it
    cell_fractions: np.ndarray | None = None
    # (m, d+1) with cell_fractions: each copy's material level at its vertices, its signed
    # distance to the cut's plane (where the body was when cut) times its side, so its material
    # is where the level's linear interpolation is >= 0; whole cells next to the cut carry
    # their distance on their side, others +inf rows. The cut faces' contact surfaces are level
    # sets of it (contact/cut/surface.py)
    cell_levels: np.ndarray | None = None
    # (cell of each row (r,), levels (r, d+1)) with cell_levels: the further levels of cells
    # several cuts bound (copies of cells several cuts cross; whole cells next to several
    # cuts): a copy's material, and its contact region, are where all its levels allow
    cell_more_levels: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def cell_kind(self) -> str:
        """The cells' kind in words, plural: "tetrahedra", "quadratic tetrahedra",
        "20-node hexahedra", "wedges"... (the run banner, repr)."""
        kind = {2: "triangles", 3: "tetrahedra"}.get(self.dim, "cells")
        if self.cell_type == "wedge":
            return "wedges"
        if not self.simplicial:
            kind = "quadrilaterals" if self.dim == 2 else "hexahedra"
            return f"{self.cells.shape[1]}-node {kind}" if self.order == 2 else kind
        return f"quadratic {kind}" if self.order == 2 else kind

    def __repr__(self) -> str:
        kind = self.cell_kind
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
    def cell_type(self) -> str:
        """meshio's name of the cells: "triangle", "tetra", "triangle6", "tetra10", "quad",
        "hexahedron", "quad8", "quad9", "hexahedron20", "hexahedron27" or "wedge"."""
        return CELL_TYPES[self.dim, int(self.cells.shape[1])]

    @property
    def simplicial(self) -> bool:
        """True for triangles and tetrahedra (linear or quadratic), False for quadrilaterals and
        hexahedra (Q1 or quadratic) and wedges."""
        d, nv = self.dim, int(self.cells.shape[1])
        return nv in (d + 1, (d + 1) * (d + 2) // 2)

    @property
    def order(self) -> int:
        """1 for linear simplices, Q1 cells and wedges, 2 for 6-node triangles / 10-node
        tetrahedra and the quadratic quadrilaterals and hexahedra (8, 9, 20, 27 nodes)."""
        d, nv = self.dim, int(self.cells.shape[1])
        return 2 if nv == (d + 1) * (d + 2) // 2 or nv in _QUADRATIC_TENSOR[d] else 1

    @property
    def facet_nodes(self) -> int:
        """Corner nodes of a boundary facet: d (edges, triangles), 4 for hexahedra' quad faces
        and for wedges' facets (a triangle as (a, b, c, c))."""
        return 4 if self.dim == 3 and not self.simplicial else self.dim

    @property
    def corners(self) -> np.ndarray:
        """(m, d + 1) the corner vertices of every cell ((m, 2^d) for quadrilaterals and
        hexahedra: all nodes of Q1 cells; (m, 6) for wedges)."""
        if not self.simplicial:
            return self.cells[:, : 2**self.dim]
        return self.cells[:, : self.dim + 1]

    @cached_property
    def _subdivision(self) -> tuple[np.ndarray, np.ndarray]:
        if self.cell_type == "wedge":
            from tissuesim.mesh.cells.wedge import subdivide as split_wedges

            return split_wedges(self.points, self.cells)
        if not self.simplicial and self.order == 2:
            from tissuesim.mesh.cells.tensor_quadratic import subdivide as split_quadratic

            return split_quadratic(self.points, self.cells)
        if not self.simplicial:
            from tissuesim.mesh.cells.tensor import subdivide as split

            return split(self.points, self.cells)
        if self.order == 1:
            return self.cells, np.arange(self.n_cells)
        from tissuesim.mesh.cells.quadratic import subdivide

        return subdivide(self.points, self.cells)

    @property
    def simplices(self) -> np.ndarray:
        """Linear simplices (k, d + 1) over all nodes: the cells themselves for order 1, the
        linear subdivision of each quadratic cell (4 triangles, 8 tetrahedra) for order 2, the
        split of each Q1 cell (2 triangles, 6 tetrahedra; ``mesh/cells/tensor.py``), quadratic
        quadrilateral / hexahedron (6 or 8 triangles, 22 or 48 tetrahedra;
        ``mesh/cells/tensor_quadratic.py``) or wedge (3 tetrahedra; ``mesh/cells/wedge.py``).
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
        if self.order == 1 and self.simplicial:
            return self
        return Mesh(self.points, self.simplices, source=f"{self.source} (linear subdivision)")

    def per_simplex(self, cell_values: np.ndarray) -> np.ndarray:
        """Per-cell values (m, ...) repeated onto ``simplices`` (k, ...)."""
        if self.order == 1 and self.simplicial:
            return cell_values
        return cell_values[self.simplex_parent]

    @cached_property
    def midside(self):
        """Corner pairs (k, 2) -> their midside nodes (k,) (-1 where none); order 2 only."""
        from tissuesim.mesh.cells.quadratic import midside_lookup

        return midside_lookup(self.cells, self.dim)
