"""Projection of batched symmetric matrices onto the positive semidefinite cone.

    project_psd(A)            A (q, n, n): sym(A) = V diag(w) V^T -> V diag(max(w, 0)) V^T
    project_tangent_psd(T)    T (q, d, d, d, d) viewed as (q, d*d, d*d), projected, reshaped back

Used to make element Hessians of non-convex laws (inverted or compressed) safe for Newton.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import InputError

__all__ = ["project_psd", "project_tangent_psd"]


def project_psd(A: np.ndarray) -> np.ndarray:
    """Symmetrise each (n, n) block and clamp its negative eigenvalues to 0; (q, n, n).

    Blocks whose symmetric part has no negative eigenvalue are returned as that symmetric part
    exactly (no eigendecomposition round-off).
    """
    A = np.asarray(A, dtype=float)
    if A.ndim != 3 or A.shape[1] != A.shape[2]:
        raise InputError(f"project_psd expects shape (q, n, n), got {A.shape}")
    sym = 0.5 * (A + np.swapaxes(A, 1, 2))
    w, V = np.linalg.eigh(sym)
    clamped = (V * np.maximum(w, 0.0)[:, None, :]) @ np.swapaxes(V, 1, 2)
    return np.where((w >= 0.0).all(axis=1)[:, None, None], sym, clamped)


def project_tangent_psd(tangent: np.ndarray) -> np.ndarray:
    """PSD projection of dP/dF as a (d*d, d*d) matrix per point; (q, d, d, d, d)."""
    tangent = np.asarray(tangent, dtype=float)
    if tangent.ndim != 5 or len(set(tangent.shape[1:])) != 1:
        raise InputError(f"project_tangent_psd expects shape (q, d, d, d, d), got {tangent.shape}")
    q, d = tangent.shape[:2]
    return project_psd(tangent.reshape(q, d * d, d * d)).reshape(tangent.shape)
