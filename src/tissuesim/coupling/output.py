"""Running a CoupledSimulation with output: VTU series per body, the cut, summary.json with the
forces per step, and 3D pictures (PyVista, off-screen).

Per written frame, in the output directory:

- ``<organ>`` (one series per organ): its tetrahedra at the current positions, with the
  displacement and the cells' J.
- ``tissue_points``: every tissue integration point as a vertex cell, with ``alive`` (0 once
  cut away or torn; such points stay where they were last), the largest principal Green strain,
  J and the displacement: threshold on ``alive`` in ParaView to see the parted tissue.
- ``cut``: the surface the blades swept, as cut, in world coordinates (frames from the first
  cut on).

summary.json: as for other runs, plus "forces" (time and force vector per grasper and support,
one entry per step) and each step's topology events. final.png and run.gif show the organs'
surfaces, the tissue points coloured by strain and the cut in red (``render/pyvista3d.py``);
without PyVista installed the run still writes everything else and says so in the summary.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from tissuesim.io.run_output import RunOutput
from tissuesim.io.vtu_series import VTUSeriesWriter, remove_series
from tissuesim.mesh.boundary import boundary_facets

if TYPE_CHECKING:
    from tissuesim.coupling.simulation import CoupledSimulation

__all__ = ["CoupledRunOutput"]

_ORGAN_COLOURS = ("#c8745a", "#d9b35b", "#8fb0c9", "#a3c48d", "#b89ad0")


class CoupledRunOutput(RunOutput):
    """Runs a CoupledSimulation's steps and writes its output into ``directory``."""

    body_key = "bodies"

    def __init__(
        self,
        sim: CoupledSimulation,
        directory: str | os.PathLike[str] | None,
        *,
        every: int = 1,
        render: bool = True,
        metadata: dict | None = None,
    ) -> None:
        sim.build()
        super().__init__(sim, directory, every=every, render=render, metadata=metadata)
        self.organ_series: list[VTUSeriesWriter] = []
        self.point_series: VTUSeriesWriter | None = None
        self.cut_series: VTUSeriesWriter | None = None
        self.surfaces = [boundary_facets(m.mesh.cells) for m in sim.system.organs]
        samples = sim.tissue_samples
        self._last_points = None if samples is None else samples.points.copy()
        self.pictures: str = "not rendered"

    def _describe_body(self) -> dict[str, Any]:
        return self.sim.describe()

    def _open_series(self) -> None:
        sim = self.sim
        for name, model in zip(sim.organ_names, sim.system.organs, strict=True):
            self.organ_series.append(VTUSeriesWriter(self.directory, model.mesh, name))
        if sim.tissue_samples is not None:
            n = sim.tissue_samples.n
            ids = np.arange(n, dtype=np.int64)[:, None]
            self.point_series = VTUSeriesWriter(
                self.directory, None, "tissue_points", cells=("vertex", ids), n_points=n
            )
        if sim.cuts:
            self.cut_series = VTUSeriesWriter(
                self.directory, None, "cut", cells=("triangle", np.zeros((1, 3), int)), n_points=3
            )
        else:
            remove_series(self.directory, "cut")
        self.series = self.organ_series[0]

    def _tissue_state(self):
        """All original tissue points: positions (dead ones where last seen), alive, strain."""
        sim = self.sim
        samples = sim.tissue_samples
        if samples is None:
            return None
        alive = sim.dissection.alive
        strain = np.zeros(samples.n)
        J = np.ones(samples.n)
        f = sim.tissue_fields()
        if f:
            self._last_points[f["ids"]] = f["positions"]
            strain[f["ids"]] = f["max_principal_strain"]
            J[f["ids"]] = f["J"]
        return self._last_points.copy(), alive.copy(), strain, J

    def _write_frame(self) -> None:
        sim = self.sim
        time = sim.time
        organs = []
        for j, model in enumerate(sim.system.organs):
            x = sim.system.organ_x(sim.state.x, j).reshape(-1, 3)
            if self.organ_series:
                J = model.elastic.jacobians(x.ravel())
                self.organ_series[j].write(
                    time,
                    x,
                    point_data={"displacement": x - model.mesh.points},
                    cell_data={"J": J},
                )
            organs.append(x.copy())
        tissue = self._tissue_state()
        if tissue is not None and self.point_series is not None:
            p, alive, strain, J = tissue
            self.point_series.write(
                time,
                p,
                point_data={
                    "alive": alive.astype(np.int8),
                    "max_principal_strain": strain,
                    "J": J,
                    "displacement": p - sim.tissue_samples.points,
                },
            )
        cut = sim.cut_surface
        if self.cut_series is not None and len(cut):
            self.cut_series.write(
                time,
                cut.reshape(-1, 3),
                cells=("triangle", np.arange(3 * len(cut)).reshape(-1, 3)),
            )
        graspers = [g.name for g in sim.graspers]
        force = None
        if graspers and sim.history:
            force = float(np.linalg.norm(sim.history[-1].extra["forces"][graspers[0]]))
        self.frames.append((time, organs, tissue, cut, force))

    def _summary(self) -> dict:
        out = super()._summary()
        out["forces"] = [{"time": r.time, **r.extra["forces"]} for r in self.sim.history]
        out["pictures"] = self.pictures
        return out

    def _frame3d(self, frame, clim):
        from tissuesim.render.pyvista3d import Frame3D, PointLayer, SurfaceLayer

        t, organs, tissue, cut, force = frame
        surfaces = [
            SurfaceLayer(name, x, tri, color=_ORGAN_COLOURS[j % len(_ORGAN_COLOURS)])
            for j, (name, x, tri) in enumerate(
                zip(self.sim.organ_names, organs, self.surfaces, strict=True)
            )
        ]
        points = []
        if tissue is not None:
            p, alive, strain, _ = tissue
            points.append(
                PointLayer(
                    "tissue",
                    p[alive],
                    strain[alive],
                    scalar_name="tissue strain",
                    cmap="viridis",
                    clim=clim,
                )
            )
        title = f"t = {t:.3g} s" + ("" if force is None else f"   grasper force {force:.3g} N")
        return Frame3D(surfaces, points, [cut] if len(cut) else [], title)

    def _render(self) -> None:
        try:
            from tissuesim.render.pyvista3d import GifWriter, render_frame_png

            strains = [f[2][2][f[2][1]] for f in self.frames if f[2] is not None]
            strains = np.concatenate(strains) if strains else np.zeros(0)
            # one colour range for the whole run; the 99th percentile, so that a few points at
            # the lips of a cut do not wash out the colours of the rest
            top = float(np.percentile(strains, 99)) if strains.size else 0.0
            clim = (0.0, max(top, 1e-6))
            camera = render_frame_png(
                self.directory / "final.png", self._frame3d(self.frames[-1], clim)
            )
            if len(self.frames) > 1:
                # the last frame spans the scene (the retracted organ is farthest away)
                gif = GifWriter(self.directory / "run.gif", camera=camera)
                for frame in self.frames:
                    gif.add(self._frame3d(frame, clim))
                gif.close()
            self.pictures = "final.png, run.gif (PyVista)"
        except ImportError as exc:
            self.pictures = f"skipped: {exc}"
        self._write_summary()
