"""F at integration points from frame configurations (Bosman et al. eq. 8, indexing repaired).

With d = pbar_s - xbar_i the rest offset of point s from frame i, w = w_i(pbar_s) and
g = dw_i/dX at pbar_s, eq. (8) reads

    F_s = sum_i [ (x_i + R_i lbar_s^i) g^T + w R_i Rbar_i^T ] = sum_i [ (x_i + A_i d) g^T + w A_i ],

linear in the frame configuration z_i = (x_i, A_i[:, 0..2]). Seen as four virtual nodes per frame
(x_i and the three columns of A_i) it is F = sum_a z^a (G^a)^T with constant

    G^(i, x) = g,      G^(i, b) = d_b g + w e_b,   b = 0, 1, 2,

exactly the structure of P1 elements, so ``NodalKinematics`` (and its fused Numba loop) compute
energy, gradient and Hessian with respect to z. Points (integration points for mass, markers,
display surfaces) move by eq. (3), p = sum_i w (x_i + A_i d): a constant sparse matrix E with
p = E Z, Z = z reshaped (4 n, 3).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from tissuesim.frames.shape_functions import ShapeFunctions
from tissuesim.kinematics.nodal import NodalKinematics

__all__ = ["frame_kinematics", "embedding_matrix", "virtual_nodes"]


def virtual_nodes(frames: np.ndarray) -> np.ndarray:
    """(q, 4 k) virtual-node indices 4 i + (0: origin, 1..3: columns of A) of frames (q, k)."""
    return (frames[:, :, None] * 4 + np.arange(4)).reshape(frames.shape[0], -1)


def frame_kinematics(
    frame_positions: np.ndarray, points: np.ndarray, volumes: np.ndarray, shape: ShapeFunctions
) -> NodalKinematics:
    """Kinematics of integration points ``points`` (q, 3) with ``volumes`` (q,)."""
    q, k = shape.frames.shape
    w = shape.weights  # (q, k)
    g = shape.gradients  # (q, k, 3)
    d = points[:, None, :] - frame_positions[shape.frames]  # (q, k, 3)
    grads = np.empty((q, k, 4, 3))
    grads[:, :, 0] = g
    eye = np.eye(3)
    for b in range(3):
        grads[:, :, 1 + b] = d[:, :, b, None] * g + w[:, :, None] * eye[b]
    cells = virtual_nodes(shape.frames)
    return NodalKinematics(
        cells=cells,
        stencil=NodalKinematics.dof_stencil(cells, 3),
        weights=np.asarray(volumes, dtype=float),
        grads=grads.reshape(q, 4 * k, 3),
        n_nodes=4 * frame_positions.shape[0],
    )


def embedding_matrix(
    frame_positions: np.ndarray, points: np.ndarray, shape: ShapeFunctions
) -> sp.csr_matrix:
    """E (q, 4 n) with current positions p = E @ z.reshape(4 n, 3) (eq. 3)."""
    q, k = shape.frames.shape
    d = points[:, None, :] - frame_positions[shape.frames]  # (q, k, 3)
    coef = shape.weights[:, :, None] * np.concatenate([np.ones((q, k, 1)), d], axis=2)
    rows = np.repeat(np.arange(q), 4 * k)
    E = sp.csr_matrix(
        (coef.ravel(), (rows, virtual_nodes(shape.frames).ravel())),
        shape=(q, 4 * frame_positions.shape[0]),
    )
    E.sum_duplicates()  # padding entries repeat a frame with weight 0
    return E
