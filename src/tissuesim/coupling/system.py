"""Organs and connective tissue as one system for one Newton solve.

Configuration c = [x_organ_0, x_organ_1, ..., z_tissue] (positions of every organ vertex, then
the tissue frames' 12 numbers each); Newton's tangent DOFs are the same for the organs and the
frames' 6 (rigid) or 12 (affine) per frame for the tissue, so organs come first and share their
offsets in both vectors. Phi(c) = sum over bodies of their own energies (elastic, inertia,
loads, springs) + the attachments' coupling energy (``attachment.py``).

Assembly: each body assembles on its own pattern as it does alone (FEM kernels, frame tangent
assembly with the rotation-chart curvature); the global CSR pattern is the union of the bodies'
patterns at their offsets and the organ-tissue cross blocks of the attachments, and every body
entry has a precomputed position in it. Cross blocks: the coupling's d2W/dx dz = -B^T K E (x) I_3
is constant; over the tangent it is -B^T K E T(z), one 3 x t block per (organ vertex, frame)
pair, computed per evaluation from the frames' tangent maps.
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
from tissuesim.frames.frame_types import CONFIG_SIZE
from tissuesim.frames.model import FrameModel
from tissuesim.model import Model

__all__ = ["CoupledSystem"]


@dataclass(frozen=True, eq=False)
class _Cross:
    """Organ-vertex / frame pairs of one attachment and where their blocks go."""

    frames: np.ndarray  # (p,) frame of each pair
    coefficients: np.ndarray  # (p, 4) sum_s k_s b_sa E_s[i, c] for the pair (a, i)
    positions: np.ndarray  # (p, 3, t) in the global data array
    positions_t: np.ndarray  # (p, t, 3) the transposed entries


@dataclass(eq=False)
class CoupledSystem:
    """FEM organs (``Model``), optionally one frame-based tissue (``FrameModel``), and the
    attachments between them. Built once per topology: a cut rebuilds it."""

    organs: Sequence[Model]
    organ_names: Sequence[str]
    tissue: FrameModel | None = None
    attachments: Sequence[Attachment] = ()

    def __post_init__(self) -> None:
        self.organs, self.organ_names = list(self.organs), list(self.organ_names)
        self.attachments = list(self.attachments)
        if self.attachments and self.tissue is None:
            raise ValueError("attachments need a tissue body")
        if self.tissue is not None:
            self.tissue.set_attachments([a.spring() for a in self.attachments])
        sizes = [m.n_dofs for m in self.organs]
        starts = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.organ_slices = [
            slice(int(a), int(b)) for a, b in zip(starts[:-1], starts[1:], strict=True)
        ]
        n_org = int(starts[-1])
        if self.tissue is not None:
            self.tissue_config = slice(n_org, n_org + CONFIG_SIZE * self.tissue.n_frames)
            self.tissue_tangent = slice(n_org, n_org + self.tissue.n_dofs)
        else:
            self.tissue_config = self.tissue_tangent = slice(n_org, n_org)
        self.n_config, self.n_dofs = self.tissue_config.stop, self.tissue_tangent.stop
        self._build_pattern()
        self.organ_hessians = [
            OrganSide.hessian(a, self.organs[a.organ].pattern) for a in self.attachments
        ]
        self.set_prescribed()

    # -- structure ----------------------------------------------------------------------------
    def _build_pattern(self) -> None:
        rows, cols = [], []
        body_patterns = [
            (m.pattern, s.start) for m, s in zip(self.organs, self.organ_slices, strict=True)
        ]
        if self.tissue is not None:
            body_patterns.append((self.tissue.assembly.q_pattern, self.tissue_tangent.start))
        for pattern, off in body_patterns:
            keys = pattern.keys()
            rows.append(keys // pattern.n + off)
            cols.append(keys % pattern.n + off)
        self._cross = [self._cross_pairs(a) for a in self.attachments]
        for cross in self._cross:
            rows.append(cross[0].ravel())
            cols.append(cross[1].ravel())
            rows.append(cross[1].ravel())
            cols.append(cross[0].ravel())
        self.pattern = SparsityPattern.from_entries(
            self.n_dofs, np.concatenate(rows), np.concatenate(cols)
        )
        keys = self.pattern.keys()
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
            for (r, c, frames, coeff) in self._cross
        ]
        del self._cross

    def _cross_pairs(self, a: Attachment):
        organ = self.organs[a.organ]
        t = self.tissue.frame_type.tangent_size
        B = a.organ_matrix(organ.mesh.cells, organ.mesh.n_points)
        C = (B.T @ sp.diags(a.stiffness) @ a.tissue.matrix).tocoo()  # (vertices, 4 frames)
        n_frames = self.tissue.n_frames
        key = C.row.astype(np.int64) * n_frames + C.col // 4
        pairs, inverse = np.unique(key, return_inverse=True)
        coeff = np.zeros((pairs.size, 4))
        np.add.at(coeff, (inverse, C.col % 4), C.data)
        vert, frame = pairs // n_frames, pairs % n_frames
        off_o = self.organ_slices[a.organ].start
        off_t = self.tissue_tangent.start
        r = off_o + 3 * vert[:, None, None] + np.arange(3)[None, :, None]
        c = off_t + t * frame[:, None, None] + np.arange(t)[None, None, :]
        r, c = np.broadcast_arrays(r, c)
        return r, c, frame, coeff

    # -- DOFs --------------------------------------------------------------------------------
    def set_prescribed(self) -> None:
        """Recollect prescribed DOFs of every body (after a body's conditions changed)."""
        dofs = [
            m.prescribed.dofs + s.start for m, s in zip(self.organs, self.organ_slices, strict=True)
        ]
        if self.tissue is not None:
            dofs.append(self.tissue.prescribed_dofs + self.tissue_tangent.start)
        self.prescribed_dofs = np.concatenate(dofs).astype(np.int64)
        self.elimination = Elimination.build(self.pattern, self.prescribed_dofs)

    def organ_x(self, c: np.ndarray, j: int) -> np.ndarray:
        return c[self.organ_slices[j]]

    def tissue_z(self, c: np.ndarray) -> np.ndarray:
        return c[self.tissue_config]

    def retract(self, c: np.ndarray, dq: np.ndarray) -> np.ndarray:
        out = c.copy()
        n_org = self.tissue_config.start
        out[:n_org] += dq[:n_org]
        if self.tissue is not None:
            out[self.tissue_config] = self.tissue.frame_type.retract(
                c[self.tissue_config], dq[self.tissue_tangent]
            )
        return out

    def difference(self, c1: np.ndarray, c0: np.ndarray) -> np.ndarray:
        """The tangent step from c0 to c1 (velocities times h)."""
        out = np.empty(self.n_dofs)
        n_org = self.tissue_config.start
        out[:n_org] = c1[:n_org] - c0[:n_org]
        if self.tissue is not None:
            out[self.tissue_tangent] = self.tissue.frame_type.difference(
                c1[self.tissue_config], c0[self.tissue_config]
            )
        return out

    def apply_prescribed(self, c: np.ndarray, t: float) -> np.ndarray:
        out = c.copy()
        for m, s in zip(self.organs, self.organ_slices, strict=True):
            out[s.start + m.prescribed.dofs] = m.prescribed.positions(t)
        if self.tissue is not None:
            out[self.tissue_config] = self.tissue.apply_prescribed(c[self.tissue_config], t)
        return out

    def rest_config(self) -> np.ndarray:
        parts = [m.rest_positions() for m in self.organs]
        if self.tissue is not None:
            parts.append(self.tissue.rest_config())
        return np.concatenate(parts)

    @cached_property
    def length_scale(self) -> float:
        pts = [m.mesh.points for m in self.organs]
        if self.tissue is not None:
            pts.append(self.tissue.samples.points)
        p = np.concatenate(pts)
        return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))

    @cached_property
    def force_scale(self) -> float:
        scales = [m.force_scale for m in self.organs]
        if self.tissue is not None:
            scales.append(self.tissue.force_scale)
        return float(max(scales))

    # -- energy ------------------------------------------------------------------------------
    def evaluate(
        self,
        c: np.ndarray,
        order: int,
        project: bool = False,
        organ_energies: Sequence[Sequence] | None = None,
        tissue_energies: Sequence = (),
    ) -> Accumulator:
        """Phi at c: every body's energies plus the coupling, over the tangent DOFs."""
        organ_energies = organ_energies or [() for _ in self.organs]
        acc = Accumulator(self.pattern, order, project)
        z = c[self.tissue_config]
        organ_parts = [list(e) for e in organ_energies]
        tissue_parts = list(tissue_energies)
        for i, a in enumerate(self.attachments):
            organ = self.organs[a.organ]
            y = a.organ_positions(organ.mesh.cells, self.organ_x(c, a.organ))
            p = a.tissue.positions(z)
            r = p - y
            acc.add_value("attachment", 0.5 * float(np.sum(a.stiffness[:, None] * r * r)))
            if order >= 1:
                organ_parts[a.organ].append(
                    OrganSide(a, organ.mesh.cells, p, self.organ_hessians[i])
                )
                tissue_parts.append(TissueSide(a, y, self.tissue.attachment_hessians[i]))
        for j, (organ, name) in enumerate(zip(self.organs, self.organ_names, strict=True)):
            part = organ.evaluate(self.organ_x(c, j), order, project, organ_parts[j])
            self._merge(acc, part, self.organ_slices[j], self.body_positions[j], name)
        if self.tissue is not None:
            zacc = self.tissue.evaluate_z(z, order, project, tissue_parts)
            part = self.tissue.assembly.to_tangent(z, zacc)
            self._merge(acc, part, self.tissue_tangent, self.body_positions[-1], "tissue")
            if order >= 2 and self.cross:
                self._add_cross(z, acc.hessian)
        return acc

    @staticmethod
    def _merge(acc: Accumulator, part: Accumulator, dofs: slice, positions, name: str) -> None:
        for term, value in part.terms.items():
            acc.add_value(f"{name}.{term}", value)
        if acc.order >= 1:
            acc.gradient[dofs] += part.gradient
        if acc.order >= 2:
            acc.hessian[positions] += part.hessian

    def _add_cross(self, z: np.ndarray, hessian: np.ndarray) -> None:
        ft = self.tissue.frame_type
        T = ft.tangent_map(z).reshape(self.tissue.n_frames, 4, 3, ft.tangent_size)
        for cross in self.cross:
            blocks = -np.einsum("pc,pcjk->pjk", cross.coefficients, T[cross.frames])
            hessian += np.bincount(cross.positions.ravel(), blocks.ravel(), hessian.size)
            hessian += np.bincount(
                cross.positions_t.ravel(), np.swapaxes(blocks, 1, 2).ravel(), hessian.size
            )
