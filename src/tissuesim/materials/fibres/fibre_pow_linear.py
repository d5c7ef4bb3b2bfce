"""FEBio's power-linear fibre, ``fiber-pow-linear`` and ``fiber-pow-linear-uncoupled`` (FEBio
User Manual, "Fiber-Pow-Linear"; ``FEFiberPowLinear.cpp``, ``FEFiberPowLinearUncoupled.cpp``):
a power-law toe up to the stretch lam0, then linear (E: FEBio's fibre modulus).

    W = ksi / beta (I4 - 1)^beta                                  1 <= I4 < I0 = lam0^2
    W = b (I4 - I0) - E (sqrt(I4) - lam0) + ksi / beta (I0 - 1)^beta    I4 >= I0
    W = 0                                                          I4 < 1 (no compression)
    ksi = E / (4 (beta - 1)) I0^(-3/2) (I0 - 1)^(2 - beta)
    b = ksi (I0 - 1)^(beta - 1) + E / (2 lam0)

so that W' and W'' are continuous at I0 (both W'' = E / (4 lam0^3) there). Past lam0 the
nominal stress along the fibre, 2 lambda W' = 2 b lambda - E, is linear in its stretch
lambda = sqrt(I4); in the toe it is 2 ksi lambda (lambda^2 - 1)^(beta - 1). The uncoupled law is the
same on I4b = J^(-2/3) I4. Parameters: ``E`` (Pa) > 0, ``lam0`` > 1, ``beta`` >= 2, as FEBio's;
FEBio's ``tension_only`` = 0 (the fibre in compression too) is refused.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.fibres._single_fibre import SingleFibre, exponent
from tissuesim.materials.soft_tissue._hyperelastic import parameter

__all__ = ["FiberPowLinear", "FiberPowLinearUncoupled"]


class FiberPowLinear(SingleFibre):
    """FEBio's ``fiber-pow-linear``: a power toe ksi / beta (I4 - 1)^beta up to I4 = lam0^2,
    linear in the fibre stretch with modulus E beyond; E in Pa."""

    name = "fiber_pow_linear"
    febio_name = "fiber-pow-linear"
    uncoupled = False

    def __init__(
        self,
        *,
        E: float | None = None,
        lam0: float | None = None,
        beta: float = 2.0,
        tension_only: bool | int = True,
        fiber: object = (1.0, 0.0, 0.0),
    ) -> None:
        law = self.name
        self.E = parameter(law, "E", E, positive=True, meaning="fibre modulus")
        self.lam0 = parameter(law, "lam0", lam0, unit="", meaning="toe stretch")
        if not self.lam0 > 1.0:
            raise MaterialError(f"{law}: lam0 (the toe stretch) must be > 1, got {self.lam0!r}")
        self.beta = exponent(law, beta)
        if not tension_only:
            raise MaterialError(
                f"{law}: tension_only = 0 (a fibre in compression) is not supported by tissuesim"
            )
        I0, b = self.lam0**2, self.beta
        self._ksi = self.E / 4.0 / (b - 1.0) * I0**-1.5 * (I0 - 1.0) ** (2.0 - b)
        self._b = self._ksi * (I0 - 1.0) ** (b - 1.0) + self.E / 2.0 / self.lam0
        self._set_fibre(fiber)

    def parameters(self) -> dict[str, object]:
        return dict(E=self.E, lam0=self.lam0, beta=self.beta, **self._fibre_parameter())

    def fibre(self, I4: np.ndarray, order: int) -> tuple:
        E, beta, ksi, b = self.E, self.beta, self._ksi, self._b
        I0 = self.lam0**2
        on, toe = I4 >= 1.0, I4 < I0
        x = np.where(on, I4 - 1.0, 0.0)
        s = np.sqrt(np.where(on, I4, 1.0))
        with np.errstate(over="ignore", invalid="ignore"):
            f = np.where(
                toe,
                ksi / beta * x**beta,
                b * (I4 - I0) - E * (s - self.lam0) + ksi / beta * (I0 - 1.0) ** beta,
            )
            df = np.where(toe, ksi * x ** (beta - 1.0), b - E / (2.0 * s))
            ddf = np.where(toe, ksi * (beta - 1.0) * x ** (beta - 2.0), E / (4.0 * s**3))
        zero = np.zeros_like(x)
        return np.where(on, f, zero), np.where(on, df, zero), np.where(on, ddf, zero)


class FiberPowLinearUncoupled(FiberPowLinear):
    """FEBio's ``fiber-pow-linear-uncoupled``: the same law on I4b = J^(-2/3) I4."""

    name = "fiber_pow_linear_uncoupled"
    febio_name = "fiber-pow-linear-uncoupled"
    uncoupled = True
