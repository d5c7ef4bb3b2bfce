"""Where the connective tissue holds on to an organ: a stiff zero-length coupling energy.

Choice (docs/coupling.md): a penalty energy, not a constraint. At attachment points a_s on the
organ's surface (rest positions, inside or on the boundary of organ tetrahedron c_s with
barycentric coordinates b_s), the organ carries the point as y_s = sum_a b_sa x_a and the tissue
as p_s = E_s z (the frames' point map, eq. 3). The energy

    W = sum_s k_s / 2 |p_s - y_s|^2

is zero at rest (both bodies put the point at a_s), so it adds no pre-stress, and it is
quadratic in (x, z): its Hessian over (x, z) is the constant

    [ B^T K B   -B^T K E ]
    [ -E^T K B   E^T K E ]   (x) I_3,

and only the frames' tangent map T(z) (rigid frames) makes the tissue blocks vary. A penalty
keeps one energy for Newton (no saddle point, the same SPD solvers) and lets a cut simply drop
attachment points; its cost is a small gap |p - y| ~ force / k, reported in the summary.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from tissuesim.energies.accumulator import Accumulator
from tissuesim.frames.model import AttachmentSpring, Embedding

__all__ = ["Attachment", "OrganSide", "TissueSide"]


@dataclass(frozen=True, eq=False)
class Attachment:
    """Tissue tied to organ ``organ`` at ``points`` (S, 3) (rest, on the organ's surface).

    cells (S,): organ tetrahedra holding the points; barycentric (S, 4) in them;
    stiffness (S,) N/m; tissue: the points' embedding in the tissue's frames.
    ids (S,): stable numbers of the points (they survive cuts that remove others).
    organ: the FEM body's index in the system; tissue_body: the frame body's (None: the
    system's only frame body).
    """

    organ: int
    points: np.ndarray
    cells: np.ndarray
    barycentric: np.ndarray
    stiffness: np.ndarray
    tissue: Embedding
    ids: np.ndarray
    tissue_body: int | None = None

    @property
    def n(self) -> int:
        return int(self.points.shape[0])

    def organ_matrix(self, organ_cells: np.ndarray, n_vertices: int) -> sp.csr_matrix:
        """B (S, n_vertices): y = B X."""
        rows = np.repeat(np.arange(self.n), 4)
        cols = organ_cells[self.cells].ravel()
        return sp.csr_matrix((self.barycentric.ravel(), (rows, cols)), shape=(self.n, n_vertices))

    def organ_positions(self, organ_cells: np.ndarray, x: np.ndarray) -> np.ndarray:
        """y (S, 3) carried by the organ at its positions x (flat)."""
        X = x.reshape(-1, 3)
        return np.einsum("sa,sai->si", self.barycentric, X[organ_cells[self.cells]])

    def spring(self) -> AttachmentSpring:
        """The tissue side as a spring with moving targets (targets are set per evaluation)."""
        return AttachmentSpring(self.tissue, self.stiffness)


@dataclass(frozen=True, eq=False)
class OrganSide:
    """The organ's part of one attachment's energy at fixed tissue points p (S, 3).

    gradient B^T K (y - p); Hessian B^T K B (x) I_3 (constant, precomputed on the organ's
    pattern). The value is added once, by the coupled system, not here."""

    attachment: Attachment
    organ_cells: np.ndarray
    p: np.ndarray
    hessian_data: np.ndarray

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        a = self.attachment
        if acc.order >= 1:
            r = a.organ_positions(self.organ_cells, x) - self.p  # (S, 3)
            f = a.stiffness[:, None, None] * a.barycentric[:, :, None] * r[:, None, :]
            acc.gradient += np.bincount(
                (self.organ_cells[a.cells][:, :, None] * 3 + np.arange(3)).ravel(),
                weights=f.ravel(),
                minlength=acc.gradient.size,
            )
        if acc.order >= 2:
            acc.hessian += self.hessian_data

    @staticmethod
    def hessian(attachment: Attachment, pattern, organ_cells: np.ndarray) -> np.ndarray:
        """B^T K B (x) I_3 on an organ's pattern; ``organ_cells`` the organ's simplices (the
        cells of a P1 organ, the linear subdivision of a P2 one: their 4 nodes lie in one
        element, so every entry is in the pattern)."""
        b, k = attachment.barycentric, attachment.stiffness
        bb = k[:, None, None] * b[:, :, None] * b[:, None, :]  # (S, 4, 4)
        blocks = np.einsum("sab,ij->saibj", bb, np.eye(3)).reshape(-1, 12, 12)
        dofs = (organ_cells[attachment.cells][:, :, None] * 3 + np.arange(3)).reshape(-1, 12)
        rows = np.repeat(dofs, 12, axis=1)
        cols = np.tile(dofs, (1, 12))
        data = np.zeros(pattern.nnz)
        data += np.bincount(
            pattern.positions(rows, cols).ravel(), weights=blocks.ravel(), minlength=pattern.nnz
        )
        return data


@dataclass(frozen=True, eq=False)
class TissueSide:
    """The tissue's part at fixed organ points y (S, 3): gradient over z E^T K (p - y),
    Hessian E^T K E (x) I_3 (constant, ``FrameModel.attachment_hessians``)."""

    attachment: Attachment
    y: np.ndarray
    hessian_data: np.ndarray

    def accumulate(self, z: np.ndarray, acc: Accumulator) -> None:
        a = self.attachment
        if acc.order >= 1:
            r = a.tissue.positions(z) - self.y
            acc.gradient += (a.tissue.matrix.T @ (a.stiffness[:, None] * r)).ravel()
        if acc.order >= 2:
            acc.hessian += self.hessian_data
