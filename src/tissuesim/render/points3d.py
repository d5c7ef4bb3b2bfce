"""Pictures of meshless (frame-based) bodies with mplot3d: an embedded surface or a point cloud.

A frame-based body has no volume mesh to draw. With ``triangles`` (a surface carried by the
frames) it is drawn as shaded triangles, each coloured by the mean of its vertices' values, with
the rest surface's feature edges as a dashed grey outline; without, the points themselves are a
scatter coloured by their values over the rest points drawn faint. ``markers`` (the frame
origins) are black dots drawn on top, since they usually lie inside the body. Equal axis scaling
and a fixed view; a GIF keeps axis limits and the colour range fixed over the whole run. Colours
as in ``plot2d`` (viridis unless ``label == "J"``). The figure scaffolding is ``plot3d``'s.

Shapes: positions (n, 3); values (n,) one per point; triangles (m, 3) ids into positions;
rest (n, 3) rest positions; markers (k, 3).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.io.atomic import atomic_output
from tissuesim.render.plot2d import _bounds, _colour_map, _save_gif, _subsample
from tissuesim.render.plot3d import (
    _face_colours,
    _figure_3d,
    _finish_axes_3d,
    _rest_outline,
    _surface_collection,
)

__all__ = ["PointFrame", "render_points_gif", "render_points_png"]

PointFrame = tuple[float, np.ndarray, np.ndarray, np.ndarray]
"""(time, positions (n, 3), values (n,), markers (k, 3)) of one state."""


def _as_frame(
    positions: np.ndarray,
    values: np.ndarray,
    markers: np.ndarray | None,
    n: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Float arrays with their shapes checked against n points (markers may be absent)."""
    x = np.asarray(positions, dtype=float)
    v = np.asarray(values, dtype=float)
    m = np.zeros((0, 3)) if markers is None else np.asarray(markers, dtype=float)
    if x.shape != (n, 3):
        raise InputError(f"positions have shape {x.shape}; expected ({n}, 3)")
    if v.shape != (n,):
        raise InputError(f"values have shape {v.shape}; expected ({n},), one per point")
    if m.ndim != 2 or m.shape[1] != 3:
        raise InputError(f"markers have shape {m.shape}; expected (k, 3)")
    return x, v, m


def _check_body(n: int, triangles: np.ndarray | None, rest: np.ndarray | None):
    tri = None if triangles is None else np.asarray(triangles, dtype=np.int64)
    if tri is not None and (
        tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0 or tri.min() < 0 or tri.max() >= n
    ):
        raise InputError(f"triangles must be (m, 3) ids in [0, {n}), got shape {tri.shape}")
    x0 = None if rest is None else np.asarray(rest, dtype=float)
    if x0 is not None and x0.shape != (n, 3):
        raise InputError(f"rest positions have shape {x0.shape}; expected ({n}, 3)")
    return tri, x0


def _setup_points(
    data: Sequence[tuple[float, np.ndarray, np.ndarray, np.ndarray]],
    triangles: np.ndarray | None,
    rest: np.ndarray | None,
    label: str,
    cmap,
    norm,
    elev: float,
    azim: float,
    max_points: int,
) -> tuple[Any, Any, Callable[[np.ndarray, np.ndarray, np.ndarray], None]]:
    """Figure with limits covering every frame (and rest); returns (fig, ax, draw(x, v, m))."""
    _, x_first, _, m_first = data[0]
    arrays = [x for _, x, _, _ in data] + [m for _, _, _, m in data if len(m)]
    lo, hi = _bounds(arrays + ([rest] if rest is not None else []), pad=0.02)
    fig, ax = _figure_3d()
    sel = _subsample(len(x_first), max_points)  # a scatter of 1e5 points is slow and unreadable
    size = float(np.clip(4000.0 / len(sel), 1.0, 25.0))
    coll = None
    if triangles is not None:
        coll = _surface_collection(ax, x_first[triangles])
        if rest is not None:
            _rest_outline(ax, rest, triangles)
    elif rest is not None:
        ax.scatter(*rest[sel].T, s=0.5 * size, c="0.6", alpha=0.25, depthshade=False, zorder=0)
    (dots,) = ax.plot(*m_first.T, linestyle="none", marker="o", ms=4.0, color="k", zorder=3)
    _finish_axes_3d(fig, ax, lo, hi, label, cmap, norm, elev, azim)
    cloud = []

    def draw(x: np.ndarray, v: np.ndarray, m: np.ndarray) -> None:
        if coll is not None:
            coll.set_verts(x[triangles])
            coll.set_facecolor(_face_colours(x, triangles, v[triangles].mean(axis=1), cmap, norm))
        else:  # limits are fixed (autoscale off), so a fresh scatter leaves them alone
            if cloud:
                cloud.pop().remove()
            vals = np.ma.masked_invalid(v[sel])
            cloud.append(
                ax.scatter(*x[sel].T, c=vals, cmap=cmap, norm=norm, s=size, linewidths=0, zorder=1)
            )
        dots.set_data_3d(m[:, 0], m[:, 1], m[:, 2])

    return fig, ax, draw


def render_points_png(
    positions: np.ndarray,
    values: np.ndarray,
    path: str | os.PathLike[str],
    *,
    triangles: np.ndarray | None = None,
    rest: np.ndarray | None = None,
    markers: np.ndarray | None = None,
    title: str = "",
    label: str = "|u|",
    vmin: float | None = None,
    vmax: float | None = None,
    elev: float = 22.0,
    azim: float = -55.0,
    max_points: int = 20_000,
    dpi: int = 150,
) -> Path:
    """Draw one state of a meshless body (surface if ``triangles``, else points) to a PNG.

    Returns the path written.
    """
    tri, x0 = _check_body(np.shape(positions)[0], triangles, rest)
    x, v, m = _as_frame(positions, values, markers, np.shape(positions)[0])
    cmap, norm = _colour_map([v], label, vmin, vmax)
    fig, ax, draw = _setup_points(
        [(0.0, x, v, m)], tri, x0, label, cmap, norm, elev, azim, max_points
    )
    draw(x, v, m)
    if title:
        ax.set_title(title)
    path = Path(path)
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight", pad_inches=0.1)
    return path


def render_points_gif(
    frames: Sequence[PointFrame],
    path: str | os.PathLike[str],
    *,
    triangles: np.ndarray | None = None,
    rest: np.ndarray | None = None,
    label: str = "|u|",
    fps: int = 15,
    vmin: float | None = None,
    vmax: float | None = None,
    max_frames: int = 150,
    title: str = "",
    elev: float = 22.0,
    azim: float = -55.0,
    max_points: int = 20_000,
    dpi: int = 80,
) -> Path:
    """Animate frames [(time, positions (n, 3), values (n,), markers (k, 3)), ...] into a GIF.

    Fixed axis limits, view and colour range over the whole run; title shows t. More than
    ``max_frames`` frames are subsampled evenly (first and last kept).
    """
    if not frames:
        raise InputError("render_points_gif needs at least one frame")
    n = np.shape(frames[0][1])[0]
    tri, x0 = _check_body(n, triangles, rest)
    sel = [frames[i] for i in _subsample(len(frames), max_frames)]
    data = [(float(t), *_as_frame(x, v, m, n)) for t, x, v, m in sel]
    cmap, norm = _colour_map([v for _, _, v, _ in data], label, vmin, vmax)
    fig, ax, draw = _setup_points(data, tri, x0, label, cmap, norm, elev, azim, max_points)
    prefix = f"{title}   " if title else ""

    def update(i: int) -> Any:
        t, x, v, m = data[i]
        draw(x, v, m)
        ax.set_title(f"{prefix}t = {t:.4g}")
        return ()

    return _save_gif(fig, update, len(data), Path(path), fps, dpi)
