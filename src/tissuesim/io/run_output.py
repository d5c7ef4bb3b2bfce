"""Running a Simulation with output: VTU series + PVD, summary.json, progress bar, pictures.

summary.json is rewritten atomically after every step, so a run stopped at any point (a crash,
a ConvergenceError, Ctrl-C) leaves a valid summary whose "status" says how it ended, and every
frame listed in the .pvd exists and is complete.

``RunOutput`` owns the run loop, the summary and the status handling; what depends on the kind
of body is in four hooks a subclass overrides (``frames.output.FrameRunOutput`` does):
``_describe_body`` (once, stored under the summary key ``body_key``), ``_open_series``,
``_write_frame`` (series and in-memory frames for pictures) and ``_render``.
"""

from __future__ import annotations

import os
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import ConvergenceError
from tissuesim.io.atomic import write_json_atomic
from tissuesim.mesh.io import describe_mesh

__all__ = ["RunOutput"]


class RunOutput:
    """Runs a Simulation's steps and writes its output into ``directory`` (None: nothing)."""

    #: summary.json key of ``_describe_body()``
    body_key = "mesh"

    def __init__(
        self,
        sim: Any,
        directory: str | os.PathLike[str] | None,
        *,
        every: int = 1,
        render: bool = True,
        metadata: dict | None = None,
    ) -> None:
        if every < 1:
            raise ValueError(f"every must be >= 1, not {every}")
        self.sim = sim
        self.directory = None if directory is None else Path(directory)
        self.every = every
        self.render = render
        self.metadata = dict(metadata or {})
        self.frames: list[tuple[Any, ...]] = []  # what _render draws, one entry per frame
        self.series = None
        self.status = "running"
        # once per run: it costs about a second at 1e5 elements, and the summary is
        # rewritten after every step
        self.body_description = self._describe_body()
        self.error = None

    @property
    def mesh_description(self) -> dict:
        """The FEM name of ``body_description``, kept for existing callers."""
        return self.body_description

    # -- hooks: what depends on the kind of body ------------------------------------------
    def _describe_body(self) -> dict:
        return describe_mesh(self.sim.mesh)

    def _open_series(self) -> None:
        from tissuesim.io.vtu_series import VTUSeriesWriter

        self.series = VTUSeriesWriter(self.directory, self.sim.mesh)

    def _write_frame(self) -> None:
        sim = self.sim
        fields = sim.cell_fields()
        if self.series is not None:
            self.series.write(
                sim.time,
                sim.positions,
                point_data={"displacement": sim.displacement, "velocity": sim.velocity},
                cell_data={"J": fields["J"], "energy_density": fields["energy_density"]},
            )
        self.frames.append((sim.time, sim.positions.copy(), fields["J"].copy()))

    def _summary(self) -> dict:
        from tissuesim import __version__

        steps = [asdict(r) for r in self.sim.history]
        iters = [r.newton_iterations for r in self.sim.history]
        return {
            "tissuesim_version": __version__,
            "status": self.status,
            "error": self.error,
            **self.metadata,
            self.body_key: self.body_description,
            "simulation": self.sim.describe(),
            "totals": {
                "steps": len(steps),
                "newton_iterations": int(sum(iters)),
                "max_newton_iterations_per_step": int(max(iters, default=0)),
                "min_J": float(min((r.min_J for r in self.sim.history), default=np.nan)),
                "wall_time_s": float(sum(r.wall_time_s for r in self.sim.history)),
            },
            "steps": steps,
        }

    def _write_summary(self) -> None:
        if self.directory is not None:
            write_json_atomic(self.directory / "summary.json", self._summary())

    def run(self, steps: int, progress: bool = True) -> list:
        """Step ``steps`` times, writing every ``every``-th frame, the last, and the summary;
        return the simulation's history. The summary's status records how the run ended."""
        from tqdm import tqdm

        if steps < 0:
            raise ValueError(f"steps must be >= 0, not {steps}")
        if self.directory is not None:
            self.directory.mkdir(parents=True, exist_ok=True)
            self._open_series()
        self._write_frame()
        bar = tqdm(total=steps, disable=not progress, file=sys.stderr, unit="step")
        try:
            for k in range(steps):
                record = self.sim.step()
                if (k + 1) % self.every == 0 or k + 1 == steps:
                    self._write_frame()
                self._write_summary()
                bar.set_postfix(
                    t=f"{record.time:.4g}",
                    newton=record.newton_iterations,
                    minJ=f"{record.min_J:.3g}",
                )
                bar.update(1)
            self.status = "completed"
        except ConvergenceError as exc:
            self.status, self.error = "failed", str(exc)
            raise
        except KeyboardInterrupt:
            self.status, self.error = "interrupted", "KeyboardInterrupt"
            raise
        except Exception as exc:  # any other crash: the summary must not still say "running"
            self.status, self.error = "failed", f"{type(exc).__name__}: {exc}"
            raise
        finally:
            bar.close()
            self._write_summary()
            if self.directory is not None and self.render and len(self.frames) > 0:
                self._render()
        return self.sim.history

    def _render(self) -> None:
        from tissuesim.render import render_animation, render_frame

        mesh = self.sim.mesh
        if mesh.dim == 3 and mesh.n_cells > 200_000:
            return  # matplotlib 3D is too slow there; use ParaView on the VTU series
        t, x, J = self.frames[-1]
        render_frame(mesh, x, J, self.directory / "final.png", title=f"t = {t:.4g} s", label="J")
        if len(self.frames) > 1:
            lo = min(float(f[2].min()) for f in self.frames)
            hi = max(float(f[2].max()) for f in self.frames)
            render_animation(
                mesh,
                self.frames,
                self.directory / "run.gif",
                label="J",
                vmin=min(lo, 0.999),
                vmax=max(hi, 1.001),
            )
