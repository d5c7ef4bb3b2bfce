"""The rigid bodies' part of the system (``system.py`` ``System`` inherits it): the linked
vertices (``links.py``), the rigid blocks' loads and the reduction onto their DOFs, the
retraction that places linked vertices, and the joints and springs between rigid bodies
(``joints.py``) with their augmented Lagrangian updates."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError

__all__ = ["RigidSystemPart", "JOINT_STIFFNESS"]

#: a joint's penalty (augmented Lagrangian) against the bodies' stiffness, force scale over
#: length scale (per radian: times the length scale squared)
JOINT_STIFFNESS = 1e3


class RigidSystemPart:
    """Mixed into ``System`` (uses its bodies, slices, pattern, scales and load time)."""

    def _rigid_links(self):
        """The linked vertices of every rigid block (rigid/links.py), or None."""
        from tissuesim.rigid.links import RigidLinks

        if not self.rigid:
            return None
        dofs, rigid, offsets = [], [], []
        for j, vertices, k in self.rigid_members:
            body = self.bodies[j]
            if hasattr(body, "frame_type") or body.mesh.dim != 3:  # a frame body, or 2D
                raise InputError("a rigid body links vertices of 3D FEM bodies only")
            v = np.asarray(vertices, dtype=np.int64)
            start = self.tangent_slices[j].start
            dofs.append(start + 3 * v[:, None] + np.arange(3))
            rigid.append(np.full(len(v), k))
            offsets.append(body.mesh.points[v] - self.rigid[k].center)
        if not dofs:
            return None
        dofs = np.concatenate(dofs)
        if len(np.unique(dofs[:, 0])) < len(dofs):
            raise InputError("a vertex is linked to two rigid bodies (or twice to one)")
        k_dofs = np.array([np.arange(s.start, s.stop) for s in self.rigid_tangent_slices])
        k_conf = np.array([np.arange(s.start, s.stop) for s in self.rigid_config_slices])
        return RigidLinks(
            dofs, np.concatenate(rigid), np.concatenate(offsets), k_dofs, k_conf, self.n_dofs
        )

    def _place_rigid(self, c: np.ndarray, dq: np.ndarray, out: np.ndarray) -> np.ndarray:
        """The rigid blocks retracted too, and their linked vertices placed on them."""
        if not self.rigid:
            return out
        for r, sc, st in zip(
            self.rigid, self.rigid_config_slices, self.rigid_tangent_slices, strict=True
        ):
            out[sc] = r.retract(c[sc], dq[st])
        return self.links.place(out) if self.links is not None else out

    def _rigid_dofs(self, k: int) -> np.ndarray:
        st = self.rigid_tangent_slices[k]
        return np.arange(st.start, st.stop, dtype=np.int64)

    def joint_terms(self, c: np.ndarray, order: int = 2) -> list:
        """Per joint (value, gradient (12,), Hessian (12, 12), residuals or the spring's
        force) at c (rigid/joints.py)."""
        from tissuesim.rigid.joints import RigidSpring, joint_energy, spring_energy

        out = []
        k_force = JOINT_STIFFNESS * self.force_scale / self.length_scale
        for j, (ka, kb) in zip(self.joints, self._joint_ends, strict=True):
            ends = [c[self.rigid_config_slices[k]] for k in (ka, kb)]
            centres = np.array([z[:3] for z in ends])
            R = [z[3:12].reshape(3, 3) for z in ends]
            if isinstance(j, RigidSpring):
                rest = [j.point_a - self.rigid[ka].center, j.point_b - self.rigid[kb].center]
                y = np.array([centres[0] + R[0] @ rest[0], centres[1] + R[1] @ rest[1]])
                out.append((*spring_energy(j, y, centres), None))
                continue
            rest = j.rest_features((self.rigid[ka].center, self.rigid[kb].center))
            y = np.array(
                [centres[0] + R[0] @ rest[0], centres[1] + R[1] @ rest[1]]
                + [R[0] @ rest[i] for i in (2, 3, 4)]
                + [R[1] @ rest[i] for i in (5, 6)]
            )
            lengths = j.point_rows(self.load_time)
            k_point = k_force if j.enforcement is None else j.enforcement.penalty
            k = np.where(lengths, k_point, k_force * self.length_scale**2)
            out.append((*joint_energy(j, y, centres, self.load_time, k), k))
        return out

    def _add_joints(self, acc: Accumulator, c: np.ndarray) -> None:
        if getattr(self, "_joint_positions", None) is None:  # the pattern is fixed: once
            self._joint_positions = []
            for ka, kb in self._joint_ends:
                q = np.concatenate([self._rigid_dofs(ka), self._rigid_dofs(kb)])
                rows, cols = np.repeat(q, 12), np.tile(q, 12)
                self._joint_positions.append(
                    (q, self.pattern.positions(rows, cols, keys=self._pattern_keys()))
                )
        for (q, positions), (value, grad, hess, _, _) in zip(
            self._joint_positions, self.joint_terms(c, acc.order), strict=True
        ):
            acc.add_value("joints", value)
            if acc.order >= 1:
                np.add.at(acc.gradient, q, grad)
            if acc.order >= 2:
                np.add.at(acc.hessian, positions, hess.ravel())

    def update_joints(self, c: np.ndarray, stall_rule: bool = False) -> bool:
        """The joints' augmented Lagrangian update at a solution c (lambda <- lambda - k g,
        ``joints.augment``: until every residual is below TOLERANCE x the length scale, or by
        FEBio's rule for a joint with an enforcement); whether any changed (solve again).
        ``stall_rule``: under FEBio's solver, updates that no longer move a residual end
        (``joints.augment``)."""
        from tissuesim.rigid.joints import TOLERANCE, RigidSpring, augment

        if getattr(self, "_joints_time", None) != self.load_time:  # a new step: FEBio's naug
            self._joints_time = self.load_time
            for j in self.joints:
                j.augmentations, j.last_gap, j.stalls = 0, None, 0
        moved = False  # whether the solve moved since the last update (FEBio's solver only)
        if stall_rule:
            last = getattr(self, "_joints_c", None)  # where the last update was made
            moved = last is None or last.shape != c.shape or not np.array_equal(last, c)
            self._joints_c = np.array(c, dtype=float)
        again = False
        for j, (_, _, _, g, k) in zip(self.joints, self.joint_terms(c, 0), strict=True):
            if isinstance(j, RigidSpring):
                continue
            tight = TOLERANCE * self.length_scale
            rows = j.point_rows(self.load_time)
            again = augment(j, g, k, rows, tight, moved) or again
        return again

    def _pattern_keys(self) -> np.ndarray:
        if getattr(self, "_keys", None) is None or self._keys.size != self.pattern.nnz:
            self._keys = self.pattern.keys()
        return self._keys

    def _reduce_rigid(self, acc: Accumulator, c: np.ndarray) -> Accumulator:
        """The rigid bodies' loads, and what acts on their linked vertices mapped onto their
        six DOFs (rigid/links.py)."""
        if not self.rigid:
            return acc
        for r, sc, st in zip(
            self.rigid, self.rigid_config_slices, self.rigid_tangent_slices, strict=True
        ):
            value, g, diagonal = r.load_energy(c[sc], self.load_time, acc.order)
            acc.add_value(f"{r.name}.load", value)
            if acc.order >= 1:
                acc.gradient[st] += g
            if acc.order >= 2 and diagonal is not None:
                k = np.arange(st.start, st.stop)
                acc.hessian[self.pattern.positions(k, k, keys=self._pattern_keys())] += diagonal
        if self.joints:
            self._add_joints(acc, c)
        links = self.links
        if links is None or acc.order < 1:
            return acc
        p = links.arms(c)
        if acc.order >= 2:
            pat = self.pattern
            H = sp.csr_matrix((acc.hessian, pat.indices, pat.indptr), shape=(pat.n, pat.n))
            extra = links.reduced_hessian(H, acc.gradient, p)
            keys = self._pattern_keys()
            np.add.at(acc.hessian, pat.positions(extra.row, extra.col, keys=keys), extra.data)
            if acc.extra_hessian is not None:
                E = sp.csr_matrix(acc.extra_hessian)
                zero = np.zeros(pat.n)  # the curvature is in the main Hessian already
                acc.extra_hessian = (E + links.reduced_hessian(E, zero, p)).tocsr()
        links.reduce_gradient(acc.gradient, p)
        return acc
