"""Pictures of tetrahedral meshes with mplot3d: the boundary surface at current positions.

Each boundary triangle is coloured by the value of the tetrahedron it belongs to, with simple
Lambert shading so the shape reads in 3D. The rest configuration's feature edges (boundary edges
with a dihedral angle above 30 degrees, e.g. a block's outline) are drawn as thin grey lines when
``rest_outline``. Equal axis scaling, fixed view (elev, azim).

Shapes: positions (n, 3); cell_values (m,) one value per tetrahedron. Colours as in ``plot2d``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.io.atomic import atomic_output
from tissuesim.mesh.mesh import Mesh
from tissuesim.render.plot2d import (
    Frame,
    _bounds,
    _check,
    _colour_map,
    _new_figure,
    _save_gif,
    _subsample,
)

__all__ = ["boundary_faces", "render_frame_png_3d", "render_gif_3d"]

_LIGHT = np.array([0.35, -0.45, 0.82]) / np.linalg.norm([0.35, -0.45, 0.82])


def boundary_faces(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boundary triangles of tetrahedra cells (m, 4).

    Returns (faces (k, 3) vertex indices, outward for positively oriented tets; owner (k,) index
    of the tetrahedron each face belongs to). A face is on the boundary if exactly one
    tetrahedron has it.
    """
    cells = np.asarray(cells, dtype=np.int64)
    local = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
    faces = cells[:, local].reshape(-1, 3)
    key = np.sort(faces, axis=1)
    n = int(cells.max()) + 1 if cells.size else 1
    if n < 2_000_000:  # one int64 per face: much faster than np.unique(axis=0)
        key = (key[:, 0] * n + key[:, 1]) * n + key[:, 2]
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    once = counts[inverse.ravel()] == 1
    return faces[once], np.repeat(np.arange(len(cells)), 4)[once]


def _feature_edges(points: np.ndarray, faces: np.ndarray, angle_deg: float = 30.0) -> np.ndarray:
    """(e, 2) surface edges whose two faces meet at more than angle_deg (or with one face)."""
    tri = points[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    edges = np.sort(faces[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    owner = np.repeat(np.arange(len(faces)), 3)
    uniq, inverse, counts = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    order = np.argsort(inverse, kind="stable")
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    keep = counts != 2
    two = np.flatnonzero(counts == 2)
    f0, f1 = owner[order[start[two]]], owner[order[start[two] + 1]]
    cos = np.einsum("ij,ij->i", normals[f0], normals[f1])
    keep[two[cos < np.cos(np.radians(angle_deg))]] = True
    return uniq[keep]


def _face_colours(x: np.ndarray, faces: np.ndarray, vals: np.ndarray, cmap, norm) -> np.ndarray:
    """(k, 4) RGBA per face: colour of its value, shaded by the angle to a fixed light."""
    tri = x[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    rgba = cmap(norm(np.ma.masked_invalid(vals)))
    rgba[:, :3] *= (0.55 + 0.45 * np.abs(n @ _LIGHT))[:, None]
    return rgba


def _figure_3d():
    """(fig, 3D axes) drawing artists by zorder, so outlines and markers stay on top."""
    fig = _new_figure((7.5, 6.0))
    return fig, fig.add_subplot(projection="3d", computed_zorder=False)


def _surface_collection(ax, verts: np.ndarray):
    """Poly3DCollection of triangles verts (k, 3, 3) added to ax; face colours set later."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    many = len(verts) > 5000
    coll = Poly3DCollection(
        verts,
        edgecolors=(0.0, 0.0, 0.0, 0.3),
        linewidths=0.1 if many else 0.3,
        zorder=1,
    )
    ax.add_collection3d(coll)
    if many:  # edges in the face colour hide seams; needs the axes, so after adding
        coll.set_edgecolor("face")
    return coll


def _rest_outline(ax, points: np.ndarray, faces: np.ndarray) -> None:
    """Dashed grey feature edges of the rest surface (points (n, 3), faces (k, 3))."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    segs = points[_feature_edges(points, faces)]
    if len(segs) == 0:  # a smooth surface (an ellipsoid) has no feature edges to outline
        return
    ax.add_collection3d(
        Line3DCollection(segs, colors="0.4", linewidths=0.8, linestyles="--", zorder=2)
    )


def _finish_axes_3d(fig, ax, lo, hi, label, cmap, norm, elev, azim) -> None:
    """Fixed limits lo..hi with equal scaling, ticks, view, axis labels and the colour bar."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.ticker import MaxNLocator

    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    box = np.maximum(hi - lo, 1e-3 * (hi - lo).max())
    ax.set_box_aspect(tuple(box))
    for axis, size in zip((ax.xaxis, ax.yaxis, ax.zaxis), box / box.max(), strict=True):
        axis.set_major_locator(MaxNLocator(nbins=max(3, round(6 * size)), steps=[1, 2, 2.5, 5, 10]))
    ax.view_init(elev=elev, azim=azim)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax, label=label, shrink=0.7, pad=0.08)


def _setup_3d(mesh, all_positions, label, cmap, norm, rest_outline, elev, azim, faces):
    rest = np.asarray(mesh.points, dtype=float)
    lo, hi = _bounds([*all_positions, rest] if rest_outline else list(all_positions), pad=0.02)
    fig, ax = _figure_3d()
    coll = _surface_collection(ax, np.asarray(all_positions[0])[faces])
    if rest_outline:
        _rest_outline(ax, rest, boundary_faces(mesh.cells)[0])
    _finish_axes_3d(fig, ax, lo, hi, label, cmap, norm, elev, azim)
    return fig, ax, coll


def render_frame_png_3d(
    mesh: Mesh,
    positions: np.ndarray,
    cell_values: np.ndarray,
    path: str | os.PathLike[str],
    *,
    title: str = "",
    label: str = "J",
    vmin: float | None = None,
    vmax: float | None = None,
    rest_outline: bool = True,
    elev: float = 22.0,
    azim: float = -55.0,
    dpi: int = 150,
) -> Path:
    """Draw the deformed boundary surface (positions (n, 3)) coloured by cell_values (m,).

    Returns the path written.
    """
    x = np.asarray(positions, dtype=float)
    vals = np.asarray(cell_values, dtype=float)
    _check(mesh, x, vals, 3)
    faces, owner = boundary_faces(mesh.cells)
    cmap, norm = _colour_map([vals], label, vmin, vmax)
    fig, ax, coll = _setup_3d(mesh, [x], label, cmap, norm, rest_outline, elev, azim, faces)
    coll.set_facecolor(_face_colours(x, faces, vals[owner], cmap, norm))
    if title:
        ax.set_title(title)
    path = Path(path)
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight", pad_inches=0.1)
    return path


def render_gif_3d(
    mesh: Mesh,
    frames: Sequence[Frame],
    path: str | os.PathLike[str],
    *,
    label: str = "J",
    fps: int = 15,
    vmin: float | None = None,
    vmax: float | None = None,
    max_frames: int = 150,
    title: str = "",
    rest_outline: bool = True,
    elev: float = 22.0,
    azim: float = -55.0,
    dpi: int = 80,
) -> Path:
    """Animate frames [(time, positions (n, 3), cell_values (m,)), ...] into a GIF.

    Fixed axis limits, view and colour range over the whole run; title shows t. More than
    ``max_frames`` frames are subsampled evenly (first and last kept).
    """
    if not frames:
        raise InputError("render_gif_3d needs at least one frame")
    sel = [frames[i] for i in _subsample(len(frames), max_frames)]
    data = [(float(t), np.asarray(x, dtype=float), np.asarray(v, dtype=float)) for t, x, v in sel]
    for _, x, v in data:
        _check(mesh, x, v, 3)
    faces, owner = boundary_faces(mesh.cells)
    cmap, norm = _colour_map([v for _, _, v in data], label, vmin, vmax)
    xs = [x for _, x, _ in data]
    fig, ax, coll = _setup_3d(mesh, xs, label, cmap, norm, rest_outline, elev, azim, faces)
    prefix = f"{title}   " if title else ""

    def update(i: int) -> Any:
        t, x, v = data[i]
        coll.set_verts(x[faces])
        coll.set_facecolor(_face_colours(x, faces, v[owner], cmap, norm))
        ax.set_title(f"{prefix}t = {t:.4g}")
        return (coll,)

    return _save_gif(fig, update, len(data), Path(path), fps, dpi)
