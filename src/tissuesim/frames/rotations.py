"""Rotation vectors and matrices: the exponential and logarithm maps of SO(3), batched.

SciPy's ``Rotation`` does the maps (Rodrigues' formula, stable near 0 and pi); this file adds the
cross-product matrix, used by the frames' tangent maps.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["skew", "exp_map", "log_map"]


def skew(v: np.ndarray) -> np.ndarray:
    """[v^] with [v^] u = v x u, batched over leading axes: (..., 3) -> (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def exp_map(theta: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) of rotation vectors (n, 3)."""
    theta = np.array(theta, dtype=float).reshape(-1, 3)  # a writable copy: SciPy needs one
    return Rotation.from_rotvec(theta).as_matrix().reshape(-1, 3, 3)


def log_map(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (n, 3), |theta| <= pi, of rotation matrices (n, 3, 3)."""
    R = np.array(R, dtype=float).reshape(-1, 3, 3)
    return Rotation.from_matrix(R).as_rotvec().reshape(-1, 3)
