"""What a 3D picture shows, before any rendering library is loaded: organs as triangle surfaces
(``SurfaceLayer``), tissue as points (``PointLayer``), cuts, one moment of a scene
(``Frame3D``), and the camera that frames it (``Camera``, fitted by ``fit_camera``). Drawn by
``pyvista3d.py`` (PNG) and ``gif3d.py`` (GIF).

Shapes: SurfaceLayer points (n, 3), triangles (m, 3) ids into points, scalars (n,); PointLayer
points (q, 3), scalars (q,); each cut (m, 3, 3) triangle corners; each cut outline (k, 2, 3)
segment ends.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tissuesim.errors import InputError

__all__ = ["Camera", "Frame3D", "PointLayer", "SurfaceLayer", "_fit_camera", "_scene_points"]

_ELEV, _AZIM = 22.0, -55.0  # default view direction in degrees, as plot3d / points3d
_VIEW_ANGLE = 30.0  # VTK's default vertical view angle in degrees
# the part of the window the scene is fitted into (x0, y0, x1, y1, normalised): clear of the
# title above and of the right-hand column (legend, colour bars, axes)
_SCENE_BOX = (0.03, 0.04, 0.79, 0.90)


def _frozen_array(a: Any, dtype, what: str) -> np.ndarray:
    try:
        x = np.array(a, dtype=dtype)  # a copy: later changes to the caller's array do not leak in
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what} must be a numeric array: {exc}") from exc
    x.flags.writeable = False
    return x


@dataclass(frozen=True, eq=False)
class SurfaceLayer:
    """An organ's triangle surface: points (n, 3), triangles (m, 3) ids into points.

    Drawn smooth-shaded in ``color`` (any colour name or hex string VTK knows) with
    ``opacity``; with ``scalars`` (n,) it is coloured by them instead (viridis, one colour bar
    titled ``name``). Arrays are copied and made read-only.
    """

    name: str
    points: np.ndarray
    triangles: np.ndarray
    color: str = "lightgrey"
    opacity: float = 1.0
    scalars: np.ndarray | None = None
    scalar_name: str = ""  # the colour bar's title (layers sharing it share one bar)
    clim: tuple[float, float] | None = None
    # context (an obstacle: a floor, a ramp): drawn, but the view is framed on the bodies and
    # takes in only the part of it near them, so a large plane does not shrink them to a speck
    context: bool = False

    @property
    def bar_title(self) -> str:
        return self.scalar_name or self.name

    def __post_init__(self) -> None:
        x = _frozen_array(self.points, float, f"surface {self.name!r} points")
        tri = _frozen_array(self.triangles, np.int64, f"surface {self.name!r} triangles")
        if x.ndim != 2 or x.shape[1] != 3:
            raise InputError(f"surface {self.name!r} points have shape {x.shape}; expected (n, 3)")
        if tri.size == 0:
            tri = np.zeros((0, 3), dtype=np.int64)
        if tri.ndim != 2 or tri.shape[1] != 3:
            raise InputError(
                f"surface {self.name!r} triangles have shape {tri.shape}; expected (m, 3)"
            )
        if len(tri) and (tri.min() < 0 or tri.max() >= len(x)):
            raise InputError(f"surface {self.name!r} triangles must be ids in [0, {len(x)})")
        if not 0.0 <= float(self.opacity) <= 1.0:
            raise InputError(f"surface {self.name!r} opacity must be in [0, 1], got {self.opacity}")
        object.__setattr__(self, "points", x)
        object.__setattr__(self, "triangles", tri)
        object.__setattr__(self, "opacity", float(self.opacity))
        if self.scalars is not None:
            s = _frozen_array(self.scalars, float, f"surface {self.name!r} scalars")
            if s.shape != (len(x),):
                raise InputError(
                    f"surface {self.name!r} scalars have shape {s.shape}; expected ({len(x)},)"
                )
            object.__setattr__(self, "scalars", s)


@dataclass(frozen=True, eq=False)
class PointLayer:
    """Points (q, 3), e.g. a tissue's integration points, coloured by ``scalars`` (q,).

    ``scalar_name`` titles the colour bar (layers sharing it share one bar and one colour
    range); ``clim`` (lo, hi) fixes the colour range, else it is the data's range (in a GIF: the
    range of every frame added so far). Without scalars the points are dark grey.
    ``point_size`` is in pixels. q may be 0. Arrays are copied and made read-only.
    """

    name: str
    points: np.ndarray
    scalars: np.ndarray | None = None
    scalar_name: str = ""
    cmap: str = "viridis"
    clim: tuple[float, float] | None = None
    point_size: float = 7.0

    def __post_init__(self) -> None:
        x = _frozen_array(self.points, float, f"point layer {self.name!r} points")
        if x.size == 0:
            x = _frozen_array(np.zeros((0, 3)), float, "points")
        if x.ndim != 2 or x.shape[1] != 3:
            raise InputError(f"point layer {self.name!r} points have shape {x.shape}; (q, 3)")
        object.__setattr__(self, "points", x)
        if self.scalars is not None:
            s = _frozen_array(self.scalars, float, f"point layer {self.name!r} scalars")
            if s.shape != (len(x),):
                raise InputError(
                    f"point layer {self.name!r} scalars have shape {s.shape}; expected ({len(x)},)"
                )
            object.__setattr__(self, "scalars", s)
        if self.clim is not None:
            lo, hi = (float(c) for c in self.clim)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                raise InputError(f"point layer {self.name!r} clim must be finite lo <= hi")
            object.__setattr__(self, "clim", (lo, hi))
        if not float(self.point_size) > 0:
            raise InputError(f"point layer {self.name!r} point_size must be > 0")
        object.__setattr__(self, "point_size", float(self.point_size))

    @property
    def bar_title(self) -> str:
        return self.scalar_name or self.name


@dataclass(frozen=True, eq=False)
class Frame3D:
    """One moment of a coupled scene: organ surfaces, point layers, cuts and a title.

    ``cuts`` is a sequence of (m, 3, 3) arrays of triangle corners (a single (m, 3, 3) array is
    taken as one cut), drawn as translucent sheets; ``cut_outlines`` a sequence of (k, 2, 3)
    line segments, the border of a cut that has ended, drawn as lines only (a sheet would hide
    the organs under it for the rest of the run); any of the sequences may be empty. Stored
    as tuples.
    """

    surfaces: Sequence[SurfaceLayer] = ()
    points: Sequence[PointLayer] = ()
    cuts: Sequence[np.ndarray] = ()
    title: str = ""
    # what the colour bars show, written once above them when each bar is titled by its body
    bar_heading: str = ""
    cut_outlines: Sequence[np.ndarray] = ()

    def __post_init__(self) -> None:
        for what, items, kind in (
            ("surfaces", self.surfaces, SurfaceLayer),
            ("points", self.points, PointLayer),
        ):
            bad = [type(s).__name__ for s in items if not isinstance(s, kind)]
            if bad:
                raise TypeError(f"Frame3D.{what} must hold {kind.__name__}s, got {bad[0]}")
        cuts = self.cuts
        if isinstance(cuts, np.ndarray) and cuts.ndim == 3:
            cuts = [cuts]
        arrays = []
        for i, c in enumerate(cuts):
            a = _frozen_array(c, float, f"cut {i}")
            if a.size == 0:
                continue
            if a.ndim != 3 or a.shape[1:] != (3, 3):
                raise InputError(f"cut {i} has shape {a.shape}; expected (m, 3, 3)")
            arrays.append(a)
        lines = []
        for i, c in enumerate(self.cut_outlines):
            a = _frozen_array(c, float, f"cut outline {i}")
            if a.size == 0:
                continue
            if a.ndim != 3 or a.shape[1:] != (2, 3):
                raise InputError(f"cut outline {i} has shape {a.shape}; expected (k, 2, 3)")
            lines.append(a)
        object.__setattr__(self, "surfaces", tuple(self.surfaces))
        object.__setattr__(self, "points", tuple(self.points))
        object.__setattr__(self, "cuts", tuple(arrays))
        object.__setattr__(self, "cut_outlines", tuple(lines))
        object.__setattr__(self, "title", str(self.title))


#: context layers count for the view within this fraction of the bodies' size around them
CONTEXT_MARGIN = 0.5


def _scene_points(frame: Frame3D) -> np.ndarray:
    """(k, 3) the points the view is fitted to: the bodies' surface vertices, layer points and
    cut corners, and of context layers (obstacles) the points within CONTEXT_MARGIN of the
    bodies' size around their box (all of them when there is no body)."""
    arrays = [s.points for s in frame.surfaces if not s.context] + [p.points for p in frame.points]
    arrays += [c.reshape(-1, 3) for c in (*frame.cuts, *frame.cut_outlines)]
    own = np.concatenate([np.zeros((0, 3)), *arrays])
    context = [s.points for s in frame.surfaces if s.context]
    if not context:
        return own
    context = np.concatenate(context)
    if len(own) == 0:
        return context
    lo, hi = own.min(axis=0), own.max(axis=0)
    margin = CONTEXT_MARGIN * float(np.max(hi - lo))
    near = np.all((context >= lo - margin) & (context <= hi + margin), axis=1)
    return np.concatenate([own, context[near]])


@dataclass(frozen=True)
class Camera:
    """A fixed view: camera position, the point it looks at, and the up direction (world)."""

    position: tuple[float, float, float]
    focal_point: tuple[float, float, float]
    view_up: tuple[float, float, float]

    def __post_init__(self) -> None:
        for name in ("position", "focal_point", "view_up"):
            v = tuple(float(c) for c in getattr(self, name))
            if len(v) != 3 or not all(math.isfinite(c) for c in v):
                raise InputError(f"Camera.{name} must be 3 finite numbers, got {v}")
            object.__setattr__(self, name, v)


def _fit_camera(points: np.ndarray, window_size: tuple[int, int], pad: float) -> Camera:
    """Default view of ``points`` (k, 3) scaled about their bounding box's centre by 1 + 2 pad.

    The points are fitted (perspective, VTK's 30 degree view angle) into ``_SCENE_BOX`` of the
    window and centred in it; the camera is shifted sideways for that, so the view direction
    stays the default one.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if not len(pts):
        pts = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = 0.5 * (lo + hi)
    big = float((hi - lo).max())
    if big <= 0.0:  # a single point: show a box of size about 1 (or |point|) around it
        big = max(1.0, float(np.abs(centre).max()))
        pts = centre + 0.5 * big * np.array([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]])
    if len(pts) > 20_000:  # plenty for the framing
        pts = pts[np.linspace(0, len(pts) - 1, 20_000).astype(np.int64)]
    rel = (pts - centre) * (1.0 + 2.0 * pad)

    e, a = np.radians(_ELEV), np.radians(_AZIM)
    back = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])  # to the camera
    right = np.cross(-back, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -back)

    w, h = window_size
    tan_v = math.tan(math.radians(_VIEW_ANGLE) / 2)
    tan_h = tan_v * w / h
    x0, y0, x1, y1 = _SCENE_BOX
    # the scene box in normalised device coordinates [-1, 1]: its half sizes and centre
    sx, sy = x1 - x0, y1 - y0
    cx, cy = x0 + x1 - 1.0, y0 + y1 - 1.0
    xr, yu, zb = rel @ right, rel @ up, rel @ back
    ox = oy = 0.0  # sideways offset of the focal point, centring the picture of the points
    for _ in range(3):
        # a point at depth zb (towards the camera) fits if |xr - ox| <= (dist - zb) tan_h sx
        dist = float(
            np.max(np.maximum(np.abs(xr - ox) / (tan_h * sx), np.abs(yu - oy) / (tan_v * sy)) + zb)
        )
        px, py = (xr - ox) / (dist - zb), (yu - oy) / (dist - zb)
        ox += 0.5 * (px.min() + px.max()) * dist
        oy += 0.5 * (py.min() + py.max()) * dist
    dist = float(
        np.max(np.maximum(np.abs(xr - ox) / (tan_h * sx), np.abs(yu - oy) / (tan_v * sy)) + zb)
    )
    # shift the camera (and focal point) so the picture's centre lands at (cx, cy)
    focal = centre + (ox - cx * dist * tan_h) * right + (oy - cy * dist * tan_v) * up
    return Camera(tuple(focal + dist * back), tuple(focal), tuple(up))
