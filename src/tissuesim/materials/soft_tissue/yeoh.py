"""Yeoh, FEBio's uncoupled ``Yeoh`` and a coupled form (FEBio has no coupled Yeoh).

    yeoh            W = sum_{i=1..6} c_i (I1b - 3)^i + k/2 (ln J)^2,   I1b = J^(-2/3) I1
    coupled_yeoh    W = sum_{i=1..6} c_i (I1 - 3)^i - 2 c1 ln J + k/2 (ln J)^2

    w1 = sum_i i c_i (I1 - 3)^(i-1),   w11 = sum_i i (i - 1) c_i (I1 - 3)^(i-2)

The energy is FEBio's (its manual and ``FEYeoh::DevStrainEnergyDensity``). FEBio's own stress
routine uses sum_i c_i (I1b - 3)^(i-1) for w1 (without the factor i), so for c2..c6 != 0 its
stresses are not the derivative of its energy; tissuesim's are. The coupled form with only c1
is the neo_hookean law with mu = 2 c1, lam = k (its -2 c1 ln J makes the rest state
stress-free). Small strain: mu = 2 c1; lam = k - 2 mu / 3 (uncoupled), k + 8 c2 (coupled).
J <= 0: energy +inf, stress and tangent raise InvertedElementError.
Shapes: F (q, d, d) -> psi (q,), P (q, d, d), A (q, d, d, d, d); 2D is plane strain.
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.soft_tissue._hyperelastic import Derivatives, InvariantLaw, parameter

__all__ = ["Yeoh", "CoupledYeoh"]


class Yeoh(InvariantLaw):
    """FEBio's (uncoupled) Yeoh: sum_{i=1..6} c_i (I1b - 3)^i + k/2 (ln J)^2, in Pa."""

    name = "yeoh"
    febio_name = "Yeoh"
    uncoupled = True
    uses_i2 = False

    def __init__(
        self,
        *,
        c1: float | None = None,
        c2: float = 0.0,
        c3: float = 0.0,
        c4: float = 0.0,
        c5: float = 0.0,
        c6: float = 0.0,
        k: float | None = None,
        pressure_model: str | int = "default",
    ) -> None:
        given = dict(c1=c1, c2=c2, c3=c3, c4=c4, c5=c5, c6=c6)
        self.c = [parameter(self.name, key, value) for key, value in given.items()]
        while len(self.c) > 1 and self.c[-1] == 0.0:
            self.c.pop()  # trailing zero terms cost nothing
        k = parameter(self.name, "k", k, positive=True, meaning="bulk modulus")
        self._set_moduli(k, pressure_model)

    def parameters(self) -> dict[str, object]:
        out: dict[str, object] = {f"c{i + 1}": c for i, c in enumerate(self.c)}
        out["k"] = self.k
        return {**out, **self._bulk_parameter()}

    def w(self, I1: np.ndarray, I2: np.ndarray, order: int) -> Derivatives:
        x = I1 - 3.0
        w = np.zeros_like(x)
        w1 = np.zeros_like(x)
        w11 = np.zeros_like(x)
        for i in range(len(self.c), 0, -1):  # Horner over the (at most 6) terms, not points
            c = self.c[i - 1]
            w = (w + c) * x
            if order >= 1:
                w1 = w1 * x + i * c
            if order >= 2 and i >= 2:
                w11 = w11 * x + i * (i - 1) * c
        return Derivatives(w, w1, 0.0, w11)


class CoupledYeoh(Yeoh):
    """Coupled Yeoh: sum_{i=1..6} c_i (I1 - 3)^i - 2 c1 ln J + k/2 (ln J)^2, in Pa."""

    name = "coupled_yeoh"
    febio_name = ""
    uncoupled = False
