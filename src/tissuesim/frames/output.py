"""Running a FrameSimulation with output: three VTU series, summary.json, progress bar, pictures.

The run loop, the crash-safe summary and its status are ``io.run_output.RunOutput``'s; only what
a meshless body writes and draws differs. Per written frame, in the output directory:

- ``integration_points``: vertex cells at the integration points' current positions, with the
  displacement from rest, J, energy_density, green_strain (3x3 flattened row-major), the rest
  volume and the mass each point carries: the fields the energy is integrated from.
- ``frames``: vertex cells at the frame origins, with the displacement from rest, the columns of
  each frame's rotation as vectors axis_x, axis_y, axis_z (glyphs in ParaView show how the
  frames turn) and the support radius.
- ``surface`` (when the simulation has an embedded surface): its triangles at the current
  positions with the displacement: what the body looks like.

summary.json holds "body" (counts, volume, mass) where FEM runs hold "mesh". final.png and
run.gif show the surface (or, without one, the integration points) coloured by |u| on one fixed
colour range, and the frame origins as black dots.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from tissuesim.io.run_output import RunOutput
from tissuesim.io.vtu_series import VTUSeriesWriter, remove_series

if TYPE_CHECKING:
    from tissuesim.frames.simulation import FrameSimulation

__all__ = ["FrameRunOutput"]

_MAX_RENDER_TRIANGLES = 200_000  # as for FEM: beyond this, matplotlib 3D is too slow


def _vertices(n: int) -> tuple[str, np.ndarray]:
    """One vertex cell per point, so ParaView shows a point cloud without a glyph filter."""
    return "vertex", np.arange(n, dtype=np.int64)[:, None]


class FrameRunOutput(RunOutput):
    """Runs a FrameSimulation's steps and writes its output into ``directory`` (None: nothing)."""

    body_key = "body"

    def __init__(
        self,
        sim: FrameSimulation,
        directory: str | os.PathLike[str] | None,
        *,
        every: int = 1,
        render: bool = True,
        metadata: dict | None = None,
    ) -> None:
        super().__init__(sim, directory, every=every, render=render, metadata=metadata)
        self.point_series: VTUSeriesWriter | None = None
        self.frame_series: VTUSeriesWriter | None = None
        self.surface_series: VTUSeriesWriter | None = None

    def _describe_body(self) -> dict[str, Any]:
        model, surface = self.sim.model, self.sim.surface
        return {
            "frames": int(model.n_frames),
            "integration_points": int(model.samples.n),
            "volume": float(model.samples.volume),
            "mass": float(model.masses.sum()),
            "surface_points": 0 if surface is None else int(len(surface.points)),
            "surface_triangles": 0 if surface is None else int(len(surface.triangles)),
        }

    def _open_series(self) -> None:
        sim = self.sim
        n_points, n_frames = sim.model.samples.n, sim.n_frames
        self.point_series = VTUSeriesWriter(
            self.directory, None, "integration_points", cells=_vertices(n_points), n_points=n_points
        )
        self.frame_series = VTUSeriesWriter(
            self.directory, None, "frames", cells=_vertices(n_frames), n_points=n_frames
        )
        if sim.surface is not None:
            self.surface_series = VTUSeriesWriter(
                self.directory,
                None,
                "surface",
                cells=("triangle", sim.surface.triangles),
                n_points=len(sim.surface.points),
            )
        else:  # a surface series left by an earlier run must not pass for this run's
            remove_series(self.directory, "surface")
        self.series = self.point_series

    def _write_frame(self) -> None:
        sim, model = self.sim, self.sim.model
        t = sim.time
        fields = sim.point_fields()
        x = fields["positions"]
        u = x - model.samples.points
        frames = sim.frame_positions
        surface = None if sim.surface is None else sim.positions("surface")
        if self.point_series is not None:
            self.point_series.write(
                t,
                x,
                point_data={
                    "displacement": u,
                    "J": fields["J"],
                    "energy_density": fields["energy_density"],
                    "green_strain": fields["green_strain"],
                    "volume": model.samples.volumes,
                    "mass": model.masses,
                },
            )
            R = sim.frame_rotations
            self.frame_series.write(
                t,
                frames,
                point_data={
                    "displacement": frames - sim.rest_frames,
                    "axis_x": R[:, :, 0],
                    "axis_y": R[:, :, 1],
                    "axis_z": R[:, :, 2],
                    "radius": model.shapes.radii,
                },
            )
        if surface is not None:
            du = surface - sim.surface.points
            if self.surface_series is not None:
                self.surface_series.write(t, surface, point_data={"displacement": du})
            self.frames.append((t, surface.copy(), np.linalg.norm(du, axis=1), frames))
        else:
            self.frames.append((t, x.copy(), np.linalg.norm(u, axis=1), frames))

    def _render(self) -> None:
        from tissuesim.render.points3d import render_points_gif, render_points_png

        surface = self.sim.surface
        if surface is not None and len(surface.triangles) > _MAX_RENDER_TRIANGLES:
            return  # use ParaView on the VTU series
        drawing = {
            "triangles": None if surface is None else surface.triangles,
            "rest": self.sim.model.samples.points if surface is None else surface.points,
            "label": "|u| (m)",
            "vmin": 0.0,  # one colour range for the PNG and the whole GIF
            "vmax": max(max(float(np.nanmax(f[2], initial=0.0)) for f in self.frames), 1e-12),
        }
        t, x, mag, frames = self.frames[-1]
        render_points_png(
            x, mag, self.directory / "final.png", markers=frames, title=f"t = {t:.4g} s", **drawing
        )
        if len(self.frames) > 1:
            render_points_gif(self.frames, self.directory / "run.gif", **drawing)
