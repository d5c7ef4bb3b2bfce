"""Veronda-Westmann, FEBio's uncoupled ``Veronda-Westmann`` and ``coupled Veronda-Westmann``.

    veronda_westmann            W = c1 (exp(c2 (I1b - 3)) - 1) - c1 c2 / 2 (I2b - 3)
                                    + k/2 (ln J)^2,   I1b = J^(-2/3) I1, I2b = J^(-4/3) I2
    coupled_veronda_westmann    W = c1 (exp(c2 (I1 - 3)) - 1) - c1 c2 / 2 (I2 - 3)
                                    + k/2 (ln J)^2

    w1 = c1 c2 exp(c2 (I1 - 3)),   w2 = -c1 c2 / 2,   w11 = c2 w1

w1 + 2 w2 = 0 at rest, so the coupled form needs no ln J term to be stress-free (FEBio's has
none). Small strain: mu = c1 c2; lam = k - 2 mu / 3 (uncoupled), k + 4 c1 c2^2 - 2 c1 c2
(coupled). c1 (Pa) and c2 (dimensionless) must be > 0. J <= 0: energy +inf, stress and tangent
raise InvertedElementError. Shapes: F (q, d, d) -> psi (q,), P (q, d, d), A (q, d, d, d, d).
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.soft_tissue._hyperelastic import Derivatives, InvariantLaw, parameter

__all__ = ["VerondaWestmann", "CoupledVerondaWestmann"]


class VerondaWestmann(InvariantLaw):
    """FEBio's (uncoupled) Veronda-Westmann: c1 (exp(c2 (I1b - 3)) - 1) - c1 c2/2 (I2b - 3)
    + k/2 (ln J)^2; c1, k in Pa, c2 dimensionless."""

    name = "veronda_westmann"
    febio_name = "Veronda-Westmann"
    uncoupled = True

    def __init__(
        self,
        *,
        c1: float | None = None,
        c2: float | None = None,
        k: float | None = None,
        pressure_model: str | int = "default",
    ) -> None:
        self.c1 = parameter(self.name, "c1", c1, positive=True)
        self.c2 = parameter(self.name, "c2", c2, positive=True, unit="")
        k = parameter(self.name, "k", k, positive=True, meaning="bulk modulus")
        self._set_moduli(k, pressure_model)

    def parameters(self) -> dict[str, object]:
        return {"c1": self.c1, "c2": self.c2, "k": self.k, **self._bulk_parameter()}

    def w(self, I1: np.ndarray, I2: np.ndarray, order: int) -> Derivatives:
        c1, c2 = self.c1, self.c2
        e = np.exp(c2 * (I1 - 3.0))
        w = c1 * (e - 1.0) - 0.5 * c1 * c2 * (I2 - 3.0)
        w1 = c1 * c2 * e
        return Derivatives(w, w1, -0.5 * c1 * c2, c2 * w1)


class CoupledVerondaWestmann(VerondaWestmann):
    """FEBio's coupled Veronda-Westmann: c1 (exp(c2 (I1 - 3)) - 1) - c1 c2/2 (I2 - 3)
    + k/2 (ln J)^2."""

    name = "coupled_veronda_westmann"
    febio_name = "coupled Veronda-Westmann"
    uncoupled = False
