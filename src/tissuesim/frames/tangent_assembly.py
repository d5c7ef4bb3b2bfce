"""From energies in frame configurations z (12 per frame) to Newton's tangent DOFs q.

Energies are assembled over z on a CSR pattern of 12 x 12 frame blocks (``z_pattern``). For
rigid frames the tangent pattern has 6 x 6 blocks over the same frame pairs, and

    H_q[I, J] = T_I^T H_z[I, J] T_J  (+ K_I on the rotation block when I = J),

done for all blocks at once through precomputed positions of every block entry in both CSR data
arrays: no sparse products or pattern rebuilds per iteration. Affine frames need no transform.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.energies.accumulator import Accumulator
from tissuesim.frames.frame_types import CONFIG_SIZE, FrameType

__all__ = ["TangentAssembly", "gather"]


def gather(pattern: SparsityPattern, matrix: sp.spmatrix) -> np.ndarray:
    """Data array over ``pattern`` of a sparse matrix whose entries all lie on the pattern."""
    coo = sp.coo_matrix(matrix)
    pos = pattern.positions(coo.row, coo.col)
    return np.bincount(pos, weights=coo.data, minlength=pattern.nnz)


def block_pattern(n_frames: int, size: int, frame_stencils: list[np.ndarray]) -> SparsityPattern:
    """Pattern with full size x size blocks between frames that share a stencil row.

    Built from the (few) frame pairs, then expanded to blocks: no sort over every local entry.
    Only the first stencil (the integration points', used by the elastic energy) gets a
    scatter map; other energies add their constant Hessians through ``gather``.
    Every frame's own block is present, even for a frame no point reaches (an orphan after a
    cut), so that the block maps of ``TangentAssembly`` find all its entries."""
    n = n_frames
    keys = [np.arange(n, dtype=np.int64) * (n + 1)]
    for s in frame_stencils:
        s = np.asarray(s, dtype=np.int64)
        keys.append((s[:, :, None] * n + s[:, None, :]).ravel())
    pairs = np.unique(np.concatenate(keys))
    a = np.arange(size)
    rows = (pairs // n)[:, None, None] * size + a[:, None]
    cols = (pairs % n)[:, None, None] * size + a[None, :]
    rows, cols = np.broadcast_arrays(rows, cols)
    pattern = SparsityPattern.from_entries(n * size, rows.ravel(), cols.ravel())
    # every DOF row of frame I holds the same blocks, in order of J: the entry (I a, J b) sits
    # at indptr[I size + a] + rank(I, J) size + b, with rank the position of J among I's
    # blocks. So the scatter needs one lookup per frame pair, not per entry.
    first_of_row = np.searchsorted(pairs, (pairs // n) * n)
    rank = np.arange(pairs.size) - first_of_row
    st = np.asarray(frame_stencils[0], dtype=np.int64)  # (q, k)
    q, k = st.shape
    where = np.searchsorted(pairs, st[:, :, None] * n + st[:, None, :])  # (q, k, k)
    # positions (q, k, size, k, size): row block i, dof a, column block j, dof b
    row_start = pattern.indptr[st[:, :, None] * size + a][:, :, :, None, None]  # (q,k,size,1,1)
    col = (rank[where] * size)[:, :, None, :, None] + a[None, None, None, None, :]
    scatter = (row_start + col).reshape(q, k * size * k * size)
    return SparsityPattern(pattern.n, pattern.indptr, pattern.indices, pattern.diagonal, (scatter,))


@dataclass(frozen=True, eq=False)
class TangentAssembly:
    frame_type: FrameType
    z_pattern: SparsityPattern
    q_pattern: SparsityPattern
    pairs: np.ndarray  # (nb, 2) frame pairs of the blocks
    z_index: np.ndarray  # (nb, 12, 12) positions in z data
    q_index: np.ndarray  # (nb, t, t) positions in q data
    diagonal_blocks: np.ndarray  # block numbers with I = J, in frame order

    @classmethod
    def build(
        cls, frame_type: FrameType, n_frames: int, frame_stencils: list[np.ndarray]
    ) -> TangentAssembly:
        z_pattern = block_pattern(n_frames, CONFIG_SIZE, frame_stencils)
        t = frame_type.tangent_size
        q_pattern = z_pattern if t == CONFIG_SIZE else block_pattern(n_frames, t, frame_stencils)
        zk = z_pattern.keys()
        rows, cols = zk // z_pattern.n, zk % z_pattern.n
        first = (rows % CONFIG_SIZE == 0) & (cols % CONFIG_SIZE == 0)
        pairs = np.stack([rows[first], cols[first]], axis=1) // CONFIG_SIZE
        a = np.arange(CONFIG_SIZE)
        I, J = pairs[:, 0, None, None], pairs[:, 1, None, None]
        z_index = z_pattern.positions(
            I * CONFIG_SIZE + a[:, None], J * CONFIG_SIZE + a[None, :], keys=zk
        )
        b = np.arange(t)
        q_index = q_pattern.positions(I * t + b[:, None], J * t + b[None, :])
        diagonal_blocks = np.flatnonzero(pairs[:, 0] == pairs[:, 1])
        diagonal_blocks = diagonal_blocks[np.argsort(pairs[diagonal_blocks, 0])]
        return cls(frame_type, z_pattern, q_pattern, pairs, z_index, q_index, diagonal_blocks)

    def hessian(self, z: np.ndarray, h_z: np.ndarray, g_z: np.ndarray | None) -> np.ndarray:
        """H_q data from H_z data (and, for rigid frames, the z gradient for K)."""
        if not self.frame_type.rigid:
            return h_z
        T = self.frame_type.tangent_map(z)  # (n, 12, 6)
        blocks = h_z[self.z_index]  # (nb, 12, 12)
        TI, TJ = T[self.pairs[:, 0]], T[self.pairs[:, 1]]
        out = np.matmul(np.swapaxes(TI, 1, 2), np.matmul(blocks, TJ))  # (nb, 6, 6)
        if g_z is not None:
            out[self.diagonal_blocks, 3:, 3:] += self.frame_type.curvature(z, g_z)
        h_q = np.zeros(self.q_pattern.nnz)
        h_q[self.q_index] = out
        return h_q

    def to_tangent(self, z: np.ndarray, acc: Accumulator) -> Accumulator:
        """The accumulator of Phi over q at dq = 0, from the one over z."""
        if not self.frame_type.rigid:
            return acc
        out = Accumulator(self.q_pattern, 0, acc.project)
        out.order, out.value, out.terms = acc.order, acc.value, acc.terms
        if acc.order >= 1:
            out.gradient = self.frame_type.tangent_gradient(z, acc.gradient)
        if acc.order >= 2:
            out.hessian = self.hessian(z, acc.hessian, acc.gradient)
        return out
