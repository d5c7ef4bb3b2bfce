"""Arruda-Boyce, FEBio's uncoupled ``Arruda-Boyce`` and a coupled form.

    arruda_boyce            W = mu sum_{i=1..5} a_i (I1b^i - 3^i) / N^(i-1) + k/2 (ln J)^2
    coupled_arruda_boyce    W = mu sum_{i=1..5} a_i (I1^i - 3^i) / N^(i-1) - 2 w1(3) ln J
                                + k/2 (ln J)^2

    a = (1/2, 1/10, 11/350, 19/1750, 519/134750)   (FEBio's ``FEArrudaBoyce``)
    w1 = mu sum_i i a_i (I1/N)^(i-1),   w11 = mu / N sum_i i (i - 1) a_i (I1/N)^(i-2)

N (FEBio's "links", lambda_m^2 of the classic form) and mu ("initial modulus") are FEBio's
parameters. FEBio's a_i are i times the classic series (1/2, 1/20, 11/1050, 19/7000,
519/673750); they are kept so that a FEBio model means the same thing here. The small-strain
shear modulus is therefore ``.mu`` = 2 w1(3) = mu (1 + 6/(5N) + 297/(175 N^2) + ...), not the
parameter mu (equal as N -> infinity). The coupled form is not FEBio's "Arruda-Boyce
unconstrained" (a different, inverse-Langevin law); its -2 w1(3) ln J term makes the rest state
stress-free. lam = k - 2 .mu / 3 (uncoupled), k + 4 w11(3) (coupled).
J <= 0: energy +inf, stress and tangent raise InvertedElementError.
Shapes: F (q, d, d) -> psi (q,), P (q, d, d), A (q, d, d, d, d); 2D is plane strain.
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.soft_tissue._hyperelastic import Derivatives, InvariantLaw, parameter

__all__ = ["ArrudaBoyce", "CoupledArrudaBoyce"]

#: FEBio's coefficients a_1..a_5
COEFFICIENTS = (0.5, 0.1, 11.0 / 350.0, 19.0 / 1750.0, 519.0 / 134750.0)


class ArrudaBoyce(InvariantLaw):
    """FEBio's (uncoupled) Arruda-Boyce: mu sum_i a_i (I1b^i - 3^i) / N^(i-1) + k/2 (ln J)^2;
    mu and k in Pa, N > 0 dimensionless. ``.mu`` is the small-strain shear modulus 2 w1(3)."""

    name = "arruda_boyce"
    febio_name = "Arruda-Boyce"
    uncoupled = True
    uses_i2 = False

    def __init__(
        self,
        *,
        mu: float | None = None,
        N: float | None = None,
        k: float | None = None,
        pressure_model: str | int = "default",
    ) -> None:
        self.initial_modulus = parameter(self.name, "mu", mu, positive=True)
        self.N = parameter(self.name, "N", N, positive=True, unit="", meaning="links")
        k = parameter(self.name, "k", k, positive=True, meaning="bulk modulus")
        self._set_moduli(k, pressure_model)

    def parameters(self) -> dict[str, object]:
        return {"mu": self.initial_modulus, "N": self.N, "k": self.k, **self._bulk_parameter()}

    def w(self, I1: np.ndarray, I2: np.ndarray, order: int) -> Derivatives:
        m, N = self.initial_modulus, self.N
        f = I1 / N
        # I1^i - 3^i = (I1 - 3) sum_{j<i} I1^j 3^(i-1-j): no cancellation near the rest state
        geometric = np.zeros_like(I1)
        w = np.zeros_like(I1)
        w1 = np.zeros_like(I1)
        w11 = np.zeros_like(I1)
        for i, a in enumerate(COEFFICIENTS, start=1):  # five terms, not a loop over points
            geometric = geometric * 3.0 + I1 ** (i - 1)
            w = w + a * geometric / N ** (i - 1)
        for i in range(5, 0, -1):  # Horner in f = I1 / N
            a = COEFFICIENTS[i - 1]
            w1 = w1 * f + i * a
            if i >= 2:
                w11 = w11 * f + i * (i - 1) * a
        w = w * (I1 - 3.0)
        return Derivatives(m * w, m * w1, 0.0, m * w11 / N)


class CoupledArrudaBoyce(ArrudaBoyce):
    """Coupled Arruda-Boyce: mu sum_i a_i (I1^i - 3^i) / N^(i-1) - 2 w1(3) ln J
    + k/2 (ln J)^2."""

    name = "coupled_arruda_boyce"
    febio_name = ""
    uncoupled = False
