"""The VTU series of one body, the same habits for every kind: points at their **rest**
positions with ``displacement`` (and ``velocity``) as point data, so ParaView's Warp By Vector
shows the deformed body, and the continuum fields of ``materials/measures.py`` (``J``,
``green_strain``, ``cauchy_stress``, ``von_mises``, ``energy_density``; tensors as 3 x 3) as cell
data of FEM elements or point data at integration points.

- FEM body ``<name>``: its triangles / tetrahedra.
- frame body ``<name>``: its integration points as vertex cells (with ``volume`` and ``mass``);
  ``<name>_frames``: the frame origins with the axes of each frame's rotation (``axis_x``,
  ``axis_y``, ``axis_z``) and support ``radius``; ``<name>_surface``: its embedded surface.
- tissue ``<name>_points``: every original integration point, with ``alive`` (0 once cut away or
  torn; such points keep their last displacement) and ``max_principal_strain``; threshold on
  ``alive`` to see the parted tissue.
- a visual surface a FEM body carries (``Simulation.add_visual_surface``), its own name
  (``<body>_visual`` by default): its triangles (lines in 2D) on their rest points with
  ``displacement`` and ``velocity`` (``VisualSeries``).

Each writer's ``write`` returns what the pictures need of that frame (``render/scene.py``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.io.series.vtu import VTUSeriesWriter, remove_series
from tissuesim.materials.measures import FIELD_NAMES

__all__ = ["series_for", "BodySeries", "VisualSeries", "series_names"]


def _vertices(n: int) -> tuple[str, np.ndarray]:
    """One vertex cell per point, so ParaView shows a point cloud without a glyph filter."""
    return "vertex", np.arange(n, dtype=np.int64)[:, None]


def _kept(keep: dict | None, name: str) -> list | None:
    return None if keep is None else keep.get(name)


def _fields(fields: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {k: fields[k] for k in FIELD_NAMES}


def series_names(name: str, kind: str) -> list[str]:
    """The series a body of ``kind`` named ``name`` writes (checked for name clashes)."""
    if kind == "fem":
        return [name]
    if kind == "frames":
        return [name, f"{name}_frames", f"{name}_surface"]
    return [f"{name}_points"]


class BodySeries:
    """Base: ``open(directory)`` once, then ``write(sim, time)`` per written frame. ``keep``
    (series name -> (time, file) of the frames so far): continue a resumed run's series."""

    def __init__(self, body) -> None:
        self.body = body
        self.writers: list[VTUSeriesWriter] = []

    def open(self, directory: Path, keep: dict | None = None) -> None:
        raise NotImplementedError

    def write(self, sim, t: float) -> dict[str, Any]:
        raise NotImplementedError


class FemSeries(BodySeries):
    def open(self, directory: Path, keep: dict | None = None) -> None:
        name = self.body.name
        self.writers = [VTUSeriesWriter(directory, self.body.mesh, name, keep=_kept(keep, name))]

    def write(self, sim, t: float) -> dict[str, Any]:
        b = self.body
        _, c, v = sim.body_state(b.name)
        rest = b.mesh.points
        x = c.reshape(rest.shape)
        u = x - rest
        fields = b.cell_fields(c)
        if self.writers:
            if self.writers[0].mesh is not b.mesh:  # cut since the last frame
                self.writers[0].set_mesh(b.mesh)
            cell_data = _fields(fields)
            if "region" in fields:  # a body of regions: colour by it in ParaView
                cell_data["region"] = np.asarray(fields["region"])
            if b.mesh.cell_fractions is not None:  # a cut body: the copies' part of their cell
                cell_data["material_fraction"] = np.asarray(b.mesh.cell_fractions)
            self.writers[0].write(
                t,
                rest,
                point_data={"displacement": u, "velocity": v.reshape(rest.shape)},
                cell_data=cell_data,
            )
        # the mesh and weights of this frame: a body cut later has other ones (the pictures)
        return {
            "kind": "fem",
            "positions": x.copy(),
            "cells": fields,
            "displacement": u,
            "mesh": b.mesh,
            "weights": b.model.kinematics.cell_weights,
        }


class FrameSeries(BodySeries):
    def open(self, directory: Path, keep: dict | None = None) -> None:
        b = self.body
        n_points, n_frames = b.model.samples.n, b.n_frames
        frames = f"{b.name}_frames"
        self.writers = [
            VTUSeriesWriter(
                directory,
                None,
                b.name,
                cells=_vertices(n_points),
                n_points=n_points,
                keep=_kept(keep, b.name),
            ),
            VTUSeriesWriter(
                directory,
                None,
                frames,
                cells=_vertices(n_frames),
                n_points=n_frames,
                keep=_kept(keep, frames),
            ),
        ]
        if b.surface is not None:
            self.writers.append(
                VTUSeriesWriter(
                    directory,
                    None,
                    f"{b.name}_surface",
                    cells=("triangle", b.surface.triangles),
                    n_points=len(b.surface.points),
                    keep=_kept(keep, f"{b.name}_surface"),
                )
            )
        else:  # a surface series left by an earlier run must not pass for this run's
            remove_series(directory, f"{b.name}_surface")

    def write(self, sim, t: float) -> dict[str, Any]:
        b, m = self.body, self.body.model
        _, z, v = sim.body_state(b.name)
        fields = b.point_fields(z)
        x, rest = fields["positions"], m.samples.points
        zdot = m.config_velocity(z, v)
        origins, R = m.frame_type.split(z)[0], m.rotations(z)
        surface = None if b.surface is None else b.embedded["surface"].positions(z)
        if self.writers:
            self.writers[0].write(
                t,
                rest,
                point_data={
                    "displacement": x - rest,
                    "velocity": m.point_map.positions(zdot),
                    **_fields(fields),
                    "volume": m.samples.volumes,
                    "mass": m.masses,
                },
            )
            self.writers[1].write(
                t,
                b.rest_frames,
                point_data={
                    "displacement": origins - b.rest_frames,
                    "velocity": m.frame_type.split(zdot)[0],
                    "axis_x": R[:, :, 0],
                    "axis_y": R[:, :, 1],
                    "axis_z": R[:, :, 2],
                    "radius": m.shapes.radii,
                },
            )
            if surface is not None:
                self.writers[2].write(
                    t, b.surface.points, point_data={"displacement": surface - b.surface.points}
                )
        return {
            "kind": "frames",
            "positions": x.copy(),
            "points": fields,
            "displacement": x - rest,
            "surface": None if surface is None else surface.copy(),
            "frames": origins.copy(),
        }


class TissueSeries(BodySeries):
    def __init__(self, body) -> None:
        super().__init__(body)
        s = body.samples
        self._last_u = np.zeros_like(s.points)  # dead points keep their last displacement
        self._last = {k: np.zeros(s.n) for k in ("J", "von_mises", "energy_density")}
        self._last["J"] = np.ones(s.n)
        self._last_tensors = {k: np.zeros((s.n, 3, 3)) for k in ("green_strain", "cauchy_stress")}
        self._strain = np.zeros(s.n)
        self._velocity = np.zeros_like(s.points)

    def open(self, directory: Path, keep: dict | None = None) -> None:
        n, name = self.body.samples.n, f"{self.body.name}_points"
        kept = _kept(keep, name)
        self.writers = [
            VTUSeriesWriter(directory, None, name, cells=_vertices(n), n_points=n, keep=kept)
        ]
        if kept:  # a resumed run: cut-away points keep the values of the last frame written
            self._continue(directory / kept[-1][1])

    def _continue(self, path: Path) -> None:
        import meshio

        data = meshio.read(path).point_data
        n = self.body.samples.n
        self._last_u[:] = data["displacement"]
        self._strain[:] = data["max_principal_strain"]
        for k in self._last:
            self._last[k][:] = data[k]
        for k in self._last_tensors:
            self._last_tensors[k][:] = np.reshape(data[k], (n, 3, 3))

    def write(self, sim, t: float) -> dict[str, Any]:
        b = self.body
        f = sim.tissue_fields()
        if f:
            ids = f["ids"]
            self._last_u[ids] = f["positions"] - b.samples.points[ids]
            for k in self._last:
                self._last[k][ids] = f[k]
            for k in self._last_tensors:
                self._last_tensors[k][ids] = f[k]
            self._strain[ids] = f["max_principal_strain"]
            m = b.model
            _, z, v = sim.body_state(b.name)
            zdot = m.config_velocity(z, v)
            self._velocity[:] = 0.0  # cut-away points stand still
            self._velocity[ids] = m.point_map.positions(zdot)
        alive = b.dissection.alive.copy()
        if self.writers:
            self.writers[0].write(
                t,
                b.samples.points,
                point_data={
                    "displacement": self._last_u,
                    "velocity": self._velocity,
                    "alive": alive.astype(np.int8),
                    "max_principal_strain": self._strain,
                    **self._last,
                    **self._last_tensors,
                },
            )
        points = {**{k: v.copy() for k, v in self._last.items()}}
        points["green_strain"] = self._last_tensors["green_strain"].copy()
        return {
            "kind": "tissue",
            "positions": b.samples.points + self._last_u,
            "alive": alive,
            "points": points,
            "max_principal_strain": self._strain.copy(),
            "displacement": self._last_u.copy(),
        }


class VisualSeries(BodySeries):
    """A visual surface carried by FEM body ``body`` (``bodies/visual_surface.py``): its rest
    points (z = 0 in 2D) with ``displacement`` and ``velocity``, triangles (lines in 2D)."""

    def __init__(self, body, visual) -> None:
        super().__init__(body)
        self.visual = visual

    def open(self, directory: Path, keep: dict | None = None) -> None:
        v = self.visual
        self.writers = [
            VTUSeriesWriter(
                directory,
                None,
                v.name,
                cells=(v.cell_type, v.cells),
                n_points=len(v.points),
                keep=_kept(keep, v.name),
            )
        ]

    def write(self, sim, t: float) -> dict[str, Any]:
        v = self.visual
        _, c, vel = sim.body_state(v.body)
        shape = self.body.mesh.points.shape
        x = v.positions(c.reshape(shape))
        if self.writers:
            self.writers[0].write(
                t,
                _in_3d(v.points),
                point_data={
                    "displacement": _in_3d(x - v.points),
                    "velocity": _in_3d(v.positions(vel.reshape(shape))),
                },
            )
        return {"positions": x}


def _in_3d(a: np.ndarray) -> np.ndarray:
    """Points or vectors (n, 2) padded with z = 0; (n, 3) as they are."""
    return a if a.shape[1] == 3 else np.column_stack([a, np.zeros(len(a))])


def series_for(body) -> BodySeries:
    return {"fem": FemSeries, "frames": FrameSeries, "tissue": TissueSeries}[body.kind](body)
