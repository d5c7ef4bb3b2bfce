"""FrameModel: frames, integration points, material, mass, loads, springs and fixed frames.

Everything constant for a frame-based body is built once: shape functions at the integration
points, the virtual-node kinematics, the z and tangent sparsity patterns, the generalised mass,
the elimination sets. ``evaluate`` sums energies over z (the frames' 12-number configurations)
and returns value, gradient and Hessian over the tangent DOFs Newton works on.

Mass (choice): the full generalised mass M_z = sum_s m_s E_s^T E_s (x) I_3 of the integration
points' masses through the frame-to-point map p = E z (Gilles et al. 2011, eq. 11). It is
constant in z, it is exactly what the point masses' kinetic energy gives (1/2 zdot^T M_z zdot
with pdot = E zdot), and it is the Hessian of Backward Euler's inertia term, so implicit steps are
consistent with the elastic discretisation as FEM's consistent mass is. ``mass="lumped"`` keeps
only each frame's own rigid-body mass, sum_s m_s w_is [1, d][1, d]^T (x) I_3 (block-diagonal
per frame, total mass preserved), a cheaper approximation for explicit steps that neglects the
inertial coupling between neighbouring frames.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal

import numpy as np
import scipy.sparse as sp

from tissuesim.backend import resolve_backend
from tissuesim.constraints.dirichlet import Elimination
from tissuesim.energies.accumulator import Accumulator
from tissuesim.energies.elastic import ElasticEnergy
from tissuesim.energies.mass import MassMatrix
from tissuesim.errors import InputError
from tissuesim.frames.frame_types import CONFIG_SIZE, FrameType, frame_type
from tissuesim.frames.kinematics import embedding_matrix, frame_kinematics
from tissuesim.frames.rotations import exp_map
from tissuesim.frames.sampling import IntegrationPoints
from tissuesim.frames.shape_functions import PairFilter, ShapeFunctions, shape_functions
from tissuesim.frames.tangent_assembly import TangentAssembly, gather
from tissuesim.materials.base import Material

__all__ = ["FrameModel", "FrameMassKind", "PrescribedFrames", "AttachmentSpring", "Embedding"]

FrameMassKind = Literal["full", "lumped"]
Motion = Callable[[float], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True, eq=False)
class Embedding:
    """Points carried by the frames (eq. 3): rest ``points`` (k, 3), p = matrix @ Z."""

    points: np.ndarray
    shape: ShapeFunctions
    matrix: sp.csr_matrix

    def positions(self, z: np.ndarray) -> np.ndarray:
        return self.matrix @ z.reshape(-1, 3)


@dataclass(frozen=True, eq=False)
class PrescribedFrames:
    """Frames moved by ``motion(t) -> (displacement (k, 3), rotation vector (k, 3))`` about
    their own origins, rest-relative; ``motion`` None holds them at rest (clamped)."""

    frames: np.ndarray
    motion: Motion | None = None

    def values(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        k = self.frames.size
        if self.motion is None:
            return np.zeros((k, 3)), np.zeros((k, 3))
        u, r = self.motion(t)
        u = np.broadcast_to(np.asarray(u, dtype=float), (k, 3))
        r = np.broadcast_to(np.asarray(r, dtype=float), (k, 3))
        if not (np.all(np.isfinite(u)) and np.all(np.isfinite(r))):
            raise InputError(f"prescribed frame motion is not finite at t = {t:g} s")
        return u, r


@dataclass(frozen=True, eq=False)
class AttachmentSpring:
    """Zero-length springs 1/2 k |p - target(t)|^2 from embedded points to targets (N/m)."""

    embedding: Embedding
    stiffness: np.ndarray  # (k,)
    target: Callable[[float], np.ndarray] | None = None  # None: the rest positions

    def targets(self, t: float) -> np.ndarray:
        if self.target is None:
            return self.embedding.points
        return np.broadcast_to(np.asarray(self.target(t), dtype=float), self.embedding.points.shape)


@dataclass(frozen=True, eq=False)
class SpringEnergy:
    spring: AttachmentSpring
    targets: np.ndarray
    hessian_data: np.ndarray

    def accumulate(self, z: np.ndarray, acc: Accumulator) -> None:
        E = self.spring.embedding.matrix
        r = E @ z.reshape(-1, 3) - self.targets
        k = self.spring.stiffness
        acc.add_value("springs", 0.5 * float(np.sum(k[:, None] * r * r)))
        if acc.order >= 1:
            acc.gradient += (E.T @ (k[:, None] * r)).ravel()
        if acc.order >= 2:
            acc.hessian += self.hessian_data


@dataclass(eq=False)
class FrameModel:
    """A frame-based body.

    frame_positions: (n, 3) rest origins xbar_i (m). samples: integration points with volumes.
    frame_rotations: (n, 3, 3) rest orientations Rbar_i (identity if None).
    shape: "wendland" or "shepard"; radius: None (automatic), scalar or (n,); radius_factor
    scales the automatic radii. min_frames: frames each integration point must see.
    """

    frame_positions: np.ndarray
    samples: IntegrationPoints
    material: Material
    density: float | np.ndarray = 1.0
    frame_kind: str | FrameType = "rigid"
    shape: str = "wendland"
    radius: float | np.ndarray | None = None
    radius_factor: float = 1.5
    min_frames: int = 1
    frame_rotations: np.ndarray | None = None
    mass_kind: FrameMassKind = "full"
    backend: str = "auto"
    loads: list = field(default_factory=list)
    keep_pair: PairFilter | None = None  # drops (point, frame) pairs: cuts (coupling/cutting.py)
    allow_orphans: bool = False  # frames reaching no point are held, not an error (after cuts)

    def __post_init__(self) -> None:
        X = np.asarray(self.frame_positions, dtype=float)
        if X.ndim != 2 or X.shape[1] != 3 or X.shape[0] == 0:
            raise InputError(f"frame positions must be an (n, 3) array, not shape {X.shape}")
        self.frame_positions = X
        n = X.shape[0]
        self.frame_type = frame_type(self.frame_kind)
        if self.frame_rotations is None:
            self.frame_rotations = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        R = np.asarray(self.frame_rotations, dtype=float)
        if R.shape != (n, 3, 3) or not np.allclose(R @ np.swapaxes(R, 1, 2), np.eye(3), atol=1e-9):
            raise InputError("frame rotations must be (n, 3, 3) rotation matrices")
        self.frame_rotations = R
        if self.mass_kind not in ("full", "lumped"):
            raise InputError(f"frame mass must be 'full' or 'lumped', not {self.mass_kind!r}")
        self.masses = self.samples.masses(self.density)
        self.shapes = shape_functions(
            X,
            self.samples.points,
            kind=self.shape,
            radius=self.radius,
            radius_factor=self.radius_factor,
            min_frames=self.min_frames,
            what="integration point",
            keep_pair=self.keep_pair,
        )
        reached = np.zeros(n, dtype=bool)
        reached[self.shapes.frames[self.shapes.weights > 0]] = True
        # orphans: no mass and no stiffness; held where they are (eliminated from Newton)
        self.orphan_frames = np.flatnonzero(~reached) if self.allow_orphans else np.zeros(0, int)
        if not reached.all() and not self.allow_orphans:
            i = int(np.flatnonzero(~reached)[0])
            raise InputError(
                f"frame {i} at {X[i].round(6).tolist()} reaches no integration point "
                f"(support radius {self.shapes.radii[i]:.4g}): it would have no stiffness and "
                "no mass. Move it inside the body, increase its radius, or remove it."
            )
        self.kinematics = frame_kinematics(
            X, self.samples.points, self.samples.volumes, self.shapes
        )
        self.point_map = Embedding(
            self.samples.points, self.shapes, embedding_matrix(X, self.samples.points, self.shapes)
        )
        self.backend, self.backend_reason = resolve_backend(self.backend)
        self.springs: list[AttachmentSpring] = []
        self.attachments: list[AttachmentSpring] = []  # to other bodies (coupling/system.py)
        self.prescribed: list[PrescribedFrames] = []
        self._build()

    # -- set-up -----------------------------------------------------------------------------
    @property
    def n_frames(self) -> int:
        return self.frame_positions.shape[0]

    @property
    def n_dofs(self) -> int:
        """Tangent DOFs (6 or 12 per frame)."""
        return self.n_frames * self.frame_type.tangent_size

    # -- the body interface shared with Model (system.py) ------------------------------------
    @property
    def n_config(self) -> int:
        return CONFIG_SIZE * self.n_frames

    @property
    def tangent_pattern(self):
        return self.assembly.q_pattern

    @property
    def scale_points(self) -> np.ndarray:
        return self.samples.points

    def retract(self, z: np.ndarray, dq: np.ndarray) -> np.ndarray:
        return self.frame_type.retract(z, dq)

    def difference(self, z1: np.ndarray, z0: np.ndarray) -> np.ndarray:
        return self.frame_type.difference(z1, z0)

    def _build(self) -> None:
        stencils = [self.shapes.frames] + [
            s.embedding.shape.frames for s in self.springs + self.attachments
        ]
        self.assembly = TangentAssembly.build(self.frame_type, self.n_frames, stencils)
        self.elastic = ElasticEnergy(self.kinematics, self.material, 0, self.backend)
        E, m = self.point_map.matrix, self.masses
        if self.mass_kind == "full":
            nodes = (E.T @ sp.diags(m) @ E).tocsr()
        else:
            nodes = self._lumped_nodes()
        Mz = sp.kron(nodes, sp.identity(3), format="csr")
        data = gather(self.assembly.z_pattern, Mz)
        rows = np.asarray(Mz.sum(axis=1)).ravel()
        self.mass = MassMatrix(self.mass_kind, self.assembly.z_pattern, data, rows, rows)
        self._spring_hessians = [self._spring_hessian(s) for s in self.springs]
        self.attachment_hessians = [self._spring_hessian(s) for s in self.attachments]
        self.elimination = Elimination.build(self.assembly.q_pattern, self.prescribed_dofs)

    def _spring_hessian(self, spring: AttachmentSpring) -> np.ndarray:
        """Constant z Hessian data of 1/2 k |E z - target|^2: E^T diag(k) E (x) I_3."""
        E = spring.embedding.matrix
        return gather(
            self.assembly.z_pattern, sp.kron(E.T @ sp.diags(spring.stiffness) @ E, sp.identity(3))
        )

    def _lumped_nodes(self) -> sp.csr_matrix:
        sf, d = (
            self.shapes,
            self.samples.points[:, None, :] - self.frame_positions[self.shapes.frames],
        )
        c = np.concatenate([np.ones(d.shape[:2] + (1,)), d], axis=2)  # (q, k, 4)
        blocks = (self.masses[:, None] * sf.weights)[:, :, None, None] * (
            c[:, :, :, None] * c[:, :, None, :]
        )
        nodes = sf.frames[:, :, None] * 4 + np.arange(4)  # (q, k, 4)
        rows = np.broadcast_to(nodes[:, :, :, None], blocks.shape).ravel()
        cols = np.broadcast_to(nodes[:, :, None, :], blocks.shape).ravel()
        n = 4 * self.n_frames
        return sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(n, n))

    def embed(
        self,
        points: np.ndarray,
        what: str = "embedded point",
        keep_pair: PairFilter | None = None,
        min_frames: int = 1,
    ) -> Embedding:
        """Carry rest points (k, 3) with the frames (same kernel and radii as the body);
        ``keep_pair`` drops (point, frame) pairs (cuts)."""
        P = np.asarray(points, dtype=float)
        if P.ndim != 2 or P.shape[1] != 3:
            raise InputError(f"{what}s must be a (k, 3) array, not shape {P.shape}")
        radius = None if self.shape == "shepard" else self.shapes.radii
        sf = shape_functions(
            self.frame_positions,
            P,
            kind=self.shape,
            radius=radius,
            min_frames=min_frames,
            what=what,
            keep_pair=keep_pair,
        )
        return Embedding(P, sf, embedding_matrix(self.frame_positions, P, sf))

    def add_spring(self, spring: AttachmentSpring) -> None:
        self.springs.append(spring)
        self._build()

    def set_attachments(self, attachments: list[AttachmentSpring]) -> None:
        """Springs whose targets are points of other bodies, evaluated by the coupled system:
        their stencils enter the pattern and their constant Hessians ``attachment_hessians``."""
        self.attachments = list(attachments)
        self._build()

    def set_prescribed(self, prescribed: list[PrescribedFrames]) -> None:
        self.prescribed = list(prescribed)
        self.elimination = Elimination.build(self.assembly.q_pattern, self.prescribed_dofs)

    @property
    def prescribed_frames(self) -> np.ndarray:
        """Frames Newton does not move: prescribed ones and orphans (held where they are)."""
        held = [p.frames for p in self.prescribed] + [self.orphan_frames]
        return np.unique(np.concatenate(held).astype(np.int64))

    @property
    def prescribed_dofs(self) -> np.ndarray:
        t = self.frame_type.tangent_size
        return (self.prescribed_frames[:, None] * t + np.arange(t)).ravel()

    # -- configurations -----------------------------------------------------------------------
    def rest_config(self) -> np.ndarray:
        return self.frame_type.join(
            self.frame_positions, np.broadcast_to(np.eye(3), (self.n_frames, 3, 3))
        )

    def apply_prescribed(self, z: np.ndarray, t: float) -> np.ndarray:
        """z with prescribed frames at their positions and rotations at time t."""
        if not self.prescribed:
            return z
        x, A = self.frame_type.split(z.copy())
        x, A = x.copy(), A.copy()
        for p in self.prescribed:
            u, r = p.values(t)
            x[p.frames] = self.frame_positions[p.frames] + u
            A[p.frames] = exp_map(r)
        return self.frame_type.join(x, A)

    def rotations(self, z: np.ndarray) -> np.ndarray:
        """Current frame orientations R_i = A_i Rbar_i (n, 3, 3) (polar part for affine)."""
        _, A = self.frame_type.split(z)
        if not self.frame_type.rigid:
            U, _, Vt = np.linalg.svd(A)
            A = U @ Vt
        return A @ self.frame_rotations

    @cached_property
    def length_scale(self) -> float:
        p = self.samples.points
        return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0))) or 1.0

    @cached_property
    def force_scale(self) -> float:
        return float(self.material.mu * self.samples.volume / self.length_scale)

    # -- energies ----------------------------------------------------------------------------
    def external_force(self, t: float) -> np.ndarray:
        """Dead loads as a force over z (12 n,)."""
        f = np.zeros((4 * self.n_frames, 3))
        for load in self.loads:
            f += load.z_forces(self, t)
        return f.ravel()

    def spring_energies(self, t: float) -> list[SpringEnergy]:
        return [
            SpringEnergy(s, s.targets(t), h)
            for s, h in zip(self.springs, self._spring_hessians, strict=True)
        ]

    def evaluate_z(
        self, z: np.ndarray, order: int, project: bool = False, energies=()
    ) -> Accumulator:
        acc = Accumulator(self.assembly.z_pattern, order, project)
        self.elastic.accumulate(z, acc)
        for energy in energies:
            energy.accumulate(z, acc)
        return acc

    def evaluate(
        self, z: np.ndarray, order: int, project: bool = False, energies=()
    ) -> Accumulator:
        """Elastic energy plus ``energies`` at z, over the tangent DOFs at dq = 0."""
        return self.assembly.to_tangent(z, self.evaluate_z(z, order, project, energies))

    def tangent_mass(self, z: np.ndarray) -> sp.csr_matrix:
        """M_q = T^T M_z T at z over the tangent pattern."""
        data = self.assembly.hessian(z, self.mass.data, None)
        return self.assembly.q_pattern.matrix(data)

    def config_velocity(self, z: np.ndarray, v: np.ndarray) -> np.ndarray:
        """zdot = T(z) v (12 n,): the tangent velocity v in configuration space."""
        T = self.frame_type.tangent_map(z)
        return np.einsum("nij,nj->ni", T, v.reshape(self.n_frames, -1)).ravel()

    def kinetic_energy(self, z: np.ndarray, v: np.ndarray) -> float:
        zdot = self.config_velocity(z, v)
        return 0.5 * float(zdot @ self.mass.dot(zdot))

    def point_fields(self, z: np.ndarray) -> dict[str, np.ndarray]:
        """At the integration points: positions, F, J, Green strain, energy density."""
        F = self.kinematics.deformation_gradients(z)
        L = 0.5 * (np.swapaxes(F, 1, 2) @ F - np.eye(3))
        return {
            "positions": self.point_map.positions(z),
            "F": F,
            "J": np.linalg.det(F),
            "green_strain": L,
            "energy_density": self.material.evaluate(F, 0).energy,
        }
