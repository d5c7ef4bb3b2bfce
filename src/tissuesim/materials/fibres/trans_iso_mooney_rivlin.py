"""Transversely isotropic Mooney-Rivlin, FEBio's uncoupled ``trans iso Mooney-Rivlin``.

    W = c1 (I1b - 3) + c2 (I2b - 3) + Wf(lb) + U(J),   lb = sqrt(I4b), I4b = J^(-2/3) a . C a

The fibre (FEBio's ``FEFiberExpLinearUC``, ``fibre_exp_linear.py``) bears tension only; its
lb dWf/dlb is

    0                                 lb < 1
    c3 (exp(c4 (lb - 1)) - 1)         1 <= lb < lam_max
    c5 lb + c6                        lb >= lam_max,   c6 = c3 (exp(c4 (lam_max - 1)) - 1)
                                                             - c5 lam_max
so Wf = c3 exp(-c4) (Ei(c4 lb) - Ei(c4)) - c3 ln lb below lam_max, and past it
c5 (lb - lam_max) + c6 ln(lb / lam_max) + Wf(lam_max) (Ei the exponential integral). With
c3 = 0, FEBio takes c3 = c5 / c4 exp(-c4 (lam_max - 1)) (a continuous slope), and so does this
law. In the invariant I4b: dWf/dI4b = s / (2 I4b), d2Wf/dI4b2 = (lb s' - 2 s) / (4 I4b^2),
s = lb dWf/dlb. U(J) = k/2 (ln J)^2 (FEBio's ``pressure_model`` picks another).

``fiber``: the reference fibre direction, one vector or one per element ((m, 3), expanded by
``bind``). ``.mu`` = 2 (c1 + c2), ``.lam`` = k - 2 mu / 3 are the matrix's small-strain moduli.
J <= 0: energy +inf, stress and tangent raise InvertedElementError.

``coupled_trans_iso_mooney_rivlin`` is FEBio's ``coupled trans-iso Mooney-Rivlin``
(``FECoupledTransIsoMooneyRivlin``): the same on I1, I2 and the fibre stretch l = sqrt(I4),

    W = c1 (I1 - 3) + c2 (I2 - 3) - 2 (c1 + 2 c2) ln J + Wf(l) + k/2 (ln J)^2

with the same fibre except that c3 = 0 stays 0 (FEBio's coupled law: slack up to lam_max, then
l dWf/dl = c5 (l - lam_max)). ``.mu`` = 2 (c1 + c2), ``.lam`` = k + 4 c2.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.fibres._fibres import FibreLaw, planar_keys, unit_vectors
from tissuesim.materials.fibres.fibre_exp_linear import ExpLinearFibre
from tissuesim.materials.soft_tissue._hyperelastic import (
    BULK_KINDS,
    PRESSURE_MODELS,
    bulk_energy,
    parameter,
)
from tissuesim.materials.soft_tissue._hyperelastic import pressure_model as _pressure_model

__all__ = ["TransIsoMooneyRivlin", "CoupledTransIsoMooneyRivlin"]


class TransIsoMooneyRivlin(FibreLaw):
    """FEBio's (uncoupled) trans iso Mooney-Rivlin: c1 (I1b - 3) + c2 (I2b - 3) + an
    exponential-linear fibre (c3, c4, c5, lam_max) along ``fiber`` + U(J); c1, c2, c3, c5, k
    in Pa."""

    name = "trans_iso_mooney_rivlin"
    febio_name = "trans iso Mooney-Rivlin"
    uncoupled = True
    uses_i2 = True

    def __init__(
        self,
        *,
        c1: float | None = None,
        c2: float = 0.0,
        c3: float = 0.0,
        c4: float = 0.0,
        c5: float = 0.0,
        lam_max: float = 1.0,
        k: float | None = None,
        fiber: object = (1.0, 0.0, 0.0),
        pressure_model: str | int = "default",
    ) -> None:
        law = self.name
        self.c1, self.c2 = parameter(law, "c1", c1), parameter(law, "c2", c2)
        self._fibre = ExpLinearFibre(law, c3, c4, c5, lam_max)
        self.c3, self.c4, self.c5 = self._fibre.c3, self._fibre.c4, self._fibre.c5
        self.lam_max = self._fibre.lam_max
        self.k = parameter(law, "k", k, positive=True, meaning="bulk modulus")
        self.fiber = unit_vectors(law, "fiber", fiber)
        self.planar = planar_keys(fiber=fiber)
        self.fibres = self.fiber.reshape(-1, 1, 3)
        self.bulk_kind = _pressure_model(law, pressure_model)
        self.mu = 2.0 * (self.c1 + self.c2)
        self.lam = self.k - 2.0 * self.mu / 3.0
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        out: dict[str, object] = dict(c1=self.c1, c2=self.c2, c3=self.c3, c4=self.c4)
        out.update(c5=self.c5, lam_max=self.lam_max, k=self.k, fiber=self.fiber.tolist())
        out["pressure_model"] = PRESSURE_MODELS[BULK_KINDS.index(self.bulk_kind)]
        return out

    def bulk(self, J: np.ndarray, lnJ: np.ndarray) -> tuple:
        return bulk_energy(self.bulk_kind, self.k, J, lnJ)

    def w(self, inv: np.ndarray, order: int) -> tuple:
        I1, I2, I4 = inv[:, 0], inv[:, 1], inv[:, 2]
        Wf, dWf, ddWf = self._fibre(I4, order)
        w = self.c1 * (I1 - 3.0) + self.c2 * (I2 - 3.0) + Wf
        g = np.stack([np.full_like(I1, self.c1), np.full_like(I1, self.c2), dWf], 1)
        h = np.zeros((inv.shape[0], 3, 3))
        if order >= 2:
            h[:, 2, 2] = ddWf
        return w, g, h


class CoupledTransIsoMooneyRivlin(TransIsoMooneyRivlin):
    """FEBio's coupled trans-iso Mooney-Rivlin: c1 (I1 - 3) + c2 (I2 - 3) - 2 (c1 + 2 c2) ln J
    + an exponential-linear fibre on l = sqrt(I4) + k/2 (ln J)^2; c1 > 0, c2, c3, c5, k in Pa."""

    name = "coupled_trans_iso_mooney_rivlin"
    febio_name = "coupled trans-iso Mooney-Rivlin"
    uncoupled = False

    def __init__(
        self,
        *,
        c1: float | None = None,
        c2: float = 0.0,
        c3: float = 0.0,
        c4: float = 0.0,
        c5: float = 0.0,
        lam_max: float = 1.0,
        k: float | None = None,
        fiber: object = (1.0, 0.0, 0.0),
    ) -> None:
        super().__init__(c1=c1, c2=c2, c3=c3, c4=c4, c5=c5, lam_max=lam_max, k=k, fiber=fiber)
        if not self.c1 > 0.0:
            raise MaterialError(f"{self.name}: c1 must be > 0 Pa, got {self.c1!r}")
        self._fibre = ExpLinearFibre(self.name, c3, c4, c5, lam_max, continuous_slope=False)
        self.lam = self.k + 4.0 * self.c2
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        out = super().parameters()
        del out["pressure_model"]
        return out

    def bulk(self, J: np.ndarray, lnJ: np.ndarray) -> tuple:
        a = 2.0 * (self.c1 + 2.0 * self.c2)
        U = -a * lnJ + 0.5 * self.k * lnJ**2
        return U, (self.k * lnJ - a) / J, (self.k * (1.0 - lnJ) + a) / J**2
