"""A fine visual surface carried by a coarse FEM body (SOFA's barycentric mapping).

Any triangle surface (a polyline in 2D) is embedded once, at rest, in the body's simplices by
barycentric coordinates (``mesh/queries/embedding.py``); it then moves with the body at the cost of
one sparse product per frame, is written as its own series (``io/series/bodies.py VisualSeries``)
and is drawn instead of the body's coarse surface in the 3D pictures (``render/scene.py``). It takes
no part in the mechanics: it has no mass, no stiffness, no contact.

Points outside the body's mesh (a fine surface sticks out of a coarse mesh by up to an element)
are carried by the element of the closest boundary facet, with extrapolated coordinates; a point
farther outside than ``max_outside`` (default: one element, the carrying element's longest
edge) is an error: such a surface is in other units or another place than the body.

A body that is cut or tears refuses a visual surface (and a body with one refuses a cut): the
surface's triangles would bridge the opening and hide the cut.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from tissuesim.errors import InputError, MeshError
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries.embedding import Embedding, embed_points
from tissuesim.validate import short

__all__ = ["VisualSurface", "make_visual_surface", "read_visual_cells"]

#: a point may lie this many of its element's longest edges outside the body by default
MAX_OUTSIDE_ELEMENTS = 1.0
_SURFACE_TYPES = {"triangle": 3, "triangle6": 3, "triangle7": 3}
_QUAD_TYPES = ("quad", "quad8", "quad9")
_LINE_TYPES = {"line": 2, "line3": 2}


@dataclass(frozen=True, eq=False)
class VisualSurface:
    """A surface carried by FEM body ``body``: rest ``points`` (q, d), ``cells`` (m, d)
    (triangles in 3D, segments in 2D), where it came from, and its ``embedding``."""

    name: str
    body: str
    points: np.ndarray
    cells: np.ndarray
    source: str
    embedding: Embedding

    @property
    def dim(self) -> int:
        return int(self.points.shape[1])

    @property
    def cell_type(self) -> str:
        """meshio's name of the cells: "triangle" (3D) or "line" (2D)."""
        return "triangle" if self.dim == 3 else "line"

    def positions(self, body_positions: np.ndarray) -> np.ndarray:
        """The surface's points (q, d) where the body's mesh points are at (n, d)."""
        return self.embedding.positions(body_positions)

    def describe(self) -> dict[str, Any]:
        e = self.embedding
        return {
            "body": self.body,
            "source": self.source,
            "points": int(len(self.points)),
            self.cell_type + "s": int(len(self.cells)),
            "points_outside_body": int(e.outside.sum()),
            "max_distance_outside_m": float(e.distance.max(initial=0.0)),
        }


def _from_file(path: str, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """(points (n, 3), cells) of a surface file: triangles (quadrilaterals split) in 3D,
    line segments in 2D."""
    from tissuesim.mesh.io import _load
    from tissuesim.validate import regular_file

    if not os.path.exists(path):
        raise MeshError(f"{path}: no such surface file; check the path (cwd is {os.getcwd()})")
    try:
        regular_file(path, "surface file")  # a FIFO or device would block the reader
    except InputError as exc:
        raise MeshError(str(exc)) from None
    m = _load(path)
    blocks = []
    if dim == 3:
        for b in m.cells:
            data = np.asarray(b.data)
            if b.type in _SURFACE_TYPES:
                blocks.append(data[:, :3])
            elif b.type in _QUAD_TYPES:  # OBJ and PLY quadrilaterals, split along a diagonal
                blocks += [data[:, [0, 1, 2]], data[:, [0, 2, 3]]]
        want = "triangles (STL, OBJ, PLY, ...)"
    else:
        blocks = [np.asarray(b.data)[:, :2] for b in m.cells if b.type in _LINE_TYPES]
        want = "line segments (a polyline: VTK, VTU, OBJ 'l' lines, ...)"
    if not any(len(b) for b in blocks):
        found = ", ".join(f"{b.type} ({len(b.data)})" for b in m.cells) or "none"
        raise MeshError(
            f"{path}: no {want}; cell types found: {found}. A {dim}D body's visual surface "
            f"needs {want}"
        )
    return np.asarray(m.points, dtype=np.float64), np.concatenate(blocks)


def read_visual_cells(source: Any, dim: int) -> tuple[np.ndarray, np.ndarray, str]:
    """(points (q, dim), cells (m, dim), label) of a file path, a ``Surface`` (points,
    triangles) or a (points, cells) pair; exact duplicate points merged (an STL stores every
    triangle's corners apart), cells that repeat a vertex and unused points dropped."""
    if isinstance(source, str | os.PathLike):
        label = os.fspath(source)
        points, cells = _from_file(label, dim)
    elif hasattr(source, "points") and hasattr(source, "triangles"):
        label = str(getattr(source, "source", "<surface>"))
        points, cells = source.points, source.triangles
    elif isinstance(source, tuple | list) and len(source) == 2:
        label = "<arrays>"
        points, cells = source
    else:
        raise InputError(
            f"a visual surface is a file path (STL, OBJ, PLY, ...), a Surface or a (points, "
            f"cells) pair, not {short(source)}"
        )
    try:
        points = np.array(points, dtype=np.float64)
        cells = np.asarray(cells)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{label}: points and cells must be numeric arrays ({exc})") from None
    if dim == 2 and points.ndim == 2 and points.shape[1] == 3:  # a file's points are 3D
        if np.abs(points[:, 2]).max(initial=0.0) > 1e-9 * max(np.ptp(points[:, :2]), 1e-300):
            raise MeshError(f"{label}: a 2D body's polyline must lie in the plane z = 0")
        points = points[:, :2]
    if points.ndim != 2 or points.shape[1] != dim or not len(points):
        raise MeshError(f"{label}: points have shape {points.shape}; expected (n, {dim})")
    if not np.isfinite(points).all():
        raise MeshError(f"{label}: the surface has non-finite point coordinates")
    kind = "triangles" if dim == 3 else "segments"
    if cells.ndim != 2 or cells.shape[1] != dim or not len(cells):
        raise MeshError(f"{label}: {kind} must be an (m, {dim}) array, m >= 1; got {cells.shape}")
    if not np.issubdtype(cells.dtype, np.integer) or cells.min() < 0 or cells.max() >= len(points):
        raise MeshError(f"{label}: {kind} must be integer ids in [0, {len(points)})")
    # merged points keep the order of their first occurrence (a welded surface keeps its own)
    _, first, inverse = np.unique(points, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    unique = points[first[order]]
    cells = rank[inverse.reshape(-1)][cells.astype(np.int64)]
    s = np.sort(cells, axis=1)
    cells = cells[np.all(s[:, 1:] != s[:, :-1], axis=1)]
    if not len(cells):
        raise MeshError(f"{label}: every one of its {kind} is degenerate (a repeated corner)")
    used = np.unique(cells)
    new = np.full(len(unique), -1, dtype=np.int64)
    new[used] = np.arange(len(used))
    return unique[used], new[cells], label


def make_visual_surface(
    name: str, body: str, mesh: Mesh, source: Any, max_outside: float | None = None
) -> VisualSurface:
    """Read ``source`` (see ``read_visual_cells``) and embed it in ``mesh`` (the rest mesh of
    FEM body ``body``); an error if a point lies farther outside than ``max_outside`` (m;
    None: one element, its longest edge)."""
    from tissuesim.validate import real

    points, cells, label = read_visual_cells(source, mesh.dim)
    emb = embed_points(mesh, points)
    if max_outside is None:
        limit, allowed = MAX_OUTSIDE_ELEMENTS * emb.size, "one element"
    else:
        limit = real(max_outside, "max_outside", low=0.0, unit="m")
        allowed = f"max_outside = {limit:g} m"
    far = emb.distance > limit
    if far.any():
        i = int(np.argmax(np.where(far, emb.distance, -1.0)))
        size = float(np.ptp(mesh.points, axis=0).max())
        raise InputError(
            f"visual surface {name!r} ({label}): {int(far.sum())} of its {len(points)} points "
            f"{'lies' if far.sum() == 1 else 'lie'} farther outside body {body!r} than {allowed} "
            f"(the farthest "
            f"{emb.distance[i]:.3g} m, at {np.round(points[i], 6).tolist()}; the body is "
            f"{size:.3g} m across): give the body's own surface, in metres and in its place, "
            f"or a larger max_outside"
        )
    return VisualSurface(name, body, points, cells, label, emb)
