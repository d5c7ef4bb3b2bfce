"""Holmes-Mow, FEBio's ``Holmes-Mow`` (coupled) and ``uncoupled Holmes-Mow``.

    holmes_mow            W = Ha / (4 beta) (exp(Q) - 1),
                          Q = beta / Ha ((2 mu - lam)(I1 - 3) + lam (I2 - 3)) - beta ln I3
    uncoupled_holmes_mow  W = mu / (2 beta) (exp(beta (I1b - 3)) - 1) + U(J)

with (coupled) mu = E / (2 (1 + v)), lam = E v / ((1 + v)(1 - 2 v)), Ha = lam + 2 mu and
I3 = J^2, so ln I3 = 2 ln J: FEBio's ``FEHolmesMow`` (its E, v, beta) and ``FEHolmesMowUC``
(mu, beta, k; U = k/2 (ln J)^2 or FEBio's ``pressure_model``). In (I1, I2, J), with
Q1 = beta (2 mu - lam) / Ha, Q2 = beta lam / Ha, QJ = -2 beta / J, QJJ = 2 beta / J^2:

    W_a = Ha / (4 beta) exp(Q) Q_a,   W_ab = Ha / (4 beta) exp(Q) (Q_a Q_b + Q_ab)

The coupled law is stress-free at rest (Q1 + 2 Q2 + QJ = 0 there) and at small strain is Hooke's
law with mu, lam; its volumetric part does not split off (mean dilatation keeps it whole: U = 0).
The uncoupled one is ``InvariantLaw`` with w1 = mu/2 exp(beta (I1b - 3)), w11 = beta w1.
beta > 0 (FEBio allows 0, where W is the limit; not taken here). J <= 0: energy +inf, stress and
tangent raise InvertedElementError.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import check_input, cofactor, det
from tissuesim.materials.soft_tissue._hyperelastic import (
    Derivatives,
    HyperelasticMaterial,
    InvariantLaw,
    invariant_tensors,
    inverted_error,
    parameter,
)

__all__ = ["HolmesMow", "UncoupledHolmesMow"]


class HolmesMow(HyperelasticMaterial):
    """FEBio's (coupled) Holmes-Mow: Ha / (4 beta) (exp(Q) - 1); E (Pa), v, beta."""

    name = "holmes_mow"
    febio_name = "Holmes-Mow"
    #: no bulk term of its own (``volumetric.py``: U = 0)
    k = 0.0
    bulk_kind = "log"

    def __init__(
        self, *, E: float | None = None, v: float | None = None, beta: float | None = None
    ):
        law = self.name
        self.E = parameter(law, "E", E, positive=True)
        self.v = parameter(law, "v", v, unit="")
        if not -1.0 < self.v < 0.5:
            raise MaterialError(f"{law}: v must be in (-1, 0.5), got {self.v!r}")
        self.beta = parameter(law, "beta", beta, positive=True, unit="")
        self.mu = 0.5 * self.E / (1.0 + self.v)
        self.lam = self.v * self.E / ((1.0 + self.v) * (1.0 - 2.0 * self.v))
        self._ha = self.lam + 2.0 * self.mu
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        return {"E": self.E, "v": self.v, "beta": self.beta}

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        d = F.shape[-1]
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0
        if order > 0 and not ok.all():
            raise inverted_error(self.name, J, ok)
        Js = np.where(ok, J, 1.0)
        extra = 3.0 - d  # plane strain's unit out-of-plane stretch
        I1 = np.einsum("qij,qij->q", F, F) + extra
        C = np.einsum("qki,qkj->qij", F, F)
        I2 = 0.5 * (I1**2 - np.einsum("qij,qij->q", C, C) - extra)
        b, ha = self.beta, self._ha
        q1, q2 = b * (2.0 * self.mu - self.lam) / ha, b * self.lam / ha
        Q = q1 * (I1 - 3.0) + q2 * (I2 - 3.0) - 2.0 * b * np.log(Js)
        s = ha / (4.0 * b) * np.exp(Q)  # Ha / (4 beta) exp(Q)
        psi = np.where(ok, s - ha / (4.0 * b), np.inf)
        if order == 0:
            return MaterialResponse(psi)
        qJ = -2.0 * b / Js
        W = (s * q1, s * q2, s * qJ)
        if order == 1:
            P, _ = invariant_tensors(F, I1, C, cof, Js, W, 1)
            return MaterialResponse(psi, P)
        W2 = (s * q1 * q1, s * q1 * q2, s * q2 * q2, s * q1 * qJ, s * q2 * qJ)
        WJJ = s * (qJ * qJ + 2.0 * b / Js**2)
        P, A = invariant_tensors(F, I1, C, cof, Js, W + W2 + (WJJ,), 2)
        return MaterialResponse(psi, P, A)


class UncoupledHolmesMow(InvariantLaw):
    """FEBio's uncoupled Holmes-Mow: mu / (2 beta) (exp(beta (I1b - 3)) - 1) + U(J); mu, k in
    Pa, beta dimensionless."""

    name = "uncoupled_holmes_mow"
    febio_name = "uncoupled Holmes-Mow"
    uncoupled = True
    uses_i2 = False

    def __init__(
        self,
        *,
        mu: float | None = None,
        beta: float | None = None,
        k: float | None = None,
        pressure_model: str | int = "default",
    ) -> None:
        self.shear = parameter(self.name, "mu", mu, positive=True)
        self.beta = parameter(self.name, "beta", beta, positive=True, unit="")
        k = parameter(self.name, "k", k, positive=True, meaning="bulk modulus")
        self._set_moduli(k, pressure_model)

    def parameters(self) -> dict[str, object]:
        return {"mu": self.shear, "beta": self.beta, "k": self.k, **self._bulk_parameter()}

    def w(self, I1: np.ndarray, I2: np.ndarray, order: int) -> Derivatives:
        e = np.exp(self.beta * (I1 - 3.0))
        w1 = 0.5 * self.shear * e
        return Derivatives(self.shear / (2.0 * self.beta) * (e - 1.0), w1, 0.0, self.beta * w1)
