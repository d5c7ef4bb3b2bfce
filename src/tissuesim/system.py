"""The assembled system of a simulation: every body and the attachments between them, for one
Newton solve per step.

Configuration c = [c_0, c_1, ...]: each body's block in turn (FEM: vertex positions, 3 or 2 per
vertex; frames: 12 numbers per frame). Newton's tangent DOFs q = [q_0, q_1, ...] are the same
for FEM bodies and 6 (rigid) or 12 (affine) per frame for frame bodies, so a body has one slice
in c and one in q. Phi(c) = sum over bodies of their energies (elastic, inertia, loads, springs;
``Model.evaluate`` / ``FrameModel.evaluate`` over the body's own tangent pattern) + the
attachments' coupling energy (``coupling/attachment.py``).

A body is a ``Model`` (FEM) or a ``FrameModel`` (frames); both offer n_config, n_dofs,
tangent_pattern, rest_config, retract, difference, apply_prescribed, prescribed_dofs, mass,
external_force, kinetic_energy and evaluate(c, order, project, energies).

Assembly: each body assembles on its own pattern as it would alone (fused FEM kernels, frame
tangent assembly with the rotation-chart curvature); the global CSR pattern is the union of the
bodies' patterns at their offsets and the FEM-frame cross blocks of the attachments, and every
body entry has a precomputed position in it. A system of one body without attachments uses the
body's pattern itself and its accumulator unchanged: the one-body case costs nothing extra.
Cross blocks: the coupling's d2W/dx dz = -B^T K E (x) I_3 is constant; over the tangent it is
-B^T K E T(z), one 3 x t block per (vertex, frame) pair, computed per evaluation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.constraints.dirichlet import Elimination
from tissuesim.coupling.attachment import Attachment, OrganSide, TissueSide
from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError
from tissuesim.rigid.in_system import RigidSystemPart

__all__ = ["System", "is_frame_body"]


def is_frame_body(body) -> bool:
    """A FrameModel (frames have a frame type; FEM Models do not)."""
    return hasattr(body, "frame_type")


@dataclass(frozen=True, eq=False)
class _Cross:
    """Vertex / frame pairs of one attachment and where their blocks go."""

    frames: np.ndarray  # (p,) frame of each pair
    coefficients: np.ndarray  # (p, 4) sum_s k_s b_sa E_s[i, c] for the pair (a, i)
    positions: np.ndarray  # (p, 3, t) in the global data array
    positions_t: np.ndarray  # (p, t, 3) the transposed entries


@dataclass(eq=False)
class System(RigidSystemPart):
    """Bodies (``Model`` or ``FrameModel``) named ``names``, and attachments between a FEM body
    (``Attachment.organ``) and a frame body (``Attachment.tissue_body``; None: the only frame
    body). Built once per topology: a cut rebuilds it."""

    bodies: Sequence
    names: Sequence[str]
    attachments: Sequence[Attachment] = ()
    ties: Sequence = ()  # coupling/tie.py: FEM bodies glued where they touch
    contact: object = None  # contact/model.py ContactModel, or None
    #: penalty contact pairs between FEM bodies' facets (contact/penalty/pair.py)
    penalty_contacts: Sequence = ()
    #: rigid bodies (rigid/body.py RigidModel), their blocks after the bodies' in c and q, and
    #: the FEM vertices that follow them: (body index, vertex indices, rigid index) each
    rigid: Sequence = ()
    rigid_members: Sequence = ()
    #: joints and springs between rigid bodies (rigid/joints.py), by the rigid bodies' names
    joints: Sequence = ()
    #: the time of the rigid bodies' loads (the step's end time: Simulation.step_energies)
    load_time: float = 0.0
    # the last implicit step's body energies (inertia about its prediction, loads): its Phi,
    # for the instrument linearisation (contact/readout/haptics.py)
    last_step_energies: list | None = None

    def __post_init__(self) -> None:
        self.bodies, self.names = list(self.bodies), list(self.names)
        if len(self.bodies) != len(self.names) or not self.bodies:
            raise InputError("a system needs one name per body and at least one body")
        frame_bodies = [j for j, b in enumerate(self.bodies) if is_frame_body(b)]
        self.attachments = list(self.attachments)
        self._tissue_of = []
        for a in self.attachments:
            j = a.tissue_body if a.tissue_body is not None else _only(frame_bodies)
            if not is_frame_body(self.bodies[j]) or is_frame_body(self.bodies[a.organ]):
                raise InputError("an attachment joins a FEM body to a frame body")
            self._tissue_of.append(j)
        # each frame body gets its attachments (stencils in its pattern, constant Hessians)
        self._slot = [0] * len(self.attachments)
        for j in frame_bodies:
            mine = [i for i, t in enumerate(self._tissue_of) if t == j]
            for slot, i in enumerate(mine):
                self._slot[i] = slot
            if mine or self.bodies[j].attachments:
                self.bodies[j].set_attachments([self.attachments[i].spring() for i in mine])
        c0 = t0 = 0
        self.config_slices, self.tangent_slices = [], []
        for b in self.bodies:
            self.config_slices.append(slice(c0, c0 + b.n_config))
            self.tangent_slices.append(slice(t0, t0 + b.n_dofs))
            c0, t0 = c0 + b.n_config, t0 + b.n_dofs
        self.rigid = list(self.rigid)
        self.rigid_config_slices, self.rigid_tangent_slices = [], []
        for r in self.rigid:
            self.rigid_config_slices.append(slice(c0, c0 + r.n_config))
            self.rigid_tangent_slices.append(slice(t0, t0 + r.n_dofs))
            c0, t0 = c0 + r.n_config, t0 + r.n_dofs
        self.n_config, self.n_dofs = c0, t0
        self.ties = list(self.ties)
        self.single = len(self.bodies) == 1 and not self.attachments and not self.rigid
        self.links = self._rigid_links()
        self.joints = list(self.joints)
        names = [r.name for r in self.rigid]
        for j in self.joints:
            for end in (j.a, j.b):
                if end not in names:
                    raise InputError(f"joint {j.name!r}: {end!r} is not a rigid body")
        self._joint_ends = [(names.index(j.a), names.index(j.b)) for j in self.joints]
        self._tie_matrices = [self._tie_matrix(t) for t in self.ties]
        self._build_pattern()
        self.organ_hessians = [
            OrganSide.hessian(a, self.bodies[a.organ].pattern, self.bodies[a.organ].mesh.simplices)
            for a in self.attachments
        ]
        self.set_prescribed()

    # -- structure ----------------------------------------------------------------------------
    def _build_pattern(self) -> None:
        if self.single:
            self.pattern = self.bodies[0].tangent_pattern
            self.body_positions = [None]
            self.cross = []
            return
        rows, cols = [], []
        body_patterns = [
            (b.tangent_pattern, s.start)
            for b, s in zip(self.bodies, self.tangent_slices, strict=True)
        ]
        for pattern, off in body_patterns:
            keys = pattern.keys()
            rows.append(keys // pattern.n + off)
            cols.append(keys % pattern.n + off)
        pairs = [
            self._cross_pairs(a, j) for a, j in zip(self.attachments, self._tissue_of, strict=True)
        ]
        for r, c, _, _ in pairs:
            rows += [r.ravel(), c.ravel()]
            cols += [c.ravel(), r.ravel()]
        tie_hessians = [
            (Gt.T @ sp.diags(np.repeat(t.stiffness, 3)) @ Gt).tocoo()
            for t, (_, Gt) in zip(self.ties, self._tie_matrices, strict=True)
        ]
        for H in tie_hessians:
            rows.append(H.row.astype(np.int64))
            cols.append(H.col.astype(np.int64))
        if self.links is not None:
            r, c = self.links.pattern_entries(np.concatenate(rows), np.concatenate(cols))
            rows.append(r.astype(np.int64))
            cols.append(c.astype(np.int64))
        for ka, kb in self._joint_ends:  # a joint couples its two rigid blocks
            q = np.concatenate([self._rigid_dofs(ka), self._rigid_dofs(kb)])
            rows.append(np.repeat(q, 12))
            cols.append(np.tile(q, 12))
        if self.rigid and not self.links:
            for k in range(len(self.rigid)):
                q = self._rigid_dofs(k)
                rows.append(np.repeat(q, 6))
                cols.append(np.tile(q, 6))
        self.pattern = SparsityPattern.from_entries(
            self.n_dofs, np.concatenate(rows), np.concatenate(cols)
        )
        keys = self.pattern.keys()
        self.tie_hessian = np.zeros(self.pattern.nnz)  # constant: the ties are quadratic
        for H in tie_hessians:
            np.add.at(self.tie_hessian, self.pattern.positions(H.row, H.col, keys=keys), H.data)
        self.body_positions = []
        for pattern, off in body_patterns:
            k = pattern.keys()
            self.body_positions.append(
                self.pattern.positions(k // pattern.n + off, k % pattern.n + off, keys=keys)
            )
        self.cross = [
            _Cross(
                frames,
                coeff,
                self.pattern.positions(r, c, keys=keys),
                self.pattern.positions(np.swapaxes(c, 1, 2), np.swapaxes(r, 1, 2), keys=keys),
            )
            for (r, c, frames, coeff) in pairs
        ]

    def _tie_matrix(self, tie):
        """G over the configuration (for G c) and over the tangent DOFs (gradient, Hessian)."""
        ja, jb = self.index(tie.a), self.index(tie.b)
        A, B = self.bodies[ja].mesh.simplices, self.bodies[jb].mesh.simplices
        sc, st = self.config_slices, self.tangent_slices
        return (
            tie.matrix(A, B, sc[ja].start, sc[jb].start, self.n_config),
            tie.matrix(A, B, st[ja].start, st[jb].start, self.n_dofs),
        )

    def tie_residuals(self, c: np.ndarray) -> list[np.ndarray]:
        """y - w - d (S, 3) per tie: the gaps the penalty lets open."""
        return [
            (Gc @ c).reshape(-1, 3) - t.offset
            for t, (Gc, _) in zip(self.ties, self._tie_matrices, strict=True)
        ]

    def _cross_pairs(self, a: Attachment, j: int):
        organ, tissue = self.bodies[a.organ], self.bodies[j]
        t = tissue.frame_type.tangent_size
        B = a.organ_matrix(organ.mesh.simplices, organ.mesh.n_points)
        C = (B.T @ sp.diags(a.stiffness) @ a.tissue.matrix).tocoo()  # (vertices, 4 frames)
        n_frames = tissue.n_frames
        key = C.row.astype(np.int64) * n_frames + C.col // 4
        pairs, inverse = np.unique(key, return_inverse=True)
        coeff = np.zeros((pairs.size, 4))
        np.add.at(coeff, (inverse, C.col % 4), C.data)
        vert, frame = pairs // n_frames, pairs % n_frames
        off_o = self.tangent_slices[a.organ].start
        off_t = self.tangent_slices[j].start
        r = off_o + 3 * vert[:, None, None] + np.arange(3)[None, :, None]
        c = off_t + t * frame[:, None, None] + np.arange(t)[None, None, :]
        r, c = np.broadcast_arrays(r, c)
        return r, c, frame, coeff

    # -- DOFs ---------------------------------------------------------------------------------
    def set_prescribed(self) -> None:
        """Recollect prescribed DOFs of every body (after a body's conditions changed)."""
        dofs = [
            b.prescribed_dofs + s.start
            for b, s in zip(self.bodies, self.tangent_slices, strict=True)
        ]
        dofs += [
            r.prescribed_dofs + s.start
            for r, s in zip(self.rigid, self.rigid_tangent_slices, strict=True)
        ]
        if self.links is not None:
            dofs.append(self.links.dofs.ravel())
        self.prescribed_dofs = np.concatenate(dofs).astype(np.int64)
        if self.single:
            self.elimination = self.bodies[0].elimination
        else:
            self.elimination = Elimination.build(self.pattern, self.prescribed_dofs)

    def body_config(self, c: np.ndarray, j: int) -> np.ndarray:
        return c[self.config_slices[j]]

    def index(self, name: str) -> int:
        return self.names.index(name)

    def retract(self, c: np.ndarray, dq: np.ndarray) -> np.ndarray:
        if self.single:
            return self.bodies[0].retract(c, dq)
        out = np.empty(self.n_config)
        for b, sc, st in zip(self.bodies, self.config_slices, self.tangent_slices, strict=True):
            out[sc] = b.retract(c[sc], dq[st])
        return self._place_rigid(c, dq, out)

    def difference(self, c1: np.ndarray, c0: np.ndarray) -> np.ndarray:
        """The tangent step from c0 to c1 (velocities times h)."""
        if self.single:
            return self.bodies[0].difference(c1, c0)
        out = np.empty(self.n_dofs)
        for b, sc, st in zip(self.bodies, self.config_slices, self.tangent_slices, strict=True):
            out[st] = b.difference(c1[sc], c0[sc])
        for r, sc, st in zip(
            self.rigid, self.rigid_config_slices, self.rigid_tangent_slices, strict=True
        ):
            out[st] = r.difference(c1[sc], c0[sc])
        return out

    def apply_prescribed(self, c: np.ndarray, t: float) -> np.ndarray:
        out = c.copy()
        for b, sc in zip(self.bodies, self.config_slices, strict=True):
            out[sc] = b.apply_prescribed(c[sc], t)
        for r, sc in zip(self.rigid, self.rigid_config_slices, strict=True):
            out[sc] = r.apply_prescribed(c[sc], t)
        return self.links.place(out) if self.links is not None else out

    def rest_config(self) -> np.ndarray:
        return np.concatenate(
            [b.rest_config() for b in self.bodies] + [r.rest_config() for r in self.rigid]
        )

    def kinetic_energy(self, c: np.ndarray, v: np.ndarray) -> float:
        return float(
            sum(
                b.kinetic_energy(c[sc], v[st])
                for b, sc, st in zip(
                    self.bodies, self.config_slices, self.tangent_slices, strict=True
                )
            )
        )

    @cached_property
    def length_scale(self) -> float:
        if self.single:
            return self.bodies[0].length_scale
        p = np.concatenate([b.scale_points for b in self.bodies])
        return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0))) or 1.0

    @cached_property
    def force_scale(self) -> float:
        return float(max(b.force_scale for b in self.bodies))

    # -- energy -------------------------------------------------------------------------------
    def evaluate(
        self,
        c: np.ndarray,
        order: int,
        project: bool = False,
        energies: Sequence[Sequence] | None = None,
        contact: bool = True,
    ) -> Accumulator:
        """Phi at c: every body's energies (``energies[j]``: the extra energies of body j in
        its configuration space) plus the coupling, over the tangent DOFs; ``contact`` False
        leaves the contact energy out (contact/barrier/kinematic.py adds its own). ``project``:
        False (exact Hessians), True (every part projected to PSD) or "contact" (only the contact
        energy's, per collision as IPC does)."""
        energies = energies if energies is not None else [() for _ in self.bodies]
        contact_project = bool(project)
        project = project is True
        if self.single:
            acc = self.bodies[0].evaluate(c, order, project, energies[0])
            self._add_penalty_contacts(acc, c, contact_project)
            return self._add_contact(acc, c, contact_project) if contact else acc
        acc = Accumulator(self.pattern, order, project)
        parts = [list(e) for e in energies]
        for i, a in enumerate(self.attachments):
            organ, j = self.bodies[a.organ], self._tissue_of[i]
            tissue = self.bodies[j]
            y = a.organ_positions(organ.mesh.simplices, c[self.config_slices[a.organ]])
            p = a.tissue.positions(c[self.config_slices[j]])
            r = p - y
            acc.add_value("attachment", 0.5 * float(np.sum(a.stiffness[:, None] * r * r)))
            if order >= 1:
                parts[a.organ].append(OrganSide(a, organ.mesh.simplices, p, self.organ_hessians[i]))
                parts[j].append(TissueSide(a, y, tissue.attachment_hessians[self._slot[i]]))
        for j, body in enumerate(self.bodies):
            part = body.evaluate(c[self.config_slices[j]], order, project, parts[j])
            self._merge(acc, part, j)
        for t, (_, Gt), r in zip(self.ties, self._tie_matrices, self.tie_residuals(c), strict=True):
            kr = t.stiffness[:, None] * r
            acc.add_value("ties", 0.5 * float(np.sum(kr * r)))
            if order >= 1:
                acc.gradient += Gt.T @ kr.ravel()
        if order >= 2 and self.ties:
            acc.hessian += self.tie_hessian
        if order >= 2:
            for i, cross in enumerate(self.cross):
                j = self._tissue_of[i]
                self._add_cross(cross, self.bodies[j], c[self.config_slices[j]], acc.hessian)
        self._add_penalty_contacts(acc, c, contact_project)
        if contact:
            self._add_contact(acc, c, contact_project)
        return self._reduce_rigid(acc, c)

    def _add_contact(self, acc: Accumulator, c: np.ndarray, project: bool) -> Accumulator:
        """The barrier contact energy (contact/model.py) on top of everything else."""
        if self.contact is None:
            return acc
        value, grad, hess = self.contact.evaluate(c, acc.order, project)
        acc.add_value("contact", value)
        if grad is not None and acc.order >= 1:
            acc.gradient += grad
        if hess is not None and acc.order >= 2:
            acc.extra_hessian = hess if acc.extra_hessian is None else acc.extra_hessian + hess
        return acc

    def body_positions_and_dofs(self, c: np.ndarray) -> tuple[list, list]:
        """Every body's vertex positions (k, 3) at c and their tangent DOFs (k, 3) (FEM
        bodies; a frame body's entries are None)."""
        positions, dofs = [], []
        for b, sc, st in zip(self.bodies, self.config_slices, self.tangent_slices, strict=True):
            if is_frame_body(b):
                positions.append(None)
                dofs.append(None)
                continue
            d = b.mesh.dim
            positions.append(c[sc].reshape(-1, d))
            dofs.append(np.arange(st.start, st.stop).reshape(-1, d))
        return positions, dofs

    def _add_penalty_contacts(self, acc: Accumulator, c: np.ndarray, project: bool) -> None:
        """FEBio-style penalty contact pairs (contact/penalty/pair.py), their Hessians added
        to the changing-sparsity part."""
        if not self.penalty_contacts:
            return
        positions, dofs = self.body_positions_and_dofs(c)
        for pair in self.penalty_contacts:
            value, grad, hess = pair.evaluate(positions, dofs, self.n_dofs, acc.order, project)
            acc.add_value(f"penalty_contact.{pair.name}", value)
            if grad is not None and acc.order >= 1:
                acc.gradient += grad
            if hess is not None and acc.order >= 2:
                acc.extra_hessian = hess if acc.extra_hessian is None else acc.extra_hessian + hess

    def update_penalty_contacts(self, c: np.ndarray) -> bool:
        """The penalty pairs' lagged terms at a solution c (augmentation, current areas);
        whether any changed."""
        positions, _ = self.body_positions_and_dofs(c)
        changed = False
        for pair in self.penalty_contacts:
            changed = pair.update(positions) or changed
        return changed

    def _merge(self, acc: Accumulator, part: Accumulator, j: int) -> None:
        for term, value in part.terms.items():
            acc.add_value(f"{self.names[j]}.{term}", value)
        if acc.order >= 1:
            acc.gradient[self.tangent_slices[j]] += part.gradient
        if acc.order >= 2:
            acc.hessian[self.body_positions[j]] += part.hessian

    @staticmethod
    def _add_cross(cross: _Cross, tissue, z: np.ndarray, hessian: np.ndarray) -> None:
        ft = tissue.frame_type
        T = ft.tangent_map(z).reshape(tissue.n_frames, 4, 3, ft.tangent_size)
        blocks = -np.einsum("pc,pcjk->pjk", cross.coefficients, T[cross.frames])
        hessian += np.bincount(cross.positions.ravel(), blocks.ravel(), hessian.size)
        hessian += np.bincount(
            cross.positions_t.ravel(), np.swapaxes(blocks, 1, 2).ravel(), hessian.size
        )


def _only(frame_bodies: list[int]) -> int:
    if len(frame_bodies) != 1:
        raise InputError(
            "an attachment must name its frame body (tissue_body) when the system has "
            f"{len(frame_bodies)} frame bodies"
        )
    return frame_bodies[0]
