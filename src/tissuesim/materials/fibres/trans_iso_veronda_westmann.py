"""Transversely isotropic Veronda-Westmann, FEBio's uncoupled ``trans iso Veronda-Westmann``.

    W = c1 (exp(c2 (I1b - 3)) - 1) - c1 c2 / 2 (I2b - 3) + Wf(lb) + U(J),
    lb = sqrt(I4b), I4b = J^(-2/3) a . C a

FEBio's ``FETransIsoVerondaWestmann``: the Veronda-Westmann matrix (``veronda_westmann.py``) and
the same exponential-linear fibre as trans iso Mooney-Rivlin (c3, c4, c5, lam_max; tension only,
``fibre_exp_linear.py``). Invariant derivatives of the matrix:

    w1 = c1 c2 exp(c2 (I1b - 3)),   w2 = -c1 c2 / 2,   w11 = c2 w1,   w12 = w22 = 0

(w1 + 2 w2 = 0 at rest: stress-free). U(J) = k/2 (ln J)^2 (FEBio's ``pressure_model`` picks
another). ``fiber``: the reference fibre, one vector or one per element ((m, 3), expanded by
``bind``). ``.mu`` = c1 c2, ``.lam`` = k - 2 mu / 3 are the matrix's small-strain moduli.
J <= 0: energy +inf, stress and tangent raise InvertedElementError.
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.fibres._fibres import FibreLaw, planar_keys, unit_vectors
from tissuesim.materials.fibres.fibre_exp_linear import ExpLinearFibre
from tissuesim.materials.soft_tissue._hyperelastic import (
    BULK_KINDS,
    PRESSURE_MODELS,
    bulk_energy,
    parameter,
)
from tissuesim.materials.soft_tissue._hyperelastic import pressure_model as _pressure_model

__all__ = ["TransIsoVerondaWestmann"]


class TransIsoVerondaWestmann(FibreLaw):
    """FEBio's (uncoupled) trans iso Veronda-Westmann: c1 (exp(c2 (I1b - 3)) - 1)
    - c1 c2/2 (I2b - 3) + an exponential-linear fibre (c3, c4, c5, lam_max) along ``fiber``
    + U(J); c1, c3, c5, k in Pa, c2, c4 dimensionless."""

    name = "trans_iso_veronda_westmann"
    febio_name = "trans iso Veronda-Westmann"
    uncoupled = True
    uses_i2 = True

    def __init__(
        self,
        *,
        c1: float | None = None,
        c2: float | None = None,
        c3: float = 0.0,
        c4: float = 0.0,
        c5: float = 0.0,
        lam_max: float = 1.0,
        k: float | None = None,
        fiber: object = (1.0, 0.0, 0.0),
        pressure_model: str | int = "default",
    ) -> None:
        law = self.name
        self.c1 = parameter(law, "c1", c1, positive=True)
        self.c2 = parameter(law, "c2", c2, positive=True, unit="")
        self._fibre = ExpLinearFibre(law, c3, c4, c5, lam_max)
        self.c3, self.c4, self.c5 = self._fibre.c3, self._fibre.c4, self._fibre.c5
        self.lam_max = self._fibre.lam_max
        self.k = parameter(law, "k", k, positive=True, meaning="bulk modulus")
        self.fiber = unit_vectors(law, "fiber", fiber)
        self.planar = planar_keys(fiber=fiber)
        self.fibres = self.fiber.reshape(-1, 1, 3)
        self.bulk_kind = _pressure_model(law, pressure_model)
        self.mu = self.c1 * self.c2
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
        c1, c2 = self.c1, self.c2
        e = np.exp(c2 * (I1 - 3.0))
        Wf, dWf, ddWf = self._fibre(I4, order)
        w = c1 * (e - 1.0) - 0.5 * c1 * c2 * (I2 - 3.0) + Wf
        g = np.stack([c1 * c2 * e, np.full_like(I1, -0.5 * c1 * c2), dWf], 1)
        h = np.zeros((inv.shape[0], 3, 3))
        if order >= 2:
            h[:, 0, 0] = c1 * c2 * c2 * e
            h[:, 2, 2] = ddWf
        return w, g, h
