"""Holzapfel-Gasser-Ogden: two fibre families with dispersion, FEBio's uncoupled
``Holzapfel-Gasser-Ogden`` and its coupled ``HGO unconstrained``.

    holzapfel_gasser_ogden   W = c/2 (I1b - 3) + sum_{a=1,2} phi(E_a) + U(J)
                             E_a = kappa (I1b - 3) + (1 - 3 kappa) (I4b_a - 1)
                             U = k/4 (J^2 - 1 - 2 ln J)  (FEBio's default for this law:
                             pressure_model "Abaqus (GOH)"; the others as for every uncoupled law)
    hgo_unconstrained        W = c/2 (I1 - 3) - c ln J + k/4 (J^2 - 1 - 2 ln J)
                                 + sum_a phi(E_a) on I1, I4_a
    phi(E) = k1 / (2 k2) (exp(k2 E^2) - 1) for E >= 0, 0 for E < 0 (fibres bear no compression;
             k2 = 0: k1/2 E^2)

The families a_1,2 = e1 cos(gamma) +- e2 sin(gamma) lie in the plane of the local axes e1, e2:
FEBio's ``mat_axis type="vector"`` (``mat_axis_a``, ``mat_axis_d``: e1 = a/|a|,
e3 = a x d/|a x d|, e2 = e3 x e1), one pair for the body or one per element ((m, 3) arrays,
expanded to the integration points by ``bind``). kappa in [0, 1/3] is the dispersion (1/3:
isotropic), gamma in degrees. The chain rule to P and dP/dF: ``_fibres.py``.

``.mu`` = c and ``.lam`` = k - 2 c / 3 (uncoupled) or k (coupled) are the ground matrix's
small-strain moduli; the fibres stiffen the law in tension beyond them. J <= 0: energy +inf,
stress and tangent raise InvertedElementError. The tangent jumps where a family passes E = 0
(phi'' = k1 there, 0 in compression), as FEBio's does.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.fibres._fibres import FibreLaw, local_axes, planar_keys
from tissuesim.materials.soft_tissue._hyperelastic import (
    BULK_KINDS,
    PRESSURE_MODELS,
    bulk_energy,
    parameter,
    pressure_model,
)

__all__ = ["HolzapfelGasserOgden", "HGOUnconstrained"]


class HolzapfelGasserOgden(FibreLaw):
    """FEBio's (uncoupled) Holzapfel-Gasser-Ogden law: c/2 (I1b - 3) + two fibre families
    k1/(2 k2) (exp(k2 E^2) - 1), E = kappa (I1b - 3) + (1 - 3 kappa) (I4b - 1) >= 0, + U(J);
    c, k1, k in Pa, k2 and kappa dimensionless, gamma in degrees."""

    name = "holzapfel_gasser_ogden"
    febio_name = "Holzapfel-Gasser-Ogden"
    uncoupled = True

    def __init__(
        self,
        *,
        c: float | None = None,
        k1: float | None = None,
        k2: float | None = None,
        kappa: float = 0.0,
        gamma: float = 0.0,
        k: float | None = None,
        mat_axis_a: object = (1.0, 0.0, 0.0),
        mat_axis_d: object = (0.0, 1.0, 0.0),
        pressure_model: str | int = "Abaqus (GOH)",
    ) -> None:
        law = self.name
        self.c = parameter(law, "c", c, positive=True)
        self.k1 = parameter(law, "k1", k1)
        self.k2 = parameter(law, "k2", k2, unit="")
        if self.k1 < 0.0 or self.k2 < 0.0:
            raise MaterialError(f"{law}: k1 and k2 must be >= 0, got {self.k1!r} and {self.k2!r}")
        self.kappa = parameter(law, "kappa", kappa, unit="", meaning="dispersion")
        if not 0.0 <= self.kappa <= 1.0 / 3.0:
            raise MaterialError(f"{law}: kappa must be in [0, 1/3], got {self.kappa!r}")
        self.gamma = parameter(law, "gamma", gamma, unit="degrees")
        self.k = parameter(law, "k", k, positive=True, meaning="bulk modulus")
        self._axes = (mat_axis_a, mat_axis_d)
        self.planar = planar_keys(mat_axis_a=mat_axis_a, mat_axis_d=mat_axis_d)
        e1, e2 = local_axes(law, mat_axis_a, mat_axis_d)
        g = np.radians(self.gamma)
        fibres = np.stack([e1 * np.cos(g) + e2 * np.sin(g), e1 * np.cos(g) - e2 * np.sin(g)], -2)
        self.fibres = fibres.reshape(-1, 2, 3)
        self._set_bulk(pressure_model)
        self.mu = self.c
        self.lam = self.k - 2.0 * self.c / 3.0 if self.uncoupled else self.k
        self._check_moduli()

    def _set_bulk(self, model: object) -> None:
        self.bulk_kind = pressure_model(self.name, model)

    def parameters(self) -> dict[str, object]:
        out: dict[str, object] = dict(c=self.c, k1=self.k1, k2=self.k2, kappa=self.kappa)
        out.update(gamma=self.gamma, k=self.k)
        a, d = (np.asarray(v, dtype=float).tolist() for v in self._axes)
        out.update(mat_axis_a=a, mat_axis_d=d)
        if self.uncoupled:
            out["pressure_model"] = PRESSURE_MODELS[BULK_KINDS.index(self.bulk_kind)]
        return out

    def bulk(self, J: np.ndarray, lnJ: np.ndarray) -> tuple:
        return bulk_energy(self.bulk_kind, self.k, J, lnJ)

    def w(self, inv: np.ndarray, order: int) -> tuple:
        c, k1, k2, kappa = self.c, self.k1, self.k2, self.kappa
        I1, I4 = inv[:, 0], inv[:, 1:]
        E = kappa * (I1[:, None] - 3.0) + (1.0 - 3.0 * kappa) * (I4 - 1.0)  # (q, 2)
        on = E >= 0.0
        Eo = np.where(on, E, 0.0)
        # a trial state stretched beyond reach overflows to an infinite energy, which the
        # line search and the start choice reject: not a warning for the user
        with np.errstate(over="ignore"):
            ex = np.exp(k2 * Eo**2)
            phi = 0.5 * k1 * (np.expm1(k2 * Eo**2) / k2 if k2 > 0.0 else Eo**2)
        d1 = np.where(on, k1 * Eo * ex, 0.0)  # phi'(E)
        d2 = np.where(on, k1 * (1.0 + 2.0 * k2 * Eo**2) * ex, 0.0)  # phi''(E)
        w = 0.5 * c * (I1 - 3.0) + phi.sum(axis=1)
        dE = np.array([kappa, 1.0 - 3.0 * kappa])  # dE/dI1, dE/dI4 of its own family
        g = np.concatenate([(0.5 * c + kappa * d1.sum(axis=1))[:, None], dE[1] * d1], axis=1)
        h = np.zeros((inv.shape[0], 3, 3))
        if order >= 2:
            h[:, 0, 0] = kappa**2 * d2.sum(axis=1)
            h[:, 0, 1:] = h[:, 1:, 0] = kappa * dE[1] * d2
            h[:, 1, 1], h[:, 2, 2] = dE[1] ** 2 * d2[:, 0], dE[1] ** 2 * d2[:, 1]
        return w, g, h


class HGOUnconstrained(HolzapfelGasserOgden):
    """FEBio's coupled ``HGO unconstrained``: c/2 (I1 - 3) - c ln J + k/4 (J^2 - 1 - 2 ln J)
    + the two fibre families on I1 and I4."""

    name = "hgo_unconstrained"
    febio_name = "HGO unconstrained"
    uncoupled = False

    def _set_bulk(self, model: object) -> None:
        if model != "Abaqus (GOH)":
            raise MaterialError(f"{self.name} has no pressure_model (FEBio's uncoupled laws only)")
        self.bulk_kind = "goh"

    def bulk(self, J: np.ndarray, lnJ: np.ndarray) -> tuple:
        U, dU, ddU = bulk_energy("goh", self.k, J, lnJ)
        return U - self.c * lnJ, dU - self.c / J, ddU + self.c / J**2
