"""Pictures of a run, one renderer for every scene: ``final.png`` and ``run.gif``.

2D scenes (FEM bodies in the plane) are drawn with matplotlib (``plot2d``); 3D scenes off-screen
with PyVista (``pyvista3d``): FEM bodies as their boundary surfaces, frame bodies as their
embedded surface (or their integration points), the tissue as points, cuts in red. Without
PyVista, a 3D scene of one FEM or one frame body falls back to matplotlib and the summary says
so; other 3D scenes are not drawn. A FEM body carrying visual surfaces
(``Simulation.add_visual_surface``) is drawn as them instead of its coarse surface, coloured
by its vertex values carried the same way. A cut of the tissue is a translucent red sheet
while its blade sweeps, and its outline only once every cut has ended (the sheet hid the
organs under it for the rest of the run).

Every picture is coloured by one field, chosen by ``field``: ``J``, ``von_mises`` (Pa),
``displacement`` (its magnitude, m) or ``green_strain`` (the largest principal Green strain),
with a labelled colour bar: final.png on its own frame's range (a torn strip's relaxed last
frame was uniformly dark on the range of the run's peak), run.gif on one range for the run, so
its frames compare (``_range``: J spans 1, the others their minimum or 0 to their 99th
percentile); the title gives the time in
seconds (and the first grasper's force). A GIF holds at most ``MAX_GIF_FRAMES`` (2D) frames,
or in 3D as many as the simulation's own wall time pays for at ``SECONDS_PER_3D_FRAME`` (6 to
``MAX_GIF_FRAMES_3D``), evenly subsampled, so drawing costs about what the simulation cost
(measured in docs/performance.md; PyVista's fixed cost, about 2 s, remains).

A frame (what ``io/series/bodies.py`` returns per written step) is
(time, {body name: data}, cut triangles (m, 3, 3), title suffix).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.render.overlays import (
    cut_outline,
    cutting_at,
    polylines_2d,
    visual_layers,
    visuals_of,
)

__all__ = ["FIELDS", "render_run", "field_label", "MAX_GIF_FRAMES"]

FIELDS = {
    "J": "J (-)",
    "von_mises": "von Mises stress (Pa)",
    "displacement": "|u| (m)",
    "green_strain": "largest principal Green strain (-)",
}
MAX_GIF_FRAMES = 40  # 2D (matplotlib, blitted: about 0.03 s a frame)
MAX_GIF_FRAMES_3D = 20  # 3D (PyVista: about 0.15 s a frame at GIF_WINDOW)
MIN_GIF_FRAMES_3D = 6
SECONDS_PER_3D_FRAME = 0.15  # a 3D GIF gets about as many frames as the run's time allows
GIF_WINDOW = (640, 480)
_ORGAN_COLOURS = ("#c8745a", "#d9b35b", "#8fb0c9", "#a3c48d", "#b89ad0")


def field_label(field: str) -> str:
    if not isinstance(field, str) or field not in FIELDS:
        from tissuesim.validate import short

        raise InputError(f"render field must be one of {list(FIELDS)}, not {short(field)}")
    return FIELDS[field]


def _values(data: dict[str, Any], field: str, where: str) -> np.ndarray:
    """The field per cell (FEM, where="cells") or per point (frames, tissue)."""
    if field == "displacement":
        return np.linalg.norm(data["displacement"], axis=1)
    source = data[where]
    if field == "green_strain":
        if "max_principal_strain" in data:
            return data["max_principal_strain"]
        return np.linalg.eigvalsh(source["green_strain"])[:, -1]
    return np.asarray(source[field], dtype=float)


def _subsample(n: int, most: int) -> list[int]:
    if n <= most:
        return list(range(n))
    return sorted(set(np.linspace(0, n - 1, most).round().astype(int).tolist()))


def gif_frames_3d(simulated_seconds: float) -> int:
    """Frames of a 3D GIF: about what the simulation's own wall time pays for, 6 to 20."""
    budget = int(simulated_seconds / SECONDS_PER_3D_FRAME)
    return max(MIN_GIF_FRAMES_3D, min(MAX_GIF_FRAMES_3D, budget))


def render_run(sim, frames: list, directory: Path, field: str = "J") -> str:
    """Draw final.png (and run.gif for several frames) into ``directory``; returns what was
    drawn, for the summary."""
    label = field_label(field)
    bodies = [sim.bodies[n] for n in frames[-1][1] if n in sim.bodies]
    if all(b.kind == "fem" and b.dim == 2 for b in bodies):
        return _render_2d(bodies, frames, directory, field, label, visuals_of(sim))
    try:
        import pyvista  # noqa: F401
    except ImportError:
        if len(bodies) == 1 and bodies[0].kind in ("fem", "frames"):
            print(
                "tissuesim: PyVista is not installed: drawing with matplotlib "
                "(pip install 'tissuesim[pyvista]' for better 3D pictures)",
                file=sys.stderr,
            )
            return _render_matplotlib_3d(bodies[0], frames, directory, field, label)
        return (
            "skipped: 3D pictures of several bodies need PyVista (pip install 'tissuesim[pyvista]')"
        )
    return _render_pyvista(sim, bodies, frames, directory, field, label)


def _on_final_meshes(bodies, frames) -> list:
    """The frames drawn on the bodies' meshes as they are now: a body cut during the run had
    other meshes before (matplotlib draws one mesh for every frame; PyVista each its own)."""

    def current(data) -> bool:
        return all(data[b.name].get("mesh", b.mesh) is b.mesh for b in bodies if b.kind == "fem")

    return [f for f in frames if current(f[1])] or frames[-1:]


# -- 2D: matplotlib ---------------------------------------------------------------------------
def _merged_mesh(bodies):
    from tissuesim.mesh.mesh import Mesh

    points, cells, offset = [], [], 0
    for b in bodies:
        points.append(b.mesh.points)
        cells.append(b.mesh.simplices + offset)
        offset += b.mesh.n_points
    return Mesh(np.concatenate(points), np.concatenate(cells), source="scene")


def _cell_values_2d(bodies, data, field) -> np.ndarray:
    out = []
    for b in bodies:
        d = data[b.name]
        if field == "displacement":  # per triangle: the mean of its vertices' |u|
            out.append(np.linalg.norm(d["displacement"], axis=1)[b.mesh.simplices].mean(axis=1))
        else:
            out.append(b.mesh.per_simplex(_values(d, field, "cells")))
    return np.concatenate(out)


def _render_2d(bodies, frames, directory, field, label, visuals=None) -> str:
    from tissuesim.render.plot2d import render_frame_png, render_gif

    frames = _on_final_meshes(bodies, frames)
    lines = [polylines_2d(bodies, data, visuals or {}) for _, data, _, _ in frames]
    if any(s is None for s in lines):
        lines = None
    mesh = _merged_mesh(bodies)
    series = [
        (
            t,
            np.concatenate([data[b.name]["positions"] for b in bodies]),
            _cell_values_2d(bodies, data, field),
        )
        for t, data, _, _ in frames
    ]
    lo, hi = _range([v for _, _, v in series], field)
    t, x, v = series[-1]
    title = f"t = {t:.4g} s{frames[-1][3]}"
    last = _range([v], field)  # final.png: its own frame's range
    render_frame_png(
        mesh,
        x,
        v,
        directory / "final.png",
        title=title,
        label=label,
        vmin=last[0],
        vmax=last[1],
        lines=None if lines is None else lines[-1],
    )
    if len(series) > 1:
        picked = _subsample(len(series), MAX_GIF_FRAMES)
        render_gif(
            mesh,
            [series[i] for i in picked],
            directory / "run.gif",
            label=label,
            vmin=lo,
            vmax=hi,
            max_frames=MAX_GIF_FRAMES,
            lines=None if lines is None else [lines[i] for i in picked],
        )
    return f"final.png, run.gif (matplotlib, coloured by {field})"


def _range(values: list[np.ndarray], field: str) -> tuple[float, float]:
    """A colour range for these values (a frame's, or a run's): J spans 1; others the 99th
    percentile (a few points at the lips of a cut would wash out the rest)."""
    v = np.concatenate([np.asarray(a, dtype=float).ravel() for a in values])
    v = v[np.isfinite(v)]
    if not v.size:
        return (0.0, 1.0)
    if field == "J":
        return (min(float(v.min()), 0.999), max(float(v.max()), 1.001))
    lo = float(min(v.min(), 0.0))
    hi = float(np.percentile(v, 99)) if v.size > 100 else float(v.max())
    return (lo, max(hi, lo + 1e-12))


# -- 3D: PyVista ------------------------------------------------------------------------------
def _vertex_values(b, cell_values: np.ndarray, d: dict | None = None) -> np.ndarray:
    """Cell values averaged to the vertices (volume-weighted), on the frame's mesh (``d``)."""
    mesh = b.mesh if d is None else d.get("mesh", b.mesh)
    w = b.model.kinematics.cell_weights if d is None else d.get("weights", None)
    w = b.model.kinematics.cell_weights if w is None else w
    n, k = mesh.n_points, mesh.cells.shape[1]
    num = np.bincount(mesh.cells.ravel(), np.repeat(w * cell_values, k), n)
    den = np.bincount(mesh.cells.ravel(), np.repeat(w, k), n)
    return num / np.where(den > 0, den, 1.0)


def _drawn_surface(mesh, cache: dict):
    """(W or None, triangles) of a FEM mesh's surface to draw: its boundary facets, or for a
    cut mesh its embedded surface with the cut faces exactly on the blade's plane (points
    V = W x); one per mesh, cached."""
    key = id(mesh)
    if key not in cache:
        if mesh.cell_levels is not None and mesh.dim == 3:
            from tissuesim.contact.cut.surface import cut_surface

            cache[key] = (mesh, cut_surface(mesh, 0.0))
        else:
            from tissuesim.mesh.queries.boundary import boundary_facets

            cache[key] = (mesh, (None, boundary_facets(mesh.simplices)))
    return cache[key][1]


def _frame3d(bodies, frame, field, label, clim, surfaces, visuals=None, cutting=True):
    """One picture of a run (``Frame3D``). visuals: body name -> its visual surfaces, drawn
    instead of its coarse surface. cutting: whether a blade is cutting at the frame's time;
    after every cut has ended the swept surface is drawn as its outline only, so it hides
    nothing (``Frame3D.cut_outlines``)."""
    from tissuesim.render.pyvista3d import Frame3D, PointLayer, SurfaceLayer

    t, data, cut, suffix = frame
    layers, points = [], []

    def bar(b) -> str:  # one colour bar per body when there are several
        return label if len(bodies) == 1 else b.name

    for name, (x, tri) in data.get("__obstacles__", {}).items():  # io/run_output.py OBSTACLES
        layers.append(SurfaceLayer(name, x, tri, color="silver", opacity=0.45, context=True))
    for j, b in enumerate(bodies):
        d = data[b.name]
        if b.kind == "fem":
            if field == "displacement":
                vals = np.linalg.norm(d["displacement"], axis=1)
            else:
                vals = _vertex_values(b, _values(d, field, "cells"), d)
            fine = visual_layers(
                b, d, None if field == "displacement" else vals, visuals or {}, bar(b), clim[b.name]
            )
            if fine:  # the fine surfaces instead of the coarse mesh's
                layers += fine
                continue
            W, tri = _drawn_surface(d.get("mesh", b.mesh), surfaces)
            x = d["positions"]
            if W is not None:
                x, vals = W @ x, W @ vals
            layers.append(
                SurfaceLayer(
                    b.name,
                    x,
                    tri,
                    scalars=vals,
                    scalar_name=bar(b),
                    clim=clim[b.name],
                )
            )
        elif b.kind == "frames" and d["surface"] is not None and field == "displacement":
            vals = np.linalg.norm(d["surface"] - b.surface.points, axis=1)
            layers.append(
                SurfaceLayer(
                    b.name,
                    d["surface"],
                    b.surface.triangles,
                    scalars=vals,
                    scalar_name=bar(b),
                    clim=clim[b.name],
                )
            )
        else:
            if b.kind == "frames" and d["surface"] is not None:
                layers.append(
                    SurfaceLayer(
                        b.name,
                        d["surface"],
                        b.surface.triangles,
                        color=_ORGAN_COLOURS[j % len(_ORGAN_COLOURS)],
                        opacity=0.35,
                    )
                )
            alive = d.get("alive", np.ones(len(d["positions"]), dtype=bool))
            points.append(
                PointLayer(
                    b.name if b.kind == "tissue" else f"{b.name} points",
                    d["positions"][alive],
                    _values(d, field, "points")[alive],
                    scalar_name=bar(b),
                    clim=clim[b.name],
                )
            )
    heading = label if len(bodies) > 1 else ""  # the bars are titled by their bodies then
    sheets = [cut] if len(cut) and cutting else []
    outlines = [cut_outline(cut)] if len(cut) and not cutting else []
    return Frame3D(layers, points, sheets, f"t = {t:.4g} s{suffix}", heading, outlines)


def _field_values(bodies, data, field) -> list[np.ndarray]:
    out = []
    for b in bodies:
        d = data[b.name]
        where = "cells" if b.kind == "fem" else "points"
        v = _values(d, field, where)
        out.append(v[d["alive"]] if "alive" in d else v)
    return out


def _render_pyvista(sim, bodies, frames, directory, field, label) -> str:
    from tissuesim.render.gif3d import GifWriter
    from tissuesim.render.pyvista3d import render_frame_png

    surfaces: dict = {}  # drawn surfaces by mesh (a body that is cut changes its mesh)
    wall = sum(r.wall_time_s for r in sim.history)
    picked = [frames[i] for i in _subsample(len(frames), gif_frames_3d(wall))]
    # each body its own colour range and bar: a stiff organ's small strains are not washed
    # out by a soft one's (or the tissue's) large ones
    clim = {
        b.name: _range([v for f in picked for v in _field_values([b], f[1], field)], field)
        for b in bodies
    }
    last = {b.name: _range(_field_values([b], frames[-1][1], field), field) for b in bodies}
    visuals, cutting = visuals_of(sim), cutting_at(sim)

    def draw(frame, ranges):
        return _frame3d(bodies, frame, field, label, ranges, surfaces, visuals, cutting(frame[0]))

    camera = render_frame_png(directory / "final.png", draw(frames[-1], last))  # its own range
    if len(frames) > 1:
        # the last frame spans the scene (a retracted organ is farthest away)
        gif = GifWriter(directory / "run.gif", camera=camera, window_size=GIF_WINDOW)
        for frame in picked:
            gif.add(draw(frame, clim))
        gif.close()
    return f"final.png, run.gif (PyVista, coloured by {field})"


def _render_matplotlib_3d(b, frames, directory, field, label) -> str:
    frames = _on_final_meshes([b], frames)
    picked = [frames[i] for i in _subsample(len(frames), MAX_GIF_FRAMES_3D)]
    if b.kind == "fem":
        from tissuesim.render.plot3d import render_frame_png_3d, render_gif_3d

        def vals(d):
            if field == "displacement":
                return np.linalg.norm(d["displacement"], axis=1)[b.mesh.simplices].mean(axis=1)
            return b.mesh.per_simplex(_values(d, field, "cells"))

        series = [(t, data[b.name]["positions"], vals(data[b.name])) for t, data, _, _ in picked]
        lo, hi = _range([v for _, _, v in series], field)
        t, x, v = series[-1]
        last = _range([v], field)  # final.png: its own frame's range
        render_frame_png_3d(
            b.mesh.linear_view,
            x,
            v,
            directory / "final.png",
            title=f"t = {t:.4g} s",
            label=label,
            vmin=last[0],
            vmax=last[1],
        )
        if len(series) > 1:
            render_gif_3d(
                b.mesh.linear_view, series, directory / "run.gif", label=label, vmin=lo, vmax=hi
            )
        return f"final.png, run.gif (matplotlib, coloured by {field}; PyVista not installed)"
    from tissuesim.render.points3d import render_points_gif, render_points_png

    surface = b.surface
    series = []
    for t, data, _, _ in picked:
        d = data[b.name]
        if surface is not None:
            x = d["surface"]
            series.append((t, x, np.linalg.norm(x - surface.points, axis=1), d["frames"]))
        else:
            series.append(
                (t, d["positions"], np.linalg.norm(d["displacement"], axis=1), d["frames"])
            )
    drawing = {
        "triangles": None if surface is None else surface.triangles,
        "rest": b.model.samples.points if surface is None else surface.points,
        "label": FIELDS["displacement"],
        "vmin": 0.0,
        "vmax": max(max(float(np.nanmax(f[2], initial=0.0)) for f in series), 1e-12),
    }
    t, x, mag, origins = series[-1]
    final = {**drawing, "vmax": max(float(np.nanmax(mag, initial=0.0)), 1e-12)}  # its own range
    render_points_png(
        x, mag, directory / "final.png", markers=origins, title=f"t = {t:.4g} s", **final
    )
    if len(series) > 1:
        render_points_gif(series, directory / "run.gif", **drawing)
    return "final.png, run.gif (matplotlib, coloured by displacement; PyVista not installed)"
