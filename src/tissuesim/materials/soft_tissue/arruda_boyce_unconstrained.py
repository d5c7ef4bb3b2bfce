"""FEBio's ``Arruda-Boyce unconstrained`` (``FEABUnconstrained``, coupled): the eight-chain
energy through the inverse Langevin function's Taylor series, a ln J term that makes the rest
stress-free, and a bulk term,

    W = w(I1) - W10 ln J + kappa/2 (J^2 - 1 - 2 ln J),   W10 = 2 w1(3)
    w1 = dw/dI1 = ksi/6 sum_{k < n} f_k x^k,   x = I1 / (3 N)
    w = ksi N sum_{k < n} f_k / (2k + 2) (x^(k+1) - N^-(k+1))

f_k are the coefficients of the inverse Langevin function's series, L^-1(y) = sum_k f_k
y^(2k+1) = 3 y + 9/5 y^3 + 297/175 y^5 + ... (``INVERSE_LANGEVIN``: its first 30, by series
reversion of L(x) = coth x - 1/x; FEBio's table has the same numbers but for a misprint in the
fifth, 126117/67373 for 126117/67375, a relative 3e-5 in a term of order (I1/3N)^4). FEBio
writes the chain stretch alpha = sqrt(I1 / (3 N)) and beta = L^-1(alpha) truncated after
``n_term`` terms: its Kirchhoff stress 2 WI b - W10 I + kappa (J^2 - 1) I, WI = ksi N beta /
(2 sqrt(3 N I1)), is this W's. In (I1, J):

    w11 = ksi/(18 N) sum_k k f_k x^(k-1),   WJ = -W10 / J + kappa (J - 1/J),
    WJJ = W10 / J^2 + kappa (1 + 1/J^2)

Parameters: ``ksi`` (Pa) > 0, ``N`` > 0, ``n_term`` in 3..30 (FEBio's default 30), ``kappa``
(Pa) > 0. Small strain: mu = W10, lam = 2 kappa + 4 w11(3). Its mean-dilatation split
(``volumetric.py``) takes the bulk term, FEBio's "Abaqus (GOH)" form with k = 2 kappa.
J <= 0: energy +inf, stress and tangent raise InvertedElementError.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import check_input, cofactor, det
from tissuesim.materials.soft_tissue._hyperelastic import (
    HyperelasticMaterial,
    invariant_tensors,
    inverted_error,
    parameter,
)

__all__ = ["ArrudaBoyceUnconstrained", "INVERSE_LANGEVIN"]

#: the inverse Langevin function's Taylor coefficients f_k of y^(2k+1), k = 0..29
INVERSE_LANGEVIN = np.array([
    3.0,
    1.8,
    1.697142857142857,
    1.758857142857143,
    1.8718664192949908,
    1.9972456800342515,
    2.1128236517767944,
    2.2023028715016078,
    2.2529578706640487,
    2.2557674927967937,
    2.2064006684261215,
    2.10642783876864,
    1.9643613379981595,
    1.7961853288408383,
    1.6250621936173801,
    1.479948306283816,
    1.3929414196781063,
    1.3953257321212837,
    1.5124802847349257,
    1.7580618778208568,
    2.128142773840306,
    2.596240340751755,
    3.1103724388731844,
    3.5933518939552567,
    3.947436540863911,
    4.064125821316466,
    3.8393076651952023,
    3.1931100612754313,
    2.092746228934893,
    0.57546341387214
])  # fmt: skip


class ArrudaBoyceUnconstrained(HyperelasticMaterial):
    """FEBio's Arruda-Boyce unconstrained: the eight-chain w(I1) of ``n_term`` terms - W10 ln J
    + kappa/2 (J^2 - 1 - 2 ln J); ksi, kappa in Pa, N and n_term dimensionless."""

    name = "arruda_boyce_unconstrained"
    febio_name = "Arruda-Boyce unconstrained"

    def __init__(
        self,
        *,
        ksi: float | None = None,
        N: float | None = None,
        n_term: int = 30,
        kappa: float | None = None,
    ) -> None:
        law = self.name
        self.ksi = parameter(law, "ksi", ksi, positive=True)
        self.N = parameter(law, "N", N, positive=True, unit="")
        terms = parameter(law, "n_term", n_term, unit="")
        if terms != int(terms) or not 3 <= terms <= 30:
            raise MaterialError(f"{law}: n_term must be a whole number in 3..30, got {terms!r}")
        self.n_term = int(terms)
        self.kappa = parameter(law, "kappa", kappa, positive=True)
        self._f = INVERSE_LANGEVIN[: self.n_term]
        w1, w11 = self._w1(np.array([3.0]))
        self._w10 = 2.0 * float(w1[0])
        self.mu = self._w10
        self.lam = 2.0 * self.kappa + 4.0 * float(w11[0])
        self.k, self.bulk_kind = 2.0 * self.kappa, "goh"  # k/4 (J^2 - 1 - 2 ln J)
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        return {"ksi": self.ksi, "N": self.N, "n_term": self.n_term, "kappa": self.kappa}

    def _w1(self, I1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(w1, w11) at I1 (q,)."""
        x = I1 / (3.0 * self.N)
        k = np.arange(self.n_term)
        w1 = self.ksi / 6.0 * np.polynomial.polynomial.polyval(x, self._f)
        w11 = self.ksi / (18.0 * self.N) * np.polynomial.polynomial.polyval(x, (k * self._f)[1:])
        return w1, w11

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        d = F.shape[-1]
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0
        if order > 0 and not ok.all():
            raise inverted_error(self.name, J, ok)
        Js = np.where(ok, J, 1.0)
        lnJ = np.log(Js)
        I1 = np.einsum("qij,qij->q", F, F) + (3.0 - d)
        k = np.arange(self.n_term)
        coeff = self.ksi * self.N * self._f / (2.0 * k + 2.0)  # of x^(k+1)
        x, x0 = I1 / (3.0 * self.N), 1.0 / self.N
        w = x * np.polynomial.polynomial.polyval(x, coeff) - x0 * np.sum(coeff * x0**k)
        kappa, w10 = self.kappa, self._w10
        U = -w10 * lnJ + 0.5 * kappa * (Js**2 - 1.0 - 2.0 * lnJ)
        psi = np.where(ok, w + U, np.inf)
        if order == 0:
            return MaterialResponse(psi)
        w1, w11 = self._w1(I1)
        WJ = -w10 / Js + kappa * (Js - 1.0 / Js)
        if order == 1:
            P, _ = invariant_tensors(F, I1, None, cof, Js, (w1, 0.0, WJ), 1)
            return MaterialResponse(psi, P)
        WJJ = w10 / Js**2 + kappa * (1.0 + 1.0 / Js**2)
        W = (w1, 0.0, WJ, w11, 0.0, 0.0, 0.0, 0.0, WJJ)
        P, A = invariant_tensors(F, I1, None, cof, Js, W, 2)
        return MaterialResponse(psi, P, A)
