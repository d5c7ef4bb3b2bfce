"""A GIF of a run from 3D frames (``layers3d.Frame3D``), drawn off-screen by ``pyvista3d.py``:
one plotter for the whole run, the camera fitted once to the first frame (so motion shows as
motion), each colour bar's range the union over the frames so far, an adaptive palette per
frame that keeps the bars' and legend's colours, written atomically when closed."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.io.atomic import atomic_output
from tissuesim.render.layers3d import Camera, Frame3D, _fit_camera, _scene_points
from tissuesim.render.pyvista3d import (
    _GIF_PAD,
    _KEY_WEIGHT,
    _check_window,
    _clims,
    _draw,
    _import_pyvista,
    _new_plotter,
    _scalar_groups,
    _screenshot,
    _union,
)

__all__ = ["GifWriter"]


def _to_palette(img: np.ndarray, keys: np.ndarray):
    """Pillow 256-colour ("P") image of img (h, w, 3), with its own palette, not dithered.

    Median cut spends colours on the picture's big areas, so small ones (a colour bar, legend
    squares) come out banded or wrong; the key colours keys (k, 3) are appended as a strip
    weighing ``_KEY_WEIGHT`` of the picture while the palette is made. Dithering would make every
    frame differ everywhere (large files, flicker).
    """
    from PIL import Image

    h, w = img.shape[:2]
    stack = img
    if len(keys):
        strip = np.repeat(keys, max(1, round(_KEY_WEIGHT * h * w / len(keys))), axis=0)
        rows = -(-len(strip) // w)
        strip = np.concatenate([strip, np.repeat(strip[-1:], rows * w - len(strip), axis=0)])
        stack = np.concatenate([img, strip.reshape(rows, w, 3)])
    pal = Image.fromarray(stack).quantize(
        256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
    )
    return pal.crop((0, 0, w, h)) if len(keys) else pal


class GifWriter:
    """Collect frames of a run into an animated GIF (looping forever), written by ``close()``.

    One off-screen plotter lives from the first ``add`` to ``close``; each added frame replaces
    the scene, is screenshot and kept as a 256-colour image. The camera is fixed over the run
    (``camera``, or fitted to the first frame's bounds enlarged by 15 % of their size on every
    side). Point colour ranges are fixed where a layer gives ``clim``; otherwise a colour bar
    covers every value added so far (it can only grow).

    Frame budget: at most ``max_frames`` frames are kept. Frames are kept with a stride k
    (a power of two, starting at 1): frame i is kept when i % k == 0; whenever the kept frames
    would exceed ``max_frames``, k doubles and the kept frames that are not multiples of the
    new k are dropped. So a long run ends up with every k-th frame, evenly spaced, and frames
    that will not be kept are never rendered. The last frame added is always shown (rendered
    by ``close()``, replacing the last kept one if the budget is full). As with any GIF writer,
    pixel-identical consecutive frames are merged into one longer frame. Kept frames are held
    in memory until ``close()``, about width x height bytes each (96 MB for 200 at 800 x 600).

    Use as a context manager (``with GifWriter(p) as gif: gif.add(f)``): on a normal exit the
    GIF is written, after an exception nothing is written and the plotter is released.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        window_size: tuple[int, int] = (800, 600),
        fps: int = 8,
        camera: Camera | None = None,
        max_frames: int = 200,
    ) -> None:
        self._pv = _import_pyvista()
        if fps < 1:
            raise InputError(f"fps must be >= 1, got {fps}")
        if max_frames < 1:
            raise InputError(f"max_frames must be >= 1, got {max_frames}")
        self.path = Path(path)
        self.window_size = _check_window(window_size)
        self.fps = int(fps)
        self.max_frames = int(max_frames)
        self._camera = camera
        self._plotter = None
        self._n_added = 0
        self._stride = 1
        self._kept: list[tuple[int, Any]] = []  # (index of the frame, palette image)
        self._pending: Frame3D | None = None  # the last frame added, if it was not rendered
        self._seen: dict[str, tuple[float, float]] = {}  # colour bar -> data range so far
        self._closed = False

    @property
    def camera(self) -> Camera | None:
        """The fixed camera (None until the first frame is added, unless one was given)."""
        return self._camera

    @property
    def n_added(self) -> int:
        """Frames added so far (kept or not)."""
        return self._n_added

    def add(self, frame: Frame3D) -> None:
        """Add the next frame of the run (rendered now if it is one the budget keeps)."""
        if self._closed:
            raise RuntimeError("GifWriter is closed")
        if not isinstance(frame, Frame3D):
            raise TypeError(f"frame must be a Frame3D, got {type(frame).__name__}")
        for title, g in _scalar_groups(frame).items():
            if g["data"] is not None:
                self._seen[title] = _union(self._seen.get(title), g["data"])
        i = self._n_added
        self._n_added += 1
        if i % self._stride:
            self._pending = frame
            return
        self._pending = None
        self._kept.append((i, self._render(frame)))
        if len(self._kept) > self.max_frames:
            self._stride *= 2
            self._kept = [(j, im) for j, im in self._kept if j % self._stride == 0]

    def close(self) -> Path:
        """Write the GIF (atomically) and release the plotter; returns the path.

        Raises ValueError if no frame was added. Calling it again does nothing.
        """
        if self._closed:
            return self.path
        try:
            if self._pending is not None:
                last = (self._n_added - 1, self._render(self._pending))
                if len(self._kept) < self.max_frames:
                    self._kept.append(last)
                else:
                    self._kept[-1] = last
                self._pending = None
            if not self._kept:
                raise InputError("GifWriter needs at least one frame")
            images = [im for _, im in self._kept]
            with atomic_output(self.path) as tmp:
                images[0].save(
                    tmp,
                    format="GIF",
                    save_all=True,
                    append_images=images[1:],
                    duration=max(20, round(1000 / self.fps)),
                    loop=0,
                )
        finally:
            self._release()
        return self.path

    def _release(self) -> None:
        self._closed = True
        self._kept = []
        self._pending = None
        if self._plotter is not None:
            self._plotter.close()
            self._plotter = None

    def __enter__(self) -> GifWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self._release()

    def _render(self, frame: Frame3D):
        if self._plotter is None:
            self._plotter = _new_plotter(self._pv, self.window_size)
        if self._camera is None:
            self._camera = _fit_camera(_scene_points(frame), self.window_size, _GIF_PAD)
        clims = _clims(_scalar_groups(frame), self._seen)
        keys = _draw(self._pv, self._plotter, frame, clims, self._camera)
        return _to_palette(_screenshot(self._plotter), keys)
