"""A meshless frame-based body of a Simulation: frames, integration points, one material, its
fixed or prescribed frames, springs, point forces, embedded points (a display surface) and
initial velocity.

The body owns its ``FrameModel`` (shape functions, kinematics, mass, patterns) from the moment
it is added. Forces reported per step: for each fixed or prescribed frame set, the reaction
force (N) = the sum over its frames of the translational part of the step's final tangent
gradient (moving a frame's origin by dx moves all its points by dx, so that part is the net
force the constraint applies); for each spring set, the springs' pull sum k (target - p).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from tissuesim.energies.loads import ExternalForce
from tissuesim.energies.mass import Inertia
from tissuesim.errors import InputError
from tissuesim.frames.frame_types import FrameType
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
from tissuesim.materials.measures import continuum_fields
from tissuesim.validate import short

__all__ = ["FrameBody"]


class FrameBody:
    """See the module docstring. Created by ``Simulation.add_frame_body``."""

    kind = "frames"

    def __init__(
        self,
        name: str,
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
        mass: FrameMassKind = "full",
        backend: str = "auto",
        claim_name: Callable[[str], str],
        changed: Callable[[], None],
        time: Callable[[], float],
    ) -> None:
        self.name = name
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
        self._claim, self._changed, self._time = claim_name, changed, time
        self.prescribed: list[tuple[str, PrescribedFrames]] = []
        self.named_springs: list[tuple[str, AttachmentSpring]] = []
        self.embedded: dict[str, Embedding] = {}
        self.surface: Surface | None = None
        self.config = self.model.rest_config()  # initial configuration (prescribed applied)
        self.velocity = np.zeros(self.model.n_dofs)

    def __repr__(self) -> str:
        m = self.model
        return (
            f"FrameBody({self.name!r}, {m.n_frames} {m.frame_type.name} frames, "
            f"{m.samples.n} integration points)"
        )

    dim = 3

    @property
    def n_frames(self) -> int:
        return self.model.n_frames

    @property
    def rest_frames(self) -> np.ndarray:
        return self.model.frame_positions

    # -- frame sets --------------------------------------------------------------------------
    def frames_where(self, predicate: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """Indices of frames whose rest positions (n, 3) satisfy ``predicate`` (-> bool (n,))."""
        mask = np.asarray(predicate(self.rest_frames), dtype=bool).reshape(-1)
        if mask.shape != (self.n_frames,):
            raise InputError("frames_where: the predicate must return one bool per frame")
        return np.flatnonzero(mask)

    def _frame_indices(self, frames, what: str) -> np.ndarray:
        arr = np.asarray(frames)
        if arr.dtype == bool:
            raise InputError(f"{what}: got a boolean mask; pass frame indices")
        if arr.size and not np.issubdtype(arr.dtype, np.integer):
            raise InputError(f"{what}: frame indices must be integers, got {arr.dtype}")
        idx = arr.astype(np.int64).ravel()
        if idx.size == 0:
            raise InputError(f"{what}: the frame selection is empty")
        if idx.min() < 0 or idx.max() >= self.n_frames:
            raise InputError(
                f"{what}: frame indices must be in [0, {self.n_frames}); got "
                f"{idx.min()}..{idx.max()}"
            )
        taken = set(self.model.prescribed_frames.tolist()) & set(idx.tolist())
        if taken:
            raise InputError(f"{what}: frames {sorted(taken)} are already fixed or prescribed")
        return idx

    def fix_frames(self, frames, name: str | None = None) -> str:
        """Clamp frames at their rest position and orientation; returns the force's name."""
        return self._prescribe(frames, None, name, f"{self.name}.fixed_frames")

    def prescribe_frames(
        self,
        frames,
        motion: Callable[[float], tuple[np.ndarray, np.ndarray]] | None,
        *,
        name: str | None = None,
    ) -> str:
        """Move frames by ``motion(t) -> (displacement (3,) or (k, 3) m, rotation vector (3,)
        or (k, 3) rad)`` about their own origins, relative to rest. None clamps them."""
        return self._prescribe(frames, motion, name, f"{self.name}.prescribed_frames")

    def _prescribe(self, frames, motion, name: str | None, default: str) -> str:
        idx = self._frame_indices(frames, "prescribe_frames")
        if motion is not None:
            PrescribedFrames(idx, motion).values(self._time())  # fail now, not mid-run
        name = self._claim(name, default)
        self.prescribed.append((name, PrescribedFrames(idx, motion)))
        self.model.set_prescribed([p for _, p in self.prescribed])
        self.config = self.model.apply_prescribed(self.config, self._time())
        self._changed("prescribed")
        return name

    # -- embedded points, loads, springs -----------------------------------------------------
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
            raise InputError(
                f"add_gravity: acceleration must be 3 finite numbers, not {short(acceleration)}"
            )
        self.model.loads.append(FrameGravity(g))

    def add_point_forces(self, points: np.ndarray, force) -> Embedding:
        """Dead forces (N) on points (k, 3) carried by the frames: (3,), (k, 3) or t -> (k, 3)."""
        embedding = self.model.embed(points, what="loaded point")
        if not callable(force):
            f = np.asarray(force, dtype=float)
            if f.shape not in ((3,), embedding.points.shape) or not np.all(np.isfinite(f)):
                raise InputError("add_point_forces: force must be (3,) or (k, 3) finite numbers")
        self.model.loads.append(PointForces(embedding, force))
        return embedding

    def add_spring(
        self,
        points: np.ndarray,
        stiffness: float | np.ndarray,
        target: Callable[[float], np.ndarray] | None = None,
        *,
        name: str | None = None,
    ) -> AttachmentSpring:
        """Zero-length springs (N/m each) from points (k, 3) carried by the frames to
        ``target(t) -> (k, 3)`` (None: their rest positions): attachment to a moving organ,
        a grasper, or a soft clamp. Their pull is reported as ``name``."""
        embedding = self.model.embed(points, what="spring point")
        k = np.broadcast_to(np.asarray(stiffness, dtype=float), (embedding.points.shape[0],))
        if not np.all(np.isfinite(k)) or np.any(k <= 0):
            raise InputError("add_spring: stiffness must be finite and > 0 (N/m)")
        spring = AttachmentSpring(embedding, k.copy(), target)
        spring.targets(self._time())  # a bad target fails now
        name = self._claim(name, f"{self.name}.springs")
        self.model.add_spring(spring)
        self.named_springs.append((name, spring))
        self._changed()
        return spring

    def set_velocity(
        self, linear: Sequence[float] = (0, 0, 0), angular: Sequence[float] = (0, 0, 0)
    ) -> None:
        """Initial velocity: every frame translates with ``linear`` (m/s) and, for rigid frames,
        spins with ``angular`` (rad/s, about its own origin)."""
        n, t = self.n_frames, self.model.frame_type.tangent_size
        lin, ang = np.asarray(linear, dtype=float), np.asarray(angular, dtype=float)
        if lin.shape != (3,) or ang.shape != (3,):
            raise InputError("set_velocity: linear and angular velocities are 3 numbers each")
        v = np.zeros((n, t))
        v[:, :3] = lin
        if self.model.frame_type.rigid:
            v[:, 3:] = ang
        elif np.any(ang != 0):
            raise InputError("set_velocity: angular velocity needs rigid frames")
        self.velocity = v.ravel()
        self._changed("velocity")

    # -- what the system and the output ask of a body -------------------------------------------
    def step_energies(self, t: float, z_pred: np.ndarray | None, h: float) -> list:
        energies = [] if z_pred is None else [Inertia(self.model.mass, z_pred, h)]
        energies.append(ExternalForce(self.model.external_force(t)))
        return energies + self.model.spring_energies(t)

    def forces(self, z: np.ndarray, gradient: np.ndarray | None, t: float) -> dict:
        out = {}
        size = self.model.frame_type.tangent_size
        for name, p in self.prescribed:
            f = np.zeros(3)
            if gradient is not None:
                f = gradient.reshape(-1, size)[p.frames, :3].sum(axis=0)
            out[name] = np.asarray(f, dtype=float).tolist()
        for name, s in self.named_springs:
            pull = s.stiffness[:, None] * (s.targets(t) - s.embedding.positions(z))
            out[name] = pull.sum(axis=0).tolist()
        return out

    def point_fields(self, z: np.ndarray) -> dict[str, np.ndarray]:
        """At the integration points: positions, F, and J, green_strain, cauchy_stress,
        von_mises, energy_density (``materials/measures.py``)."""
        F = self.model.kinematics.deformation_gradients(z)
        fields = continuum_fields(self.model.material, F)
        fields["positions"] = self.model.point_map.positions(z)
        fields["F"] = F
        return fields

    def min_J(self, z: np.ndarray) -> float:
        return float(np.linalg.det(self.model.kinematics.deformation_gradients(z)).min())

    def describe(self) -> dict:
        m = self.model
        return {
            "kind": "frames",
            "frame_type": m.frame_type.name,
            "frames": m.n_frames,
            "integration_points": m.samples.n,
            "volume": float(m.samples.volume),
            "mass": float(m.masses.sum()),
            "frames_per_point": {
                "mean": float(m.shapes.count.mean()),
                "max": int(m.shapes.count.max()),
            },
            "shape_functions": m.shape,
            "material": repr(m.material),
            "mass_matrix": m.mass_kind,
            "prescribed_dofs": int(m.prescribed_dofs.size),
            "springs": len(m.springs),
            "surface_triangles": 0 if self.surface is None else int(len(self.surface.triangles)),
            "backend": {
                "name": m.backend,
                "reason": m.backend_reason,
                "fused_elastic": m.elastic.fused,
            },
        }
