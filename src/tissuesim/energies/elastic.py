"""Elastic energy E(x) = sum_q w_q psi(F_q(x)) for any kinematics and any material.

Gradient and Hessian by the chain rule through the kinematics' dF/dx (constant for P1):
    dE/dx = sum_q w_q (dF/dx)^T P,    d2E/dx2 = sum_q w_q (dF/dx)^T (dP/dF) (dF/dx).
With ``project`` the tangent dP/dF is clamped to positive semi-definite per point, which makes
every local Hessian PSD (w B^T A B with A PSD).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InvertedElementError
from tissuesim.kinematics.p1 import P1Kinematics
from tissuesim.materials.base import Material
from tissuesim.materials.psd import project_tangent_psd

__all__ = ["ElasticEnergy"]


@dataclass(frozen=True, eq=False)
class ElasticEnergy:
    kinematics: P1Kinematics
    material: Material
    stencil_id: int = 0

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        F = self.kinematics.deformation_gradients(x)
        try:
            response = self.material.evaluate(F, min(acc.order, 2))
        except InvertedElementError:
            acc.add_value("elastic", np.inf)  # the line search backs off from here
            return
        w = self.kinematics.weights
        with np.errstate(invalid="ignore"):
            acc.add_value("elastic", float(np.dot(w, response.energy)))
        if acc.order >= 1:
            local = self.kinematics.stress_to_gradient(response.stress)
            acc.gradient += np.bincount(
                self.kinematics.stencil.ravel(), weights=local.ravel(), minlength=acc.pattern.n
            )
        if acc.order >= 2:
            A = response.tangent
            if acc.project:
                A = project_tangent_psd(A)
            acc.pattern.accumulate(
                acc.hessian, self.stencil_id, self.kinematics.tangent_to_hessian(A)
            )

    def cell_fields(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Per-element J and energy density psi (J/m^3) at positions x."""
        F = self.kinematics.deformation_gradients(x)
        psi = self.material.evaluate(F, 0).energy
        return {"J": np.linalg.det(F), "energy_density": psi}
