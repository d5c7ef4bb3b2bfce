"""Pictures with matplotlib (Agg, no display): PNG frames and animated GIFs of 2D and 3D meshes.

``render_frame`` / ``render_animation`` pick the 2D (triangles) or 3D (tetrahedra) renderer
from ``mesh.dim``; keyword arguments are passed through. ``render_points_png`` /
``render_points_gif`` draw meshless bodies (an embedded surface or a point cloud).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.mesh import Mesh
from tissuesim.render.plot2d import Frame, render_frame_png, render_gif
from tissuesim.render.plot3d import render_frame_png_3d, render_gif_3d
from tissuesim.render.points3d import render_points_gif, render_points_png

__all__ = [
    "render_animation",
    "render_frame",
    "render_frame_png",
    "render_frame_png_3d",
    "render_gif",
    "render_gif_3d",
    "render_points_gif",
    "render_points_png",
]


def render_frame(
    mesh: Mesh,
    positions: np.ndarray,
    cell_values: np.ndarray,
    path: str | os.PathLike[str],
    **kwargs: Any,
) -> Path:
    """PNG of one state: positions (n, d), cell_values (m,); dispatches on mesh.dim (2 or 3)."""
    if mesh.dim == 2:
        return render_frame_png(mesh, positions, cell_values, path, **kwargs)
    if mesh.dim == 3:
        return render_frame_png_3d(mesh, positions, cell_values, path, **kwargs)
    raise InputError(f"cannot render a {mesh.dim}D mesh; only 2D and 3D are supported")


def render_animation(
    mesh: Mesh, frames: Sequence[Frame], path: str | os.PathLike[str], **kwargs: Any
) -> Path:
    """GIF of frames [(time, positions (n, d), cell_values (m,))]; dispatches on mesh.dim."""
    if mesh.dim == 2:
        return render_gif(mesh, frames, path, **kwargs)
    if mesh.dim == 3:
        return render_gif_3d(mesh, frames, path, **kwargs)
    raise InputError(f"cannot animate a {mesh.dim}D mesh; only 2D and 3D are supported")
