"""Mooney-Rivlin, FEBio's uncoupled ``Mooney-Rivlin`` and ``coupled Mooney-Rivlin``.

    mooney_rivlin           W = c1 (I1b - 3) + c2 (I2b - 3) + k/2 (ln J)^2
                            I1b = J^(-2/3) I1, I2b = J^(-4/3) I2 (isochoric invariants)
    coupled_mooney_rivlin   W = c1 (I1 - 3) + c2 (I2 - 3) - 2 (c1 + 2 c2) ln J + k/2 (ln J)^2

Derivatives: w1 = c1, w2 = c2, second derivatives 0 (the tensors: ``_hyperelastic.py``).
Small strain: mu = 2 (c1 + c2); lam = k - 2 mu / 3 (uncoupled), k + 4 c2 (coupled).
J <= 0: energy +inf, stress and tangent raise InvertedElementError (ln J is undefined).
Shapes: F (q, d, d) -> psi (q,), P (q, d, d), A (q, d, d, d, d); 2D is plane strain.
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.soft_tissue._hyperelastic import Derivatives, InvariantLaw, parameter

__all__ = ["MooneyRivlin", "CoupledMooneyRivlin"]


class MooneyRivlin(InvariantLaw):
    """FEBio's (uncoupled) Mooney-Rivlin: c1 (I1b - 3) + c2 (I2b - 3) + k/2 (ln J)^2, in Pa
    (FEBio's ``pressure_model`` picks another bulk term U(J)).

    ``c2 = 0`` is the uncoupled neo-Hookean with shear modulus 2 c1."""

    name = "mooney_rivlin"
    febio_name = "Mooney-Rivlin"
    uncoupled = True

    def __init__(
        self,
        *,
        c1: float | None = None,
        c2: float = 0.0,
        k: float | None = None,
        pressure_model: str | int = "default",
    ) -> None:
        self.c1 = parameter(self.name, "c1", c1)
        self.c2 = parameter(self.name, "c2", c2)
        k = parameter(self.name, "k", k, positive=True, meaning="bulk modulus")
        self.uses_i2 = self.c2 != 0.0  # c2 = 0: skip the second invariant
        self._set_moduli(k, pressure_model)

    def parameters(self) -> dict[str, object]:
        return {"c1": self.c1, "c2": self.c2, "k": self.k, **self._bulk_parameter()}

    def w(self, I1: np.ndarray, I2: np.ndarray, order: int) -> Derivatives:
        return Derivatives(self.c1 * (I1 - 3.0) + self.c2 * (I2 - 3.0), self.c1, self.c2)


class CoupledMooneyRivlin(MooneyRivlin):
    """FEBio's coupled Mooney-Rivlin: c1 (I1 - 3) + c2 (I2 - 3) - 2 (c1 + 2 c2) ln J
    + k/2 (ln J)^2, in Pa (c1 > 0 as in FEBio)."""

    name = "coupled_mooney_rivlin"
    febio_name = "coupled Mooney-Rivlin"
    uncoupled = False

    def __init__(self, *, c1: float | None = None, c2: float = 0.0, k: float | None = None) -> None:
        parameter(self.name, "c1", c1, positive=True)
        super().__init__(c1=c1, c2=c2, k=k)
