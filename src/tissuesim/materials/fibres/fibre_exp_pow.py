"""FEBio's exponential-power fibre, ``fiber-exp-pow`` and ``fiber-exp-pow-uncoupled``
(FEBio User Manual, "Fiber with Exponential-Power Law"; ``FEFiberExpPow.cpp``,
``FEFiberExpPowUncoupled.cpp``):

    fiber_exp_pow              W = ksi / (alpha beta) (exp(alpha x^beta) - 1),  x = I4 - lam0^2
    fiber_exp_pow_uncoupled    the same on x = I4b - 1,  I4b = J^(-2/3) I4
    alpha = 0:                 W = ksi / beta x^beta

for x > 0 only: the fibre bears no compression (W = 0 for I4 <= lam0^2). Then

    dW/dI4   = ksi x^(beta - 1) exp(alpha x^beta)
    d2W/dI4^2 = ksi x^(beta - 2) ((alpha x^beta + 1) beta - 1) exp(alpha x^beta)

(FEBio's Wl and Wll; its Cauchy stress 2 Wl / J (F a) (x) (F a) is this law's P pushed
forward). Parameters as FEBio's: ``ksi`` (Pa) >= 0, ``alpha`` >= 0, ``beta`` >= 2, ``lam0``
>= 1 (the coupled law's slack stretch; the uncoupled law has none). FEBio's optional fibre
shear term ``mu`` (mu/4 (I5 - 2 I4 + 1)) is not implemented: ``mu`` other than 0 is refused.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.fibres._single_fibre import SingleFibre, exponent
from tissuesim.materials.soft_tissue._hyperelastic import parameter

__all__ = ["FiberExpPow", "FiberExpPowUncoupled"]

#: FEBio's coupled law switches its fibre on from x >= machine epsilon (its m_epsf = 1)
_EPS = float(np.finfo(float).eps)


class FiberExpPow(SingleFibre):
    """FEBio's ``fiber-exp-pow``: ksi / (alpha beta) (exp(alpha (I4 - lam0^2)^beta) - 1) along
    ``fiber`` for I4 > lam0^2, else 0; ksi in Pa."""

    name = "fiber_exp_pow"
    febio_name = "fiber-exp-pow"
    uncoupled = False

    def __init__(
        self,
        *,
        ksi: float | None = None,
        alpha: float = 0.0,
        beta: float = 2.0,
        lam0: float = 1.0,
        mu: float = 0.0,
        fiber: object = (1.0, 0.0, 0.0),
    ) -> None:
        law = self.name
        self.ksi = parameter(law, "ksi", ksi)
        self.alpha = parameter(law, "alpha", alpha, unit="")
        self.beta = exponent(law, beta)
        if self.ksi < 0.0 or self.alpha < 0.0:
            raise MaterialError(f"{law}: ksi and alpha must be >= 0, got {self.ksi!r}, "
                                f"{self.alpha!r}")  # fmt: skip
        self.lam0 = 1.0 if self.uncoupled else parameter(law, "lam0", lam0, unit="")
        if self.lam0 < 1.0:
            raise MaterialError(f"{law}: lam0 must be >= 1, got {self.lam0!r}")
        if parameter(law, "mu", mu) != 0.0:
            raise MaterialError(
                f"{law}: mu (FEBio's fibre shear term) is not supported by tissuesim; give 0"
            )
        self._set_fibre(fiber)

    def parameters(self) -> dict[str, object]:
        out: dict[str, object] = dict(ksi=self.ksi, alpha=self.alpha, beta=self.beta)
        if not self.uncoupled:
            out["lam0"] = self.lam0
        return {**out, **self._fibre_parameter()}

    def fibre(self, I4: np.ndarray, order: int) -> tuple:
        ksi, alpha, beta = self.ksi, self.alpha, self.beta
        x = I4 - self.lam0**2
        on = x >= 0.0 if self.uncoupled else x >= _EPS
        x = np.where(on, x, 0.0)
        xb = x**beta
        # a trial state stretched beyond reach overflows to an infinite energy, which the line
        # search rejects: not a warning for the user
        with np.errstate(over="ignore", invalid="ignore"):
            ex = np.exp(alpha * xb)
            f = ksi / (alpha * beta) * np.expm1(alpha * xb) if alpha > 0.0 else ksi / beta * xb
            df = ksi * x ** (beta - 1.0) * ex
            ddf = ksi * x ** (beta - 2.0) * ((alpha * xb + 1.0) * beta - 1.0) * ex
        zero = np.zeros_like(x)
        return np.where(on, f, zero), np.where(on, df, zero), np.where(on, ddf, zero)


class FiberExpPowUncoupled(FiberExpPow):
    """FEBio's ``fiber-exp-pow-uncoupled``: the same law on the isochoric I4b = J^(-2/3) I4,
    active for I4b > 1 (no lam0)."""

    name = "fiber_exp_pow_uncoupled"
    febio_name = "fiber-exp-pow-uncoupled"
    uncoupled = True
