"""Shared pieces of the isotropic laws: input checks, J, cofactor, d2J/dF2, a base class.

Shapes: F (q, d, d), d = 2 or 3. ``cofactor(F) = dJ/dF = J F^{-T}`` is (q, d, d);
``det_hessian(F)[q, i, j, k, l] = d2J / dF_ij dF_kl`` = eps_ik eps_jl (2D) or
eps_ikm eps_jln F_mn (3D); ``IDENTITY[d][i, j, k, l] = delta_ik delta_jl``.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material
from tissuesim.materials.isotropic.lame import lame_parameters
from tissuesim.validate import short

_EPS2 = np.array([[0.0, 1.0], [-1.0, 0.0]])
_EPS3 = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    _EPS3[_i, _j, _k], _EPS3[_i, _k, _j] = 1.0, -1.0
_DET_HESS_2D = np.einsum("ik,jl->ijkl", _EPS2, _EPS2)
# 3D: eps_ikm eps_jln F_mn has a single term, m = 3 - i - k, n = 3 - j - l: a signed gather.
_OTHER = (3 - np.add.outer(np.arange(3), np.arange(3))) % 3  # [i, k] -> m (any where i == k)
_I, _J, _K, _L = np.ix_(*[np.arange(3)] * 4)
_DET_HESS_3D_SIGN = _EPS3[_I, _K, _OTHER[_I, _K]] * _EPS3[_J, _L, _OTHER[_J, _L]]
_DET_HESS_3D_ROW, _DET_HESS_3D_COL = _OTHER[_I, _K], _OTHER[_J, _L]
IDENTITY = {d: np.einsum("ik,jl->ijkl", np.eye(d), np.eye(d)) for d in (2, 3)}


def check_input(F: np.ndarray, order: int) -> np.ndarray:
    """F as a float (q, d, d) array with d = 2 or 3; order must be 0, 1 or 2."""
    F = np.asarray(F, dtype=float)
    if F.ndim != 3 or F.shape[1] != F.shape[2] or F.shape[1] not in (2, 3):
        raise MaterialError(
            f"deformation gradients must have shape (q, d, d) with d = 2 or 3, got {F.shape}; "
            "pass a single F as F[None]"
        )
    if order not in (0, 1, 2):
        raise MaterialError(
            f"order must be 0 (energy), 1 (+ stress) or 2 (+ tangent), got {short(order)}"
        )
    return F


def cofactor(F: np.ndarray) -> np.ndarray:
    """dJ/dF = J F^{-T}, (q, d, d), in closed form (valid for singular F too)."""
    if F.shape[-1] == 2:
        return np.stack([np.stack([F[:, 1, 1], -F[:, 1, 0]], -1),
                         np.stack([-F[:, 0, 1], F[:, 0, 0]], -1)], 1)  # fmt: skip
    r0, r1, r2 = F[:, 0], F[:, 1], F[:, 2]
    return np.stack([np.cross(r1, r2), np.cross(r2, r0), np.cross(r0, r1)], 1)


def det(F: np.ndarray, cof: np.ndarray | None = None) -> np.ndarray:
    """J = det F, (q,), by expansion along the first row."""
    cof = cofactor(F) if cof is None else cof
    return np.einsum("qj,qj->q", F[:, 0], cof[:, 0])


def det_hessian(F: np.ndarray) -> np.ndarray:
    """d2J/dF_ij dF_kl, (q, d, d, d, d)."""
    if F.shape[-1] == 2:
        return np.broadcast_to(_DET_HESS_2D, (F.shape[0], 2, 2, 2, 2))
    return _DET_HESS_3D_SIGN * F[:, _DET_HESS_3D_ROW, _DET_HESS_3D_COL]


def outer(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(a ⊗ b)[q, i, j, k, l] = a[q, i, j] b[q, k, l]."""
    return a[:, :, :, None, None] * b[:, None, None, :, :]


def bcast(c: np.ndarray, ndim: int) -> np.ndarray:
    """Per-point scalars (q,) shaped to broadcast against (q, ...) arrays of ``ndim`` dims."""
    return c.reshape(c.shape + (1,) * (ndim - 1))


class IsotropicMaterial(Material):
    """A law with Lame parameters ``mu``, ``lam`` given as (E, nu) or (mu, lambda)."""

    def __init__(
        self,
        *,
        youngs_modulus: float | None = None,
        poisson_ratio: float | None = None,
        shear_modulus: float | None = None,
        lame_lambda: float | None = None,
    ) -> None:
        self.mu, self.lam = lame_parameters(
            youngs_modulus=youngs_modulus,
            poisson_ratio=poisson_ratio,
            shear_modulus=shear_modulus,
            lame_lambda=lame_lambda,
        )

    def __repr__(self) -> str:
        return f"{type(self).__name__}(shear_modulus={self.mu!r}, lame_lambda={self.lam!r})"
