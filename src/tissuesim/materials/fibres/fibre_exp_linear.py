"""FEBio's exponential-linear fibre, ``fiber-exp-linear`` and ``uncoupled fiber-exp-linear``
(``FEFiberExpLinear.cpp``, ``FEUncoupledFiberExpLinear.cpp``; the fibre of trans iso
Mooney-Rivlin too). In the fibre stretch l = sqrt(I4) (uncoupled: lb = sqrt(I4b)), l dW/dl is

    0                                 l < 1 (no compression)
    c3 (exp(c4 (l - 1)) - 1)          1 <= l < lam_max
    c5 l + c6                         l >= lam_max,   c6 = c3 (exp(c4 (lam_max - 1)) - 1)
                                                           - c5 lam_max

so W = c3 exp(-c4) (Ei(c4 l) - Ei(c4)) - c3 ln l below lam_max and
c5 (l - lam_max) + c6 ln(l / lam_max) + W(lam_max) past it (Ei the exponential integral). With
c3 = 0, FEBio takes c3 = c5 / c4 exp(-c4 (lam_max - 1)) (a continuous slope), and so do these
laws. In I4: dW/dI4 = s / (2 I4), d2W/dI4^2 = (l s' - 2 s) / (4 I4^2), s = l dW/dl.
Parameters: ``c3``, ``c5`` (Pa), ``c4`` >= 0, ``lam_max`` >= 1 (FEBio's ``lambda``).
"""

from __future__ import annotations

import numpy as np
from scipy.special import expi

from tissuesim.errors import MaterialError
from tissuesim.materials.fibres._single_fibre import SingleFibre
from tissuesim.materials.soft_tissue._hyperelastic import parameter

__all__ = ["ExpLinearFibre", "FiberExpLinear", "FiberExpLinearUncoupled"]


class ExpLinearFibre:
    """The exponential-linear fibre's W(I4) and its derivatives (checked parameters)."""

    def __init__(
        self,
        law: str,
        c3: object,
        c4: object,
        c5: object,
        lam_max: object,
        continuous_slope: bool = True,
    ) -> None:
        """``continuous_slope`` False: c3 = 0 stays 0 (FEBio's coupled trans-iso Mooney-Rivlin,
        whose fibre is then slack up to lam_max and linear past it)."""
        self.c3, self.c4 = parameter(law, "c3", c3), parameter(law, "c4", c4, unit="")
        self.c5 = parameter(law, "c5", c5)
        self.lam_max = parameter(law, "lam_max", lam_max, unit="")
        if min(self.c3, self.c4, self.c5) < 0.0 or self.lam_max < 1.0:
            raise MaterialError(f"{law}: c3, c4, c5 must be >= 0 and lam_max >= 1")
        if self.c4 == 0.0 and (self.c3 > 0.0 or self.c5 > 0.0):
            raise MaterialError(f"{law}: c4 must be > 0 for a fibre with c3 or c5 > 0")
        self._c3 = self.c3
        if self.c3 == 0.0 and self.c5 > 0.0 and continuous_slope:
            self._c3 = self.c5 / self.c4 * np.exp(-self.c4 * (self.lam_max - 1.0))
        self._c6 = self._c3 * np.expm1(self.c4 * (self.lam_max - 1.0)) - self.c5 * self.lam_max
        self._wmax = self._energy_below(np.array([self.lam_max]))[0]

    def _energy_below(self, lb: np.ndarray) -> np.ndarray:
        """W for 1 <= lb <= lam_max."""
        c3, c4 = self._c3, self.c4
        if c3 == 0.0:
            return np.zeros_like(lb)
        return c3 * np.exp(-c4) * (expi(c4 * lb) - expi(c4)) - c3 * np.log(lb)

    def __call__(self, I4: np.ndarray, order: int) -> tuple:
        """(W, dW/dI4, d2W/dI4^2) at I4 (q,), zero where the fibre is shorter than at rest."""
        lb = np.sqrt(I4)
        on, past = lb >= 1.0, lb >= self.lam_max
        lbo = np.where(on, lb, 1.0)
        c3, c4, c5, c6, lm = self._c3, self.c4, self.c5, self._c6, self.lam_max
        below = np.minimum(lbo, lm)
        W = np.where(
            past, c5 * (lbo - lm) + c6 * np.log(lbo / lm) + self._wmax, self._energy_below(below)
        )
        ex = np.exp(c4 * (below - 1.0))
        s = np.where(past, c5 * lbo + c6, c3 * (ex - 1.0))  # lb dW/dlb
        ds = np.where(past, c5, c3 * c4 * ex)  # its derivative in lb
        I4o = lbo**2
        dW = np.where(on, s / (2.0 * I4o), 0.0)
        ddW = np.where(on, (lbo * ds - 2.0 * s) / (4.0 * I4o**2), 0.0) if order >= 2 else None
        return np.where(on, W, 0.0), dW, ddW


class FiberExpLinear(SingleFibre):
    """FEBio's ``fiber-exp-linear``: l dW/dl = c3 (exp(c4 (l - 1)) - 1) up to l = lam_max,
    c5 l + c6 beyond, along ``fiber``; nothing in compression. c3, c5 in Pa."""

    name = "fiber_exp_linear"
    febio_name = "fiber-exp-linear"
    uncoupled = False

    def __init__(
        self,
        *,
        c3: float = 0.0,
        c4: float = 0.0,
        c5: float = 0.0,
        lam_max: float = 1.0,
        fiber: object = (1.0, 0.0, 0.0),
    ) -> None:
        self._fibre = ExpLinearFibre(self.name, c3, c4, c5, lam_max)
        self.c3, self.c4, self.c5 = self._fibre.c3, self._fibre.c4, self._fibre.c5
        self.lam_max = self._fibre.lam_max
        self._set_fibre(fiber)

    def parameters(self) -> dict[str, object]:
        out = dict(c3=self.c3, c4=self.c4, c5=self.c5, lam_max=self.lam_max)
        return {**out, **self._fibre_parameter()}

    def fibre(self, I4: np.ndarray, order: int) -> tuple:
        W, dW, ddW = self._fibre(I4, 2)
        return W, dW, ddW


class FiberExpLinearUncoupled(FiberExpLinear):
    """FEBio's ``uncoupled fiber-exp-linear``: the same law on the isochoric stretch
    lb = J^(-1/3) l."""

    name = "fiber_exp_linear_uncoupled"
    febio_name = "uncoupled fiber-exp-linear"
    uncoupled = True
