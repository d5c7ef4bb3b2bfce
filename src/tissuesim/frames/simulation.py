"""FrameSimulation: the object users script for a meshless frame-based body.

samples = sample_box([0, 0, 0], [0.4, 0.4, 2.0], spacing=0.1)
frames = grid_frames([0.2, 0.2, 0.0], [0.2, 0.2, 2.0], (1, 1, 8))
sim = FrameSimulation(frames, samples, StVenantKirchhoff(youngs_modulus=1e3, poisson_ratio=0.3),
                      density=1000.0, integrator="backward_euler", time_step=0.01)
sim.fix_frames(sim.frames_where(lambda X: X[:, 2] < 1e-9))
sim.embed_surface(box_surface([0, 0, 0], [0.4, 0.4, 2.0]))
sim.add_gravity([0.0, -9.81, 0.0])
sim.run(steps=100, output="out")
"""

from __future__ import annotations

import time as wallclock
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any, Literal

import numpy as np

from tissuesim.frames.frame_types import FrameType
from tissuesim.frames.integrators import (
    frame_backward_euler_step,
    frame_critical_time_step,
    frame_explicit_step,
    frame_quasistatic_step,
)
from tissuesim.frames.loads import FrameGravity, PointForces
from tissuesim.frames.model import (
    AttachmentSpring,
    Embedding,
    FrameMassKind,
    FrameModel,
    PrescribedFrames,
)
from tissuesim.frames.sampling import IntegrationPoints, Surface
from tissuesim.materials.base import Material
from tissuesim.simulation import StepRecord
from tissuesim.solve.linear import make_linear_solver
from tissuesim.solve.newton import NewtonOptions
from tissuesim.time.retry import advance, validate_stepping
from tissuesim.time.state import State

__all__ = ["FrameSimulation", "FRAME_INTEGRATORS"]

FrameIntegrator = Literal["backward_euler", "quasistatic", "explicit"]
FRAME_INTEGRATORS = {
    "backward_euler": frame_backward_euler_step,
    "quasistatic": frame_quasistatic_step,
    "explicit": frame_explicit_step,
}


class FrameSimulation:
    """A frame-based body with loads, fixed frames, springs and a time integrator.

    frames: (n, 3) rest frame origins (``grid_frames``, ``farthest_point_frames``).
    samples: integration points with volumes (``sample_box``, ``sample_surface``, ...).
    material: any Material (it sees only F). density: kg/m^3.
    frame_type: "rigid" (6 DOF, default) or "affine" (12 DOF).
    shape: "wendland" (default) or "shepard"; radius: None (automatic), scalar or (n,).
    integrator: "backward_euler", "quasistatic" or "explicit" (symplectic Euler, eq. 18).
    mass: "full" generalised mass (default) or "lumped" per-frame rigid-body mass.
    """

    def __init__(
        self,
        frames: np.ndarray,
        samples: IntegrationPoints,
        material: Material,
        *,
        density: float | np.ndarray = 1.0,
        frame_type: str | FrameType = "rigid",
        shape: str = "wendland",
        radius: float | np.ndarray | None = None,
        radius_factor: float = 1.5,
        min_frames: int = 1,
        rotations: np.ndarray | None = None,
        integrator: FrameIntegrator = "backward_euler",
        time_step: float = 0.01,
        mass: FrameMassKind = "full",
        newton: NewtonOptions | None = None,
        max_step_halvings: int = 6,
        start_time: float = 0.0,
        backend: str = "auto",
    ) -> None:
        if integrator not in FRAME_INTEGRATORS:
            raise ValueError(
                f"integrator must be one of {sorted(FRAME_INTEGRATORS)}, not {integrator!r}"
            )
        time_step, max_step_halvings = validate_stepping(time_step, max_step_halvings)
        self.model = FrameModel(
            frames,
            samples,
            material,
            density=density,
            frame_kind=frame_type,
            shape=shape,
            radius=radius,
            radius_factor=radius_factor,
            min_frames=min_frames,
            frame_rotations=rotations,
            mass_kind=mass,
            backend=backend,
        )
        self.integrator = integrator
        self.time_step = float(time_step)
        self.newton = newton or NewtonOptions()
        self.max_step_halvings = int(max_step_halvings)
        z = self.model.rest_config()
        self.start_time = float(start_time)
        self.state = State(float(start_time), z, np.zeros(self.model.n_dofs))
        self._prescribed: list[PrescribedFrames] = []
        self.embedded: dict[str, Embedding] = {}
        self.surface: Surface | None = None
        self._solver = None
        self.solver_reason = ""
        self.history: list[StepRecord] = []
        if integrator != "explicit":
            self._linear_solver()

    # -- set-up -------------------------------------------------------------------------------
    @property
    def n_frames(self) -> int:
        return self.model.n_frames

    @property
    def rest_frames(self) -> np.ndarray:
        return self.model.frame_positions

    def frames_where(self, predicate: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """Indices of frames whose rest positions (n, 3) satisfy ``predicate`` (-> bool (n,))."""
        mask = np.asarray(predicate(self.rest_frames), dtype=bool).reshape(-1)
        if mask.shape != (self.n_frames,):
            raise ValueError("frames_where: the predicate must return one bool per frame")
        return np.flatnonzero(mask)

    def _frame_indices(self, frames, what: str) -> np.ndarray:
        idx = np.asarray(frames, dtype=np.int64).ravel()
        if idx.size == 0:
            raise ValueError(f"{what}: the frame selection is empty")
        if idx.min() < 0 or idx.max() >= self.n_frames:
            raise ValueError(
                f"{what}: frame indices must be in [0, {self.n_frames}); got "
                f"{idx.min()}..{idx.max()}"
            )
        taken = set(self.model.prescribed_frames.tolist()) & set(idx.tolist())
        if taken:
            raise ValueError(f"{what}: frames {sorted(taken)} are already fixed or prescribed")
        return idx

    def fix_frames(self, frames) -> None:
        """Clamp frames at their rest position and orientation."""
        self.prescribe_frames(frames, None)

    def prescribe_frames(
        self, frames, motion: Callable[[float], tuple[np.ndarray, np.ndarray]] | None
    ) -> None:
        """Move frames by ``motion(t) -> (displacement (3,) or (k, 3) m, rotation vector (3,)
        or (k, 3) rad)`` about their own origins, relative to rest. None clamps them."""
        idx = self._frame_indices(frames, "prescribe_frames")
        if motion is not None:
            PrescribedFrames(idx, motion).values(self.time)  # fail now, not mid-run
        self._prescribed.append(PrescribedFrames(idx, motion))
        self.model.set_prescribed(self._prescribed)
        self.state = State(
            self.time, self.model.apply_prescribed(self.state.x, self.time), self.state.v
        )
        self._solver = None

    def embed(self, name: str, points: np.ndarray) -> Embedding:
        """Carry points (k, 3) (markers, a display surface) with the frames by eq. (3)."""
        embedding = self.model.embed(points, what=f"embedded point of {name!r}")
        self.embedded[name] = embedding
        return embedding

    def embed_surface(self, surface: Surface) -> Embedding:
        """A triangle surface carried by the frames, written and drawn as the body."""
        self.surface = surface
        return self.embed("surface", surface.points)

    def add_gravity(self, acceleration: Sequence[float]) -> None:
        g = np.asarray(acceleration, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ValueError(
                f"add_gravity: acceleration must be 3 finite numbers, not {acceleration!r}"
            )
        self.model.loads.append(FrameGravity(g))

    def add_point_forces(self, points: np.ndarray, force) -> Embedding:
        """Dead forces (N) on points (k, 3) carried by the frames: (3,), (k, 3) or t -> (k, 3)."""
        embedding = self.model.embed(points, what="loaded point")
        if not callable(force):
            f = np.asarray(force, dtype=float)
            if f.shape not in ((3,), embedding.points.shape) or not np.all(np.isfinite(f)):
                raise ValueError("add_point_forces: force must be (3,) or (k, 3) finite numbers")
        self.model.loads.append(PointForces(embedding, force))
        return embedding

    def add_spring(
        self,
        points: np.ndarray,
        stiffness: float | np.ndarray,
        target: Callable[[float], np.ndarray] | None = None,
    ) -> AttachmentSpring:
        """Zero-length springs (N/m each) from points (k, 3) carried by the frames to
        ``target(t) -> (k, 3)`` (None: their rest positions): attachment to a moving organ,
        a grasper, or a soft clamp."""
        embedding = self.model.embed(points, what="spring point")
        k = np.broadcast_to(np.asarray(stiffness, dtype=float), (embedding.points.shape[0],))
        if not np.all(np.isfinite(k)) or np.any(k <= 0):
            raise ValueError("add_spring: stiffness must be finite and > 0 (N/m)")
        spring = AttachmentSpring(embedding, k.copy(), target)
        spring.targets(self.time)  # a bad target fails now
        self.model.add_spring(spring)
        self._solver = None
        return spring

    def set_velocity(
        self, linear: Sequence[float] = (0, 0, 0), angular: Sequence[float] = (0, 0, 0)
    ) -> None:
        """Initial velocity: every frame translates with ``linear`` (m/s) and, for rigid frames,
        spins with ``angular`` (rad/s, about its own origin)."""
        n, t = self.n_frames, self.model.frame_type.tangent_size
        v = np.zeros((n, t))
        v[:, :3] = np.asarray(linear, dtype=float)
        if self.model.frame_type.rigid:
            v[:, 3:] = np.asarray(angular, dtype=float)
        elif np.any(np.asarray(angular) != 0):
            raise ValueError("set_velocity: angular velocity needs rigid frames")
        self.state = State(self.time, self.state.x, v.ravel())

    # -- results ------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.state.time

    @property
    def frame_positions(self) -> np.ndarray:
        return self.model.frame_type.split(self.state.x)[0].copy()

    @property
    def frame_rotations(self) -> np.ndarray:
        return self.model.rotations(self.state.x)

    def positions(self, name: str = "surface") -> np.ndarray:
        """Current positions of embedded points ``name`` (k, 3)."""
        try:
            return self.embedded[name].positions(self.state.x)
        except KeyError:
            raise KeyError(
                f"no embedded points named {name!r}; known: {sorted(self.embedded)}"
            ) from None

    def point_fields(self) -> dict[str, np.ndarray]:
        return self.model.point_fields(self.state.x)

    def energies(self) -> dict[str, float]:
        z, t = self.state.x, self.time
        acc = self.model.evaluate_z(z, 0, False, self.model.spring_energies(t))
        return {
            "elastic": acc.terms.get("elastic", 0.0),
            "springs": acc.terms.get("springs", 0.0),
            "kinetic": self.model.kinetic_energy(z, self.state.v),
            "load_potential": -float(self.model.external_force(t) @ z),
        }

    def critical_time_step(self) -> float:
        """Explicit stability limit 2 / omega_max at the current configuration (s)."""
        return frame_critical_time_step(self.model, self.state.x, self.time)

    # -- stepping -----------------------------------------------------------------------------
    def _linear_solver(self):
        if self._solver is None:
            self._solver, self.solver_reason = make_linear_solver(
                self.newton.linear_solver, self.model.n_dofs, 3, None
            )
        return self._solver

    def step(self) -> StepRecord:
        if self.integrator == "quasistatic" and not (self._prescribed or self.model.springs):
            raise ValueError(
                "a quasistatic solve needs fixed or prescribed frames, or springs, to hold the "
                "body against rigid motions; add fix_frames(...) or use backward_euler"
            )
        solver = self._linear_solver() if self.integrator != "explicit" else None
        start = wallclock.perf_counter()
        new_state, records, substeps = advance(
            FRAME_INTEGRATORS[self.integrator],
            self.model,
            self.state,
            self.time_step,
            solver,
            self.newton,
            self.max_step_halvings,
            self.start_time + (len(self.history) + 1) * self.time_step,
        )
        self.state = new_state
        record = StepRecord.build(
            len(self.history) + 1,
            self.time,
            records,
            substeps,
            start,
            solver,
            energies=self.energies(),
            min_J=float(self.point_fields()["J"].min()),
        )
        self.history.append(record)
        return record

    def run(
        self,
        steps: int,
        output: str | Path | None = None,
        *,
        every: int = 1,
        progress: bool = True,
        render: bool = True,
        metadata: dict | None = None,
    ) -> list[StepRecord]:
        """Run ``steps`` steps; with ``output``, write VTU series of the integration points, the
        frames and the embedded surface, summary.json, and (``render``) final.png and run.gif."""
        from tissuesim.frames.output import FrameRunOutput

        writer = FrameRunOutput(self, output, every=every, render=render, metadata=metadata)
        return writer.run(steps, progress=progress)

    def describe(self) -> dict[str, Any]:
        m = self.model
        return {
            "discretisation": "frames",
            "frame_type": m.frame_type.name,
            "frames": m.n_frames,
            "integration_points": m.samples.n,
            "frames_per_point": {
                "mean": float(m.shapes.count.mean()),
                "max": int(m.shapes.count.max()),
            },
            "shape_functions": m.shape,
            "integrator": self.integrator,
            "time_step": self.time_step,
            "mass": m.mass_kind,
            "material": repr(m.material),
            "n_dofs": m.n_dofs,
            "prescribed_dofs": int(m.prescribed_dofs.size),
            "springs": len(m.springs),
            "newton": asdict(self.newton),
            "linear_solver": {
                "name": getattr(self._solver, "name", None),
                "reason": self.solver_reason,
            },
            "backend": {
                "name": m.backend,
                "reason": m.backend_reason,
                "fused_elastic": m.elastic.fused,
            },
        }
