"""A scene run live in a PyVista window: it steps as fast as it can, one instrument (an
obstacle) follows the keys or the mouse, and the window shows the instrument's force and the
real-time factor (simulated seconds per wall-clock second). ``tissuesim play SCENE``.

Keys: arrows move the instrument in x and y, Page Up / Page Down (or i / k) in z, by
``key_step`` (m) per press; m switches mouse-following on and off (the instrument then moves
in the screen's plane with the mouse, ``mouse_scale`` m per pixel); q closes the window.
Each frame drives the instrument to its new place (``Simulation.drive_obstacle``), takes one
step (with a wall-clock budget when given: an early stop is shown as such, and is never an
intersection) and redraws. Off-screen (tests, headless machines) the same session runs a
number of frames, the instrument following a recorded device path (``io/device_path.py``) or
else the scene's own motion of it, and can save each frame as a PNG. Contact runs in the
predicted "interactive" mode (``time/contact_step.py``) unless the scene sets a mode; the
heads-up display and ``report()`` give the instrument's force and the real-time factor.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from tissuesim.errors import InputError

__all__ = ["LiveSession", "KEY_DIRECTIONS"]

KEY_DIRECTIONS = {
    "Left": (-1.0, 0.0, 0.0),
    "Right": (1.0, 0.0, 0.0),
    "Up": (0.0, 1.0, 0.0),
    "Down": (0.0, -1.0, 0.0),
    "Prior": (0.0, 0.0, 1.0),
    "Next": (0.0, 0.0, -1.0),
    "i": (0.0, 0.0, 1.0),
    "k": (0.0, 0.0, -1.0),
}


class LiveSession:
    """``sim``: a Simulation with contact and at least one obstacle; ``obstacle``: the name
    of the one to drive (default the first); ``budget_s``: each step's wall-clock budget (None:
    to convergence); ``path``: a DevicePath the instrument follows (``io/device_path.py``;
    default off screen: the scene's own motion of the instrument; in a window: the keys)."""

    def __init__(
        self,
        sim,
        obstacle: str | None = None,
        *,
        key_step: float | None = None,
        mouse_scale: float | None = None,
        budget_s: float | None = None,
        off_screen: bool = False,
        window_size: tuple[int, int] = (1024, 768),
        path=None,
    ) -> None:
        from tissuesim.render.pyvista3d import _import_pyvista

        self.sim = sim
        names = [ob.name for ob in sim.obstacles]
        if not names:
            raise InputError("play needs a scene with an obstacle (an instrument) to drive")
        if obstacle is None:
            obstacle = names[0]
        if obstacle not in names:
            raise InputError(f"play: no obstacle {obstacle!r} (obstacles: {', '.join(names)})")
        self.name = obstacle
        if sim.contact is not None and sim.contact.mode == "auto":
            sim.contact = replace(sim.contact, mode="interactive")
            sim._changed()
        sim.build()
        size = sim.system.length_scale
        self.key_step = float(key_step) if key_step is not None else 0.01 * size
        self.mouse_scale = float(mouse_scale) if mouse_scale is not None else 2e-4 * size
        self.budget_s = budget_s
        ob = self._obstacle()
        self.offset = (
            np.zeros(3) if ob.translation is None else np.asarray(ob.translation(sim.time), float)
        )
        self.path = path
        # the scene's own motion of the instrument, followed off screen without a path
        self.scene_motion = ob.translation
        self.off_screen = off_screen
        self.factors: list[float] = []  # each frame's real-time factor
        self.outcomes: list[str] = []  # each frame's contact prediction outcome
        self.mouse = False
        self._last_mouse: tuple[int, int] | None = None
        self.frames = 0
        self.last_force = np.zeros(3)
        self.real_time_factor = 0.0
        self.early_stops = 0
        pv = _import_pyvista()
        pv.OFF_SCREEN = off_screen
        self.pv = pv
        self.plotter = pv.Plotter(off_screen=off_screen, window_size=window_size)
        self.plotter.set_background("white")
        self._surfaces = {}
        self._add_actors()
        self.text = self.plotter.add_text(self.status(), position="upper_left", font_size=11)
        self.plotter.add_axes(xlabel="x (m)", ylabel="y (m)", zlabel="z (m)", color="black")
        self.plotter.view_isometric()
        self.plotter.reset_camera()

    # -- the picture -----------------------------------------------------------------------
    def _obstacle(self):
        return next(ob for ob in self.sim.obstacles if ob.name == self.name)

    def _add_actors(self) -> None:
        from tissuesim.mesh.queries.boundary import boundary_facets

        pv = self.pv
        for name, body in self.sim.bodies.items():
            if body.kind != "fem":
                continue
            tri = boundary_facets(body.mesh.simplices)
            if tri.shape[1] != 3:
                raise InputError("play shows 3D scenes (a 2D body has no surface to draw)")
            faces = np.column_stack([np.full(len(tri), 3), tri]).ravel()
            poly = pv.PolyData(self._positions(name).copy(), faces)
            self.plotter.add_mesh(poly, color="#d98c8c", smooth_shading=True, name=name)
            self._surfaces[name] = poly
        for ob in self.sim.obstacles:
            tri = ob.triangles
            faces = np.column_stack([np.full(len(tri), 3), tri]).ravel()
            poly = pv.PolyData(ob.positions(self.sim.time).copy(), faces)
            colour = "#4a6fa5" if ob.name == self.name else "#b0b0b0"
            self.plotter.add_mesh(poly, color=colour, opacity=0.9, name=f"obstacle {ob.name}")
            self._surfaces[f"obstacle {ob.name}"] = (poly, ob.name)

    def _positions(self, name: str) -> np.ndarray:
        body, x, _ = self.sim.body_state(name)
        return x.reshape(-1, body.mesh.dim)[: body.mesh.n_points]

    def _update_actors(self) -> None:
        for key, poly in self._surfaces.items():
            if isinstance(poly, tuple):
                poly, ob_name = poly
                ob = next(o for o in self.sim.obstacles if o.name == ob_name)
                contact = self.sim.system.contact
                points = ob.positions(self.sim.time)
                if contact is not None and contact.obstacle_state is not None:
                    rows = contact.slices[ob_name][0]
                    V = contact.obstacle_state.reshape(-1, 3)
                    points = V[rows.start - contact.n_deformable : rows.stop - contact.n_deformable]
                poly.points = points
            else:
                poly.points = self._positions(key)

    def status(self) -> str:
        f = self.last_force
        early = f", {self.early_stops} early stops" if self.early_stops else ""
        return (
            f"t = {self.sim.time:.3f} s   frame {self.frames}{early}\n"
            f"{self.name} force: |F| = {np.linalg.norm(f):.4f} N  "
            f"({f[0]:+.4f}, {f[1]:+.4f}, {f[2]:+.4f}) N\n"
            f"real-time factor {self.real_time_factor:.3g} (simulated s per wall s)\n"
            "arrows: x / y, PgUp / PgDn: z, m: mouse, q: quit"
        )

    # -- input ---------------------------------------------------------------------------
    def press(self, key: str) -> None:
        """A key press (the window's key events call this)."""
        if key in KEY_DIRECTIONS:
            self.offset = self.offset + self.key_step * np.asarray(KEY_DIRECTIONS[key])
        elif key == "m":
            self.mouse = not self.mouse
            self._last_mouse = None

    def mouse_move(self, x: int, y: int) -> None:
        """The mouse at pixel (x, y): with mouse-following on, the instrument moves by the
        pixel motion since the last event, in the plane of the screen."""
        if not self.mouse:
            return
        if self._last_mouse is not None:
            dx, dy = x - self._last_mouse[0], y - self._last_mouse[1]
            camera = self.plotter.camera
            up = np.asarray(camera.up, float)
            view = np.asarray(camera.focal_point, float) - np.asarray(camera.position, float)
            right = np.cross(view, up)
            right /= np.linalg.norm(right) or 1.0
            up /= np.linalg.norm(up) or 1.0
            self.offset = self.offset + self.mouse_scale * (dx * right + dy * up)
        self._last_mouse = (x, y)

    # -- stepping ------------------------------------------------------------------------
    def _commanded(self) -> None:
        """The instrument's place at the next step's end: the device path's, else off screen
        the scene's motion's, else where the keys and mouse put it."""
        t = self.sim.time + self.sim.time_step
        if self.path is not None:
            self.offset = self.path.translation(t)
        elif self.off_screen and self.scene_motion is not None:
            self.offset = np.asarray(self.scene_motion(t), dtype=float)

    def advance(self):
        """Drive the instrument to its commanded place, take one step, redraw; the record."""
        sim = self.sim
        self._commanded()
        rotation = None if self.path is None else self.path.rotation(sim.time + sim.time_step)
        sim.drive_obstacle(self.name, translation=self.offset, rotation=rotation)
        start = time.perf_counter()
        record = sim.step(budget_s=self.budget_s)
        wall = time.perf_counter() - start
        self.frames += 1
        self.real_time_factor = sim.time_step / max(wall, 1e-9)
        self.factors.append(self.real_time_factor)
        report = None if sim.system.contact is None else sim.system.contact.prediction_report
        self.outcomes.append("" if report is None else str(report.get("outcome", "")))
        self.last_force = np.asarray(record.extra["forces"].get(self.name, np.zeros(3)), float)
        self.early_stops += bool(record.extra.get("early_stop"))
        self._update_actors()
        self.text.SetText(2, self.status())  # 2: vtkCornerAnnotation's upper left
        return record

    def report(self) -> dict:
        """What a run of the session did: frames, the instrument and its last force (N), the
        real-time factor (the median of the frames', and the last, 3 significant digits), the
        early stops and the frames whose contact prediction was certified."""
        predicted = [o for o in self.outcomes if o]
        return {
            "frames": self.frames,
            "obstacle": self.name,
            "force_N": [round(float(v), 6) for v in self.last_force],
            "real_time_factor": float(f"{statistics.median(self.factors):.3g}")
            if self.factors
            else 0.0,
            "real_time_factor_last": float(f"{self.real_time_factor:.3g}"),
            "early_stops": self.early_stops,
            "contact_mode": None if self.sim.contact is None else self.sim.contact.mode,
            "certified_frames": sum(o == "certified" for o in predicted),
            "fallback_frames": sum(o.startswith("fell back") for o in predicted),
        }

    def run_off_screen(self, frames: int, pictures: Path | None = None) -> list:
        """``frames`` frames without a window; each saved as PNG in ``pictures`` if given."""
        records = []
        if pictures is not None:
            pictures.mkdir(parents=True, exist_ok=True)
        for k in range(frames):
            records.append(self.advance())
            self.plotter.render()
            if pictures is not None:
                self.plotter.screenshot(str(pictures / f"frame_{k:04d}.png"))
        return records

    def run_window(self, frames: int | None = None) -> None:
        """The interactive window until it is closed (or ``frames`` frames)."""
        plotter = self.plotter
        for key in [*KEY_DIRECTIONS, "m"]:
            plotter.add_key_event(key, lambda key=key: self.press(key))

        def moved(interactor, _event) -> None:
            x, y = interactor.GetEventPosition()
            self.mouse_move(int(x), int(y))

        plotter.show(interactive_update=True, auto_close=False)
        plotter.iren.add_observer("MouseMoveEvent", moved)
        while not getattr(plotter, "_closed", False) and (frames is None or self.frames < frames):
            self.advance()
            plotter.update()
            if plotter.render_window is None:
                break
        plotter.close()
