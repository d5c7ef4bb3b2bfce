"""Off-screen 3D pictures of coupled scenes with PyVista (VTK): a PNG of one moment, a GIF of a run.

A scene (``Frame3D``) holds organs as triangle surfaces (``SurfaceLayer``), connective tissue as
points (``PointLayer``, e.g. integration points coloured by strain) and cut surfaces (triangle
soups, drawn semi-transparent red, with dark red edges if they have few triangles; a cut that
has ended as its red outline only, ``Frame3D.cut_outlines``). Organs are
smooth-shaded in their colour (or coloured by their ``scalars``), without edges; points are
rendered as small spheres. Translucent meshes are drawn back to front (no depth peeling). The
title is centred at the top; a right-hand column, which the default camera keeps the scene clear
of, holds a legend naming the layers, one vertical colour bar per scalar name (stacked) and a
small x-y-z axes marker. White background.

Without a ``Camera``, the view looks from above the front right (azimuth -55 degrees, elevation
22 degrees, as the matplotlib renderers), z up, with the scene's points fitted into the free part
of the window with a small margin (4 % of the scene's size). ``gif3d.GifWriter`` fits that view
once, to the first frame enlarged by 15 % of its size on every side (or takes the ``camera``
given), so motion shows as motion rather than as a re-centred picture.

PyVista is an optional dependency (``pip install 'tissuesim[pyvista]'``), imported only when a
picture is made. Rendering is off-screen (``pyvista.OFF_SCREEN``); PNG and GIF files are written
with Pillow through ``tissuesim.io.atomic``, so a crash never leaves half a file.

Shapes: SurfaceLayer points (n, 3), triangles (m, 3) ids into points, scalars (n,); PointLayer
points (q, 3), scalars (q,); each cut (m, 3, 3) triangle corners.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.io.atomic import atomic_output
from tissuesim.render.layers3d import (  # re-exported: the picture's types
    _VIEW_ANGLE,
    Camera,
    Frame3D,
    PointLayer,
    SurfaceLayer,
    _fit_camera,
    _scene_points,
)

__all__ = ["Camera", "Frame3D", "PointLayer", "SurfaceLayer", "render_frame_png"]

_MISSING = "3D pictures of coupled scenes need PyVista: pip install 'tissuesim[pyvista]'"

_PNG_PAD = 0.04  # PNG: bounds enlarged by this fraction of their largest size on every side
_GIF_PAD = 0.15  # GIF: bounds of the first frame enlarged by this fraction on every side
_COLUMN_X = 0.80  # left edge of the right-hand column: legend on top, colour bars, axes
_BAR_BOX = (0.84, 0.20, 0.99, 0.62)  # colour bars (x0, y0, x1, y1)
_AXES_BOX = (0.84, 0.0, 0.99, 0.16)  # the small x-y-z axes
_LEGEND_TOP = 0.88  # top of the legend (normalised window height)
_CUT_COLOUR = "#e0201b"
_CUT_EDGES_MAX = 400  # cuts of up to this many triangles show their edges (more: a plain sheet)
_POINT_COLOUR = "#404040"  # points without scalars
_BACKGROUND = "white"
_KEY_WEIGHT = 0.05  # GIF palettes: weight of the key colours (bars, legend) against the picture


def _import_pyvista():
    """The pyvista module, set to render off-screen; a clear ImportError when it is missing."""
    try:
        import pyvista as pv
    except ImportError as exc:
        raise ImportError(_MISSING) from exc
    pv.OFF_SCREEN = True
    _quiet_vtk_warnings()
    return pv


def _quiet_vtk_warnings() -> None:
    """Keep VTK's warnings off stderr when rendering to files: off-screen, VTK first tries an X
    server and logs "bad X server connection" before it falls back to EGL/OSMesa, which says
    nothing about the picture. VTK's errors still reach stderr."""
    try:
        from vtkmodules.vtkCommonCore import vtkLogger, vtkObject
    except ImportError:  # an old VTK: its own defaults
        return
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
    vtkObject.GlobalWarningDisplayOff()


# ---- scene data ---------------------------------------------------------------------------


# ---- camera ---------------------------------------------------------------------------------


def _apply_camera(plotter, camera: Camera) -> None:
    cam = plotter.camera
    cam.position = camera.position
    cam.focal_point = camera.focal_point
    cam.up = camera.view_up
    cam.view_angle = _VIEW_ANGLE
    plotter.renderer.ResetCameraClippingRange()


# ---- drawing --------------------------------------------------------------------------------


def _check_window(window_size: tuple[int, int]) -> tuple[int, int]:
    w, h = (int(s) for s in window_size)
    if w < 16 or h < 16:
        raise InputError(f"window_size must be at least (16, 16), got {window_size}")
    return w, h


def _new_plotter(pv, window_size: tuple[int, int]):
    w, h = _check_window(window_size)
    plotter = pv.Plotter(off_screen=True, window_size=(w, h), lighting="light_kit")
    plotter.set_background(_BACKGROUND)
    plotter.enable_anti_aliasing("ssaa")
    plotter.add_axes(
        color="black",
        viewport=_AXES_BOX,
        line_width=2,
        xlabel="x (m)",
        ylabel="y (m)",
        zlabel="z (m)",
    )
    return plotter


def _union(a: tuple[float, float] | None, b: tuple[float, float] | None):
    if a is None:
        return b
    if b is None:
        return a
    return min(a[0], b[0]), max(a[1], b[1])


def _data_range(values: np.ndarray | None) -> tuple[float, float] | None:
    if values is None:
        return None
    v = values[np.isfinite(values)]
    return (float(v.min()), float(v.max())) if len(v) else None


def _scalar_groups(frame: Frame3D) -> dict[str, dict[str, Any]]:
    """Colour bars of a frame: title -> {cmap, given clim, data range}, in drawing order."""
    groups: dict[str, dict[str, Any]] = {}
    layers = [(s.bar_title, "viridis", s.clim, s.scalars) for s in frame.surfaces]
    layers += [(p.bar_title, p.cmap, p.clim, p.scalars) for p in frame.points]
    for title, cmap, clim, values in layers:
        if values is None:
            continue
        g = groups.setdefault(title, {"cmap": cmap, "clim": None, "data": None})
        if clim is not None:
            g["clim"] = _union(g["clim"], clim)
        else:
            g["data"] = _union(g["data"], _data_range(values))
    return groups


def _clims(groups: dict[str, dict[str, Any]], seen: dict[str, tuple[float, float]] | None):
    """title -> (lo, hi) colour range: given clims and data ranges (or ``seen`` ones) joined."""
    out = {}
    for title, g in groups.items():
        data = seen.get(title, g["data"]) if seen is not None else g["data"]
        lo, hi = _union(g["clim"], data) or (0.0, 1.0)
        if hi <= lo:  # a constant field: 0 .. 1 for zero (e.g. no strain yet), else +-5 %
            lo, hi = (0.0, 1.0) if lo == 0.0 else (lo - 0.05 * abs(lo), lo + 0.05 * abs(lo))
        out[title] = (lo, hi)
    return out


def _font_sizes(window_size: tuple[int, int]) -> tuple[int, int]:
    """(title, label) font sizes for the window, readable from 400 to 2000 pixels tall.

    In PyVista's units: text of size f is about 1.5 f pixels tall and 0.95 f wide per letter.
    """
    scale = min(window_size[0] / 1024, window_size[1] / 768)
    return max(8, round(13 * scale)), max(7, round(11 * scale))


def _draw(
    pv, plotter, frame: Frame3D, clims: dict[str, tuple[float, float]], camera: Camera
) -> np.ndarray:
    """Replace the plotter's scene by ``frame`` seen through ``camera``.

    Returns the picture's key colours (k, 3) uint8: samples of each colour bar and the legend's
    colours (small areas that a GIF palette must not lose).
    """
    for title in list(plotter.scalar_bars.keys()):
        plotter.remove_scalar_bar(title, render=False)
    plotter.clear_actors()  # surfaces, points, text and the legend's 2D actors

    title_size, label_size = _font_sizes(plotter.window_size)
    mappers: dict[str, Any] = {}
    legend: list[tuple[str, str]] = []
    eye = np.asarray(camera.position)
    translucent: list[tuple[float, Any, dict[str, Any], str | None]] = []

    def add(mesh, style: dict[str, Any], bar: str | None = None) -> None:
        actor = plotter.add_mesh(mesh, reset_camera=False, render=False, **style)
        # (render=False: else PyVista re-renders the whole scene after every add)
        if bar is not None:
            mappers.setdefault(bar, actor.mapper)

    def add_surface(points: np.ndarray, tri: np.ndarray, style: dict[str, Any], bar=None):
        if style["opacity"] >= 1.0:
            add(pv.PolyData.from_regular_faces(points, tri), style, bar)
            return
        # no depth peeling (broken in some Mesa/EGL builds): translucent triangles are drawn
        # back to front instead, and translucent meshes after the opaque ones, far to near
        depth = np.linalg.norm(points[tri].mean(axis=1) - eye, axis=1)
        mesh = pv.PolyData.from_regular_faces(points, tri[np.argsort(-depth, kind="stable")])
        translucent.append((float(depth.mean()), mesh, style, bar))

    for s in frame.surfaces:
        if not len(s.triangles):
            continue
        style: dict[str, Any] = dict(
            opacity=s.opacity,
            smooth_shading=True,
            show_edges=False,
            ambient=0.15,
            diffuse=0.8,
            specular=0.25,
            specular_power=20.0,
            show_scalar_bar=False,
        )
        if s.scalars is None:
            add_surface(s.points, s.triangles, dict(style, color=s.color))
            legend.append((s.name, s.color))
        else:
            style.update(scalars=s.scalars, cmap="viridis", clim=clims[s.bar_title])
            add_surface(s.points, s.triangles, style, s.bar_title)
    for p in frame.points:
        if not len(p.points):
            continue
        style = dict(
            style="points",
            point_size=p.point_size,
            render_points_as_spheres=True,
            ambient=0.25,
            show_scalar_bar=False,
        )
        if p.scalars is None:
            add(pv.PolyData(p.points), dict(style, color=_POINT_COLOUR))
            legend.append((p.name, _POINT_COLOUR))
        else:
            clim = clims[p.bar_title]
            style.update(scalars=p.scalars, cmap=p.cmap, clim=clim)
            add(pv.PolyData(p.points), style, p.bar_title)
            mid = mappers[p.bar_title].lookup_table.map_value(0.5 * (clim[0] + clim[1]))
            legend.append((p.name, pv.Color(mid).hex_rgb))
    if frame.cuts:
        corners = np.concatenate(frame.cuts).reshape(-1, 3)
        style = dict(
            opacity=0.55,
            color=_CUT_COLOUR,
            ambient=0.35,
            diffuse=0.7,
            show_edges=len(corners) <= 3 * _CUT_EDGES_MAX,
            edge_color="#7a0000",
            line_width=0.8,
        )
        add_surface(corners, np.arange(len(corners)).reshape(-1, 3), style)
        legend.append(("cut", _CUT_COLOUR))
    if frame.cut_outlines:  # a cut that has ended: its border only, hiding nothing
        ends = np.concatenate(frame.cut_outlines).reshape(-1, 3)
        pairs = np.arange(len(ends)).reshape(-1, 2)
        lines = np.column_stack([np.full(len(pairs), 2), pairs]).ravel()
        add(pv.PolyData(ends, lines=lines), dict(color=_CUT_COLOUR, line_width=2.0))
        legend.append(("cut (done)", _CUT_COLOUR))
    for _, mesh, style, bar in sorted(translucent, key=lambda item: -item[0]):
        add(mesh, style, bar)

    # colour bars stacked in the right-hand column under the legend, title on top
    w, h = plotter.window_size
    x0, y0, x1, y1 = _BAR_BOX
    slot = (y1 - y0) / max(1, len(mappers))
    bar_font = round(1.5 * label_size)  # VTK's scalar bar font sizes are about pixels
    shown: set[str] = set()
    for i, (title, mapper) in enumerate(mappers.items()):
        room, letter = (1.0 - _COLUMN_X) * w - 4, 0.45 * (bar_font + 2)
        name = _wrap_title(title, room, letter)
        while name in shown:  # PyVista merges bars of equal titles
            name += " "
        shown.add(name)
        bar = plotter.add_scalar_bar(
            title=name,
            mapper=mapper,
            vertical=True,
            position_x=x0,
            position_y=y1 - (i + 1) * slot + 0.02,
            width=min(0.05, 0.3 * (x1 - x0)),
            height=slot - 0.02,
            n_labels=5 if slot > 0.25 else 3,
            fmt=_label_format(*mapper.scalar_range),
            color="black",
            title_font_size=bar_font + 2,
            label_font_size=bar_font,
            unconstrained_font_size=True,
            render=False,
        )
        bar.SetVerticalTitleSeparation(round(0.8 * label_size))
    if frame.bar_heading and mappers:
        font = max(6, round(0.62 * bar_font))
        # PyVista text: letters about 0.95 font size wide (as the title's)
        lines = _wrap_title(frame.bar_heading, (1.0 - _COLUMN_X) * w - 8, 0.95 * font)
        lines = lines.split("\n")
        for k, line in enumerate(lines):  # bottom line just above the first bar's title
            plotter.add_text(
                line,
                position=(_COLUMN_X * w, (y1 + 0.045) * h + (len(lines) - 1 - k) * 1.9 * font),
                font_size=font,
                color="black",
                render=False,
            )
    _add_legend(plotter, legend, label_size)
    if frame.title:
        # shrink a long title to fit the width (PyVista text: letters about 0.95 size wide)
        size = max(7, min(title_size, int(0.96 * w / (0.95 * len(frame.title)))))
        text = plotter.add_text(
            _fit_text(frame.title, 0.96 * w, 0.95 * size),
            position=(0.5 * w, h - 2.8 * size),
            font_size=size,
            color="black",
            render=False,
        )
        text.GetTextProperty().SetJustificationToCentered()
    _apply_camera(plotter, camera)
    keys = [np.array([pv.Color(c).int_rgb for _, c in legend], dtype=np.uint8).reshape(-1, 3)]
    for m in mappers.values():
        table = pv.convert_array(m.lookup_table.GetTable())[:, :3]
        keys.append(table[np.linspace(0, len(table) - 1, 32).astype(np.int64)].astype(np.uint8))
    return np.concatenate(keys)


def _label_format(lo: float, hi: float) -> str:
    """A printf format whose significant digits tell a colour bar's labels apart: 0.998 to 1
    needs 5 (0.9985), 0 to 1000 three; at most 8."""
    span, size = abs(hi - lo), max(abs(lo), abs(hi))
    if not (span > 0.0 and math.isfinite(span) and size > 0.0):
        return "%.3g"
    digits = math.ceil(math.log10(size / span)) + 2
    return f"%.{min(8, max(3, digits))}g"


def _wrap_title(title: str, room: float, letter: float, max_lines: int = 3) -> str:
    """A colour bar's title in lines of about ``room`` pixels, broken between words ("liver"
    over "largest principal Green" over "strain (-)"); past ``max_lines`` the last is cut."""
    import textwrap

    fits = max(3, int(room / letter))
    lines = [part for line in title.split("\n") for part in textwrap.wrap(line, fits) or [""]]
    if len(lines) > max_lines:
        lines = lines[: max_lines - 1] + [_fit_text(" ".join(lines[max_lines - 1 :]), room, letter)]
    return "\n".join(_fit_text(line, room, letter) for line in lines)


def _fit_text(text: str, room: float, letter: float) -> str:
    """``text`` cut to about ``room`` pixels at ``letter`` pixels a letter (ending in "..")."""
    fits = max(3, int(room / letter))
    return text if len(text) <= fits else text[: fits - 2] + ".."


def _add_legend(plotter, entries: list[tuple[str, str]], font_size: int) -> None:
    """Colour squares with black names, top of the right-hand column (pixel layout)."""
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
    from vtkmodules.vtkRenderingCore import vtkActor2D, vtkPolyDataMapper2D

    if not entries:
        return
    pv = _import_pyvista()
    w, h = plotter.window_size
    x = _COLUMN_X * w
    room = w - x - 8  # pixels for square, gap and name
    longest = max(len(name) for name, _ in entries)
    # shrink the font (to no less than 7) so the longest name fits, then cut names still too long
    font_size = max(7, min(font_size, int(room / (0.95 * longest + 2.0))))
    box = round(1.1 * font_size)
    step = round(2.0 * font_size)
    for k, (name, colour) in enumerate(entries):
        y = _LEGEND_TOP * h - (k + 1) * step
        pts = vtkPoints()
        for px, py in ((x, y), (x + box, y), (x + box, y + box), (x, y + box)):
            pts.InsertNextPoint(px, py, 0.0)
        cells = vtkCellArray()
        cells.InsertNextCell(4, [0, 1, 2, 3])
        square = vtkPolyData()
        square.SetPoints(pts)
        square.SetPolys(cells)
        mapper = vtkPolyDataMapper2D()
        mapper.SetInputData(square)
        actor = vtkActor2D()
        actor.SetMapper(mapper)
        actor.GetProperty().SetColor(pv.Color(colour).float_rgb)
        plotter.add_actor(actor, reset_camera=False, render=False)
        plotter.add_text(
            _fit_text(name, room - box - 0.7 * font_size, 0.95 * font_size),
            position=(x + box + 0.7 * font_size, y - 0.3 * font_size),
            font_size=font_size,
            color="black",
            render=False,
        )


def _screenshot(plotter) -> np.ndarray:
    """(h, w, 3) uint8 picture of the current scene, freshly rendered."""
    plotter.render()  # PyVista's screenshot re-renders only the first time
    img = plotter.screenshot(return_img=True)
    return np.ascontiguousarray(img[..., :3], dtype=np.uint8)


# ---- PNG ------------------------------------------------------------------------------------


def render_frame_png(
    path: str | os.PathLike[str],
    frame: Frame3D,
    *,
    window_size: tuple[int, int] = (1024, 768),
    camera: Camera | None = None,
) -> Camera:
    """Render ``frame`` off-screen to a PNG of ``window_size`` (width, height) pixels.

    Without ``camera`` the view is fitted to the scene's bounds (see the module docstring).
    Returns the Camera used, so that other pictures (a ``GifWriter``) can keep the same view.
    """
    from PIL import Image

    pv = _import_pyvista()
    if not isinstance(frame, Frame3D):
        raise TypeError(f"frame must be a Frame3D, got {type(frame).__name__}")
    window_size = _check_window(window_size)
    if camera is None:
        camera = _fit_camera(_scene_points(frame), window_size, _PNG_PAD)
    plotter = _new_plotter(pv, window_size)
    try:
        _draw(pv, plotter, frame, _clims(_scalar_groups(frame), None), camera)
        img = _screenshot(plotter)
    finally:
        plotter.close()
    path = Path(path)
    with atomic_output(path) as tmp:
        Image.fromarray(img).save(tmp, format="PNG")
    return camera


# ---- GIF ------------------------------------------------------------------------------------
