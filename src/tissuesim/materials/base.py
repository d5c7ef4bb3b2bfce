"""The material interface: psi(F), P(F) and dP/dF, batched over integration points.

A material sees only deformation gradients, so it works unchanged with P1 triangles (plane
strain), P1 tetrahedra and meshless frames. Shapes:

    F        (q, d, d)          deformation gradients, d = 2 or 3
    psi      (q,)               energy density per unit rest volume (J / m^3)
    P        (q, d, d)          first Piola-Kirchhoff stress (Pa)
    dP/dF    (q, d, d, d, d)    tangent, A[q, i, j, k, l] = dP_ij / dF_kl (Pa)

In 2D every law is the plane-strain restriction of its 3D form (F_33 = 1), with the 3D Lame
parameters.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Material", "MaterialResponse"]


@dataclass(frozen=True)
class MaterialResponse:
    """What ``Material.evaluate`` returns; entries not asked for are None."""

    energy: np.ndarray  # (q,), +inf where the law is undefined (J <= 0 for log-based laws)
    stress: np.ndarray | None = None  # (q, d, d)
    tangent: np.ndarray | None = None  # (q, d, d, d, d)


class Material:
    """Base class. Subclasses implement ``evaluate``; the three accessors call it.

    ``evaluate(F, order)`` returns energy (order 0), plus stress (order >= 1), plus tangent
    (order 2), sharing intermediate results. Laws undefined for J <= 0 return +inf energy there
    and raise ``InvertedElementError`` if asked for stress or tangent there.
    """

    #: Name used in scene files and the registry.
    name: str = "material"
    #: Lame parameters in Pa, set by subclasses.
    mu: float
    lam: float

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        """The law at deformation gradients ``F`` (q, d, d): a ``MaterialResponse`` with the
        energy density psi (q,) in J/m^3, and for ``order`` >= 1 the first Piola-Kirchhoff
        stress P (q, d, d) in Pa, for ``order`` 2 also the tangent dP/dF (q, d, d, d, d) in Pa.

        ``NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3).evaluate(np.eye(3)[None], 1)``
        gives zero energy and stress at rest."""
        raise NotImplementedError

    def energy_density(self, F: np.ndarray) -> np.ndarray:
        """psi(F), (q,) in J/m^3."""
        return self.evaluate(F, 0).energy

    def stress(self, F: np.ndarray) -> np.ndarray:
        """First Piola-Kirchhoff stress P(F), (q, d, d) in Pa."""
        return self.evaluate(F, 1).stress

    def stress_derivative(self, F: np.ndarray) -> np.ndarray:
        """dP/dF, (q, d, d, d, d) in Pa."""
        return self.evaluate(F, 2).tangent
