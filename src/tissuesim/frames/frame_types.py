"""Frame types: what a frame's DOFs are and how a step moves it.

Every frame is stored the same way, as 12 numbers z_i = (x_i, A_i[:, 0], A_i[:, 1], A_i[:, 2]):
its origin x_i and a linear map A_i that carries rest offsets to current ones. Points move by
(Bosman et al. eq. 3, with lbar = Rbar^T (pbar - xbar))

    p = sum_i w_i (x_i + R_i lbar_i) = sum_i w_i (x_i + A_i (pbar - xbar_i)),  A_i = R_i Rbar_i^T,

which is linear in z. The two types differ only in their tangent space, the DOFs Newton and the
integrators work on:

rigid  (6 DOF, the document's frames): dq_i = (dx_i, dtheta_i); a step updates x_i <- x_i + dx_i
       and A_i <- exp(dtheta_i^) A_i (multiplicative, so rotations of any size stay exact; R_i is
       A_i Rbar_i). dz = T(z) dq with dA[:, b] = dtheta x A[:, b] = -[A[:, b]^] dtheta.
affine (12 DOF, Gilles et al. 2011): dq_i = dz_i; a step adds. A_i is any matrix, so frames can
       stretch and shear and an affine field is reproduced exactly.

For an energy Phi(z), the rigid tangent gradient and Hessian at dq = 0 are

    g_q = T^T g_z,     H_q = T^T H_z T + K,
    K_i = sym(M_i) - tr(M_i) I (rotation block),  M_i = sum_b (dPhi/dA_i[:, b]) A_i[:, b]^T,

K from the second derivative of exp at 0, 1/2 (E_k E_l + E_l E_k) A (E_k = [e_k^]). It is the
"geometric stiffness" of the rotation parametrisation; the Green-Lagrange part of Bosman et al.'s
missing geometric stiffness is already inside dP/dF of the material. Newton with this exact
Hessian in the chart at the current point converges quadratically (Riemannian Newton with the
exponential retraction).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError
from tissuesim.frames.rotations import exp_map, log_map, skew
from tissuesim.validate import short

__all__ = ["FrameType", "RIGID", "AFFINE", "FRAME_TYPES", "frame_type"]

CONFIG_SIZE = 12  # x (3) and the three columns of A (3 x 3)


@dataclass(frozen=True)
class FrameType:
    """One kind of frame: ``name``, ``tangent_size`` DOFs per frame."""

    name: str
    tangent_size: int

    @property
    def rigid(self) -> bool:
        return self.name == "rigid"

    # -- configurations ---------------------------------------------------------------------
    @staticmethod
    def split(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Origins (n, 3) and linear parts A (n, 3, 3) of a flat configuration (12 n,)."""
        zz = z.reshape(-1, 4, 3)
        return zz[:, 0], np.swapaxes(zz[:, 1:], 1, 2)  # z stores the columns of A

    @staticmethod
    def join(x: np.ndarray, A: np.ndarray) -> np.ndarray:
        return np.concatenate([x[:, None, :], np.swapaxes(A, 1, 2)], axis=1).ravel()

    def retract(self, z: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """The configuration reached from z by the tangent step dq."""
        if not self.rigid:
            return z + dq
        dq = dq.reshape(-1, 6)
        x, A = self.split(z)
        return self.join(x + dq[:, :3], exp_map(dq[:, 3:]) @ A)

    def difference(self, z1: np.ndarray, z0: np.ndarray) -> np.ndarray:
        """The tangent step dq at z0 with retract(z0, dq) = z1 (rotations below pi)."""
        if not self.rigid:
            return z1 - z0
        x1, A1 = self.split(z1)
        x0, A0 = self.split(z0)
        return np.concatenate([x1 - x0, log_map(A1 @ np.swapaxes(A0, 1, 2))], axis=1).ravel()

    # -- derivatives ---------------------------------------------------------------------
    def tangent_map(self, z: np.ndarray) -> np.ndarray:
        """T (n, 12, t): dz_i = T_i dq_i."""
        n = z.size // CONFIG_SIZE
        if not self.rigid:
            return np.broadcast_to(np.eye(CONFIG_SIZE), (n, CONFIG_SIZE, CONFIG_SIZE))
        _, A = self.split(z)
        T = np.zeros((n, CONFIG_SIZE, 6))
        T[:, 0:3, 0:3] = np.eye(3)
        for b in range(3):
            T[:, 3 + 3 * b : 6 + 3 * b, 3:6] = -skew(A[:, :, b])
        return T

    def tangent_gradient(self, z: np.ndarray, g_z: np.ndarray) -> np.ndarray:
        """g_q = T^T g_z, flat (t n,)."""
        if not self.rigid:
            return g_z.copy()
        _, A = self.split(z)
        gx, G = self.split(g_z)  # G[:, a, b] = dPhi/dA_ab
        torque = np.cross(np.swapaxes(A, 1, 2), np.swapaxes(G, 1, 2)).sum(axis=1)
        return np.concatenate([gx, torque], axis=1).ravel()

    def curvature(self, z: np.ndarray, g_z: np.ndarray) -> np.ndarray | None:
        """K (n, 3, 3) added to each rigid frame's rotation block; None for affine frames."""
        if not self.rigid:
            return None
        _, A = self.split(z)
        _, G = self.split(g_z)
        M = G @ np.swapaxes(A, 1, 2)  # sum_b G[:, b] A[:, b]^T
        sym = 0.5 * (M + np.swapaxes(M, 1, 2))
        return sym - np.trace(M, axis1=1, axis2=2)[:, None, None] * np.eye(3)

    def centripetal(self, z: np.ndarray, v: np.ndarray) -> np.ndarray:
        """zdd - T qdd at velocity v: (0, omega x (omega x A[:, b])) for rigid frames."""
        if not self.rigid:
            return np.zeros_like(z)
        _, A = self.split(z)
        w = skew(v.reshape(-1, 6)[:, 3:])
        return self.join(np.zeros((A.shape[0], 3)), w @ w @ A)

    def spin(self, v: np.ndarray) -> np.ndarray:
        """Angular velocities (n, 3) of rigid frames (zeros for affine ones)."""
        if not self.rigid:
            return np.zeros((v.size // CONFIG_SIZE, 3))
        return v.reshape(-1, 6)[:, 3:]


RIGID = FrameType("rigid", 6)
AFFINE = FrameType("affine", 12)
FRAME_TYPES = {"rigid": RIGID, "affine": AFFINE}


def frame_type(name: str | FrameType) -> FrameType:
    if isinstance(name, FrameType):
        return name
    try:
        return FRAME_TYPES[name]
    except KeyError:
        raise InputError(
            f"frame type must be one of {sorted(FRAME_TYPES)}, not {short(name)}"
        ) from None
