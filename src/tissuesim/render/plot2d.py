"""Pictures of triangle meshes: one PNG of a deformed state, or an animated GIF of a run.

Uses matplotlib's object-oriented API with the Agg canvas (no pyplot, no backend switching, no
display needed); matplotlib is imported inside the functions. Files are written atomically.

Shapes: positions (n, 2) current vertex positions; cell_values (m,) one value per triangle.
Colours: for ``label == "J"`` a diverging map ("RdBu_r": compression blue, expansion red) centred
at J = 1; otherwise "viridis". NaN values are drawn grey.
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

__all__ = ["render_frame_png", "render_gif"]

Frame = tuple[float, np.ndarray, np.ndarray]  # (time, positions (n, d), cell_values (m,))


# ---- helpers shared with plot3d -------------------------------------------------------------


def _colour_map(values: Sequence[np.ndarray], label: str, vmin: float | None, vmax: float | None):
    """(cmap, norm) covering every finite entry of ``values`` unless vmin/vmax are given."""
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap, Normalize, TwoSlopeNorm

    finite = [v[np.isfinite(v)] for v in (np.asarray(a, dtype=float).ravel() for a in values)]
    finite = np.concatenate(finite) if finite else np.empty(0)
    lo = float(finite.min()) if vmin is None and finite.size else vmin
    hi = float(finite.max()) if vmax is None and finite.size else vmax
    if label.split(" (")[0] == "J":  # diverging, white at J = 1; its half when one-sided
        full = colormaps["RdBu_r"]
        lo = float(min(lo, 1.0) if vmin is None and lo is not None else (1.0 if lo is None else lo))
        hi = float(max(hi, 1.0) if vmax is None and hi is not None else (1.0 if hi is None else hi))
        if lo == hi == 1.0:
            lo, hi = 0.99, 1.01
        if lo < 1.0 < hi:
            return full.with_extremes(bad="0.6"), TwoSlopeNorm(vcenter=1.0, vmin=lo, vmax=hi)
        part = np.linspace(0.5, 1.0, 128) if lo >= 1.0 else np.linspace(0.0, 0.5, 128)
        cmap = ListedColormap(full(part), name="RdBu_r_half").with_extremes(bad="0.6")
    else:
        lo = 0.0 if lo is None else float(lo)
        hi = 1.0 if hi is None else float(hi)
        cmap = colormaps["viridis"].with_extremes(bad="0.6")
    if hi <= lo:
        pad = 0.5 * max(abs(lo), 1e-12) if lo != 0 else 0.5
        lo, hi = lo - pad, hi + pad
    return cmap, Normalize(vmin=lo, vmax=hi)


def _subsample(n: int, max_frames: int) -> np.ndarray:
    """Evenly spaced indices into n frames, keeping the first and last, at most max_frames."""
    if max_frames < 1:
        raise InputError(f"max_frames must be >= 1, got {max_frames}")
    if n <= max_frames:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, max_frames)).astype(np.int64))


def _bounds(arrays: Sequence[np.ndarray], pad: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) per axis over all finite points of ``arrays`` (each (n, d)), padded."""
    pts = np.concatenate([np.asarray(a, dtype=float) for a in arrays])
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if pts.size == 0:
        raise InputError("no finite positions to draw")
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, 1e-12 + 1e-9 * np.abs(hi).max())
    margin = pad * span.max()
    return lo - margin, hi + margin


def _check(mesh: Mesh, positions: np.ndarray, values: np.ndarray, dim: int) -> None:
    if mesh.dim != dim:
        raise InputError(f"this renderer needs a {dim}D mesh, got a {mesh.dim}D one")
    if np.shape(positions) != (mesh.n_points, dim):
        raise InputError(
            f"positions have shape {np.shape(positions)}; expected ({mesh.n_points}, {dim})"
        )
    if np.shape(values) != (mesh.n_cells,):
        raise InputError(f"cell_values have shape {np.shape(values)}; expected ({mesh.n_cells},)")


def _new_figure(figsize: tuple[float, float]):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save_gif(
    fig, update, n_frames: int, path: Path, fps: int, dpi: int, blit: bool = False
) -> Path:
    """Write frames update(0..n_frames-1) of ``fig`` as a GIF.

    The layout is computed once, on the first frame, then frozen. With ``blit`` (2D), the
    static picture (axes, ticks, colour bar, labels) is drawn once and each frame only redraws
    the artists ``update`` returns, onto a copy of that background: axis drawing was 2/3 of
    the time per frame. Otherwise each frame is one full draw through matplotlib's PillowWriter
    (not FuncAnimation, whose Agg playback redraws every frame a second time).
    """
    from matplotlib.animation import PillowWriter

    if fps < 1:
        raise InputError(f"fps must be >= 1, got {fps}")
    if blit:
        return _save_gif_blitted(fig, update, n_frames, path, fps, dpi)
    update(0)
    fig.canvas.draw()
    fig.set_layout_engine("none")
    writer = PillowWriter(fps=fps)
    with atomic_output(path) as tmp, writer.saving(fig, tmp, dpi):
        for i in range(n_frames):
            update(i)
            writer.grab_frame()
    return path


def _save_gif_blitted(fig, update, n_frames: int, path: Path, fps: int, dpi: int) -> Path:
    from PIL import Image

    fig.set_dpi(dpi)
    canvas = fig.canvas
    artists = update(0)
    canvas.draw()
    fig.set_layout_engine("none")
    for a in artists:
        a.set_visible(False)
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    for a in artists:
        a.set_visible(True)
    images = []
    for i in range(n_frames):
        artists = update(i)
        canvas.restore_region(background)
        for a in artists:
            fig.draw_artist(a)
        rgb = np.asarray(canvas.buffer_rgba())[:, :, :3]
        images.append(Image.fromarray(rgb.copy()).quantize(colors=255, method=2))
    with atomic_output(path) as tmp:
        images[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=round(1000 / fps),
            loop=0,
        )
    return path


# ---- 2D ----------------------------------------------------------------------------------


def _boundary_edges(cells: np.ndarray) -> np.ndarray:
    """(k, 2) vertex pairs of edges belonging to exactly one triangle of cells (m, 3)."""
    edges = np.sort(cells[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    uniq, counts = np.unique(edges, axis=0, return_counts=True)
    return uniq[counts == 1]


def _material_weights(levels: np.ndarray) -> np.ndarray:
    """(m, 4, 3) vertex weights of each triangle's material part {level >= 0} (a cut mesh's
    copies, ``Mesh.cell_levels``; +inf for whole cells): a triangle or a quadrilateral, the
    shorter ones padded with their last corner, so that a copy is drawn as its material only
    and the faces of a cut show apart."""
    m = len(levels)
    lv = np.where(np.isfinite(levels), levels, 1.0)
    slots = np.zeros((m, 6, 3))
    valid = np.zeros((m, 6), dtype=bool)
    eye = np.eye(3)
    for k in range(3):  # edge k -> k + 1: its start if inside, then its crossing
        i, j = k, (k + 1) % 3
        li, lj = lv[:, i], lv[:, j]
        slots[:, 2 * k] = eye[i]
        valid[:, 2 * k] = li >= 0.0
        cross = li * lj < 0.0
        t = np.where(cross, li / np.where(cross, li - lj, 1.0), 0.0)
        slots[:, 2 * k + 1] = (1.0 - t)[:, None] * eye[i] + t[:, None] * eye[j]
        valid[:, 2 * k + 1] = cross
    order = np.argsort(~valid, axis=1, kind="stable")[:, :4]  # the valid corners first, in turn
    count = valid.sum(axis=1)
    last = np.take_along_axis(order, np.maximum(count - 1, 0)[:, None], axis=1)
    order = np.where(np.arange(4)[None, :] < count[:, None], order, last)
    return np.take_along_axis(slots, order[:, :, None], axis=1)


def _cell_polygons(mesh: Mesh, x: np.ndarray) -> np.ndarray:
    """The polygons to draw for each cell at positions x: the triangles, or for a cut mesh
    each copy's material part."""
    if mesh.cell_levels is None:
        return x[mesh.cells]
    if mesh.cell_more_levels is not None:  # copies several cuts bound: clipped by each level
        return np.einsum("mkv,mvd->mkd", _clipped_weights(mesh), x[mesh.cells])
    return np.einsum("mkv,mvd->mkd", _material_weights(mesh.cell_levels), x[mesh.cells])


def _clipped_weights(mesh: Mesh) -> np.ndarray:
    """(m, K, 3) vertex weights of each triangle's material part where several levels bound
    it (``Mesh.cell_more_levels``): the triangle clipped by each of its levels, shorter
    polygons padded with their last corner."""
    from tissuesim.contact.cut.surface import level_stack
    from tissuesim.mesh.cutting.polygon_clip import clip_polygons

    levels = level_stack(mesh)
    m, C, _ = levels.shape
    W = np.zeros((m, 3 + C, 3))
    W[:, np.arange(3), np.arange(3)] = 1.0
    count = np.full(m, 3)
    for i in range(C):
        W, count = clip_polygons(W, count, np.where(np.isfinite(levels[:, i]), levels[:, i], 1.0))
    last = np.take_along_axis(W, np.maximum(count - 1, 0)[:, None, None], axis=1)
    pad = np.arange(W.shape[1])[None, :, None] >= count[:, None, None]
    return np.where(pad, last, W)


def _setup_2d(
    mesh: Mesh,
    all_positions: Sequence[np.ndarray],
    label: str,
    cmap,
    norm,
    rest_outline,
    lines: np.ndarray | None = None,
):
    from matplotlib.cm import ScalarMappable
    from matplotlib.collections import LineCollection, PolyCollection

    rest = np.asarray(mesh.points, dtype=float)
    lo, hi = _bounds([*all_positions, rest] if rest_outline else list(all_positions))
    aspect = float(np.clip((hi[1] - lo[1]) / (hi[0] - lo[0]), 0.3, 1.6))
    fig = _new_figure((7.0, 1.2 + 5.2 * aspect))
    ax = fig.add_subplot()
    many = mesh.n_cells > 5000
    coll = PolyCollection(
        _cell_polygons(mesh, np.asarray(all_positions[0], dtype=float)),
        cmap=cmap,
        norm=norm,
        edgecolors="face" if many else (0.0, 0.0, 0.0, 0.25),
        linewidths=0.2 if many else 0.3,
    )
    ax.add_collection(coll)
    overlay = []  # drawn over the mesh: a GIF redraws it after the mesh in every frame
    if rest_outline:
        segs = rest[_boundary_edges(np.asarray(mesh.cells))]
        overlay.append(
            ax.add_collection(
                LineCollection(segs, colors="0.35", linewidths=0.8, linestyles="--", zorder=3)
            )
        )
    if lines is not None:  # visual polylines, over the mesh
        overlay.append(ax.add_collection(LineCollection(lines, colors="k", linewidths=1.2)))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax, label=label, shrink=0.9)
    return fig, ax, coll, overlay


def render_frame_png(
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
    dpi: int = 150,
    lines: np.ndarray | None = None,
) -> Path:
    """Draw the deformed triangles (positions (n, 2)) coloured by cell_values (m,) to a PNG.

    The rest configuration's boundary is drawn as a dashed grey outline when ``rest_outline``;
    ``lines`` (k, 2, 2), segments drawn over the mesh in black (visual polylines).
    Returns the path written.
    """
    x = np.asarray(positions, dtype=float)
    vals = np.asarray(cell_values, dtype=float)
    _check(mesh, x, vals, 2)
    cmap, norm = _colour_map([vals], label, vmin, vmax)
    fig, ax, coll, _ = _setup_2d(mesh, [x], label, cmap, norm, rest_outline, lines)
    coll.set_array(vals)
    if title:
        ax.set_title(title)
    path = Path(path)
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight", pad_inches=0.1)
    return path


def render_gif(
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
    dpi: int = 80,
    lines: Sequence[np.ndarray] | None = None,
) -> Path:
    """Animate frames [(time, positions (n, 2), cell_values (m,)), ...] into a GIF.

    Axis limits and the colour range are fixed over the whole run; each frame's title shows t
    (after ``title`` if given). More than ``max_frames`` frames are subsampled evenly (first and
    last kept). ``lines``: one (k, 2, 2) array of segments per frame, drawn over the mesh in
    black (visual polylines). Note that GIF writers merge pixel-identical consecutive frames.
    """
    if not frames:
        raise InputError("render_gif needs at least one frame")
    picked = _subsample(len(frames), max_frames)
    segments = None if lines is None else [lines[i] for i in picked]
    sel = [frames[i] for i in picked]
    data = [(float(t), np.asarray(x, dtype=float), np.asarray(v, dtype=float)) for t, x, v in sel]
    for _, x, v in data:
        _check(mesh, x, v, 2)
    cmap, norm = _colour_map([v for _, _, v in data], label, vmin, vmax)
    fig, ax, coll, overlay = _setup_2d(
        mesh,
        [x for _, x, _ in data],
        label,
        cmap,
        norm,
        rest_outline,
        None if segments is None else segments[0],
    )
    prefix = f"{title}   " if title else ""

    def update(i: int) -> Any:
        t, x, v = data[i]
        coll.set_verts(_cell_polygons(mesh, x))
        coll.set_array(v)
        if segments is not None:
            overlay[-1].set_segments(segments[i])
        ax.set_title(f"{prefix}t = {t:.4g} s")
        return (coll, *overlay, ax.title)

    return _save_gif(fig, update, len(data), Path(path), fps, dpi, blit=True)
