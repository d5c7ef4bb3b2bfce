"""Strain and stress measures written for every body: the same names, shapes and units for FEM
elements (per cell) and meshless integration points (per point).

    J               det F                                   (q,)
    green_strain    E = (F^T F - I) / 2                     (q, 3, 3)
    cauchy_stress   sigma = P F^T / J                        (q, 3, 3) Pa
    von_mises       sqrt(3/2 s:s), s = sigma - tr(sigma)/3 I (q,)     Pa
    energy_density  psi(F) per unit rest volume             (q,)     J/m^3

Tensors are always 3 x 3 so ParaView shows them as tensors. A 2D body is in plane strain
(F_33 = 1): every law of the project is the restriction of its 3D form, so the 3D law at
F3 = [[F, 0], [0, 1]] gives the in-plane stress and the out-of-plane sigma_zz the plane-strain
constraint carries. Where the law has no stress (J <= 0 for the log-based laws) or J = 0, the
stresses are NaN: ParaView shows such cells as "nan", nothing is made up.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import InvertedElementError
from tissuesim.materials.base import Material

__all__ = ["FIELD_NAMES", "continuum_fields", "von_mises", "embed_3d"]

#: the per-cell / per-point fields every body writes, in this order
FIELD_NAMES = ("J", "green_strain", "cauchy_stress", "von_mises", "energy_density")


def embed_3d(F: np.ndarray) -> np.ndarray:
    """(q, d, d) -> (q, 3, 3); a 2D F gets F_33 = 1 (plane strain)."""
    F = np.asarray(F, dtype=float)
    d = F.shape[-1]
    if d == 3:
        return F
    F3 = np.zeros((F.shape[0], 3, 3))
    F3[:, :d, :d] = F
    F3[:, 2, 2] = 1.0
    return F3


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """Von Mises equivalent stress of (q, 3, 3) Cauchy stresses (q,), Pa."""
    s = sigma - np.trace(sigma, axis1=1, axis2=2)[:, None, None] * np.eye(3) / 3.0
    return np.sqrt(1.5 * np.einsum("qij,qij->q", s, s))


def _stress_where(material: Material, F3: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """P at every point, the points not ``ok`` evaluated at rest instead: the batch keeps its
    length, so a law with data per point (fibre directions) stays aligned."""
    return material.evaluate(np.where(ok[:, None, None], F3, np.eye(3)), 1).stress


def continuum_fields(material: Material, F: np.ndarray) -> dict[str, np.ndarray]:
    """The fields of ``FIELD_NAMES`` at deformation gradients F (q, d, d), d = 2 or 3."""
    F3 = embed_3d(F)
    q = F3.shape[0]
    J = np.linalg.det(F3)
    eye = np.eye(3)
    green = 0.5 * (np.swapaxes(F3, 1, 2) @ F3 - eye)
    sigma = np.full((q, 3, 3), np.nan)
    ok = np.isfinite(J) & (J != 0.0)
    psi = material.evaluate(F3, 0).energy if q else np.zeros(0)
    if ok.any():
        try:
            P = _stress_where(material, F3, ok)
        except InvertedElementError:
            ok &= J > 0.0  # the law has no stress at J <= 0
            P = _stress_where(material, F3, ok) if ok.any() else None
        if P is not None:
            sigma[ok] = (P @ np.swapaxes(F3, 1, 2))[ok] / J[ok, None, None]
    return {
        "J": J,
        "green_strain": green,
        "cauchy_stress": sigma,
        "von_mises": von_mises(sigma),
        "energy_density": psi,
    }
