"""FEBio's Fung laws: ``Fung orthotropic`` (uncoupled, ``FEFungOrthotropic``) and
``Fung-ortho-compressible`` (coupled, ``FEFungOrthoCompressible``):

    W = c/2 (exp(Q) - 1) + U(J),   Q = 2 W_o / c
    W_o = sum_a mu_a A_a : E^2 + 1/2 sum_ab lam_ab (A_a : E)(A_b : E)

W_o is orthotropic elastic's energy (``orthotropic_elastic.py``, the same mu_a, lam_ab from
E1..v31); the uncoupled law takes E~ = (J^(-2/3) C - I)/2 and U = k/2 (ln J)^2 (FEBio's
``pressure_model`` picks another); the compressible one E and U = k/2 (ln J)^2. In the
invariants x: dW/dx = exp(Q) dW_o/dx, d2W/dx2 = exp(Q) (d2W_o/dx2 + 2/c dW_o/dx (x) dW_o/dx).
Small strain: the orthotropic Hooke law of E1..v31 plus k on the volume (uncoupled: the
deviatoric part of it); ``.mu`` the mean of G12, G23, G31, ``.lam`` = k - 2 mu / 3.
J <= 0: energy +inf, stress and tangent raise InvertedElementError.
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.orthotropic.orthotropic_elastic import OrthotropicElastic
from tissuesim.materials.soft_tissue._hyperelastic import (
    BULK_KINDS,
    PRESSURE_MODELS,
    bulk_energy,
    parameter,
)
from tissuesim.materials.soft_tissue._hyperelastic import pressure_model as _pressure_model

__all__ = ["FungOrthotropic", "FungOrthotropicCompressible"]


class FungOrthotropic(OrthotropicElastic):
    """FEBio's (uncoupled) Fung orthotropic: c/2 (exp(Q) - 1) on E~ + U(J); E1..v31, c, k."""

    name = "fung_orthotropic"
    febio_name = "Fung orthotropic"
    uncoupled = True
    has_bulk = True

    def __init__(
        self,
        *,
        c: float | None = None,
        k: float | None = None,
        pressure_model: str | int = "default",
        E1: float | None = None,
        E2: float | None = None,
        E3: float | None = None,
        G12: float | None = None,
        G23: float | None = None,
        G31: float | None = None,
        v12: float | None = None,
        v23: float | None = None,
        v31: float | None = None,
        mat_axis_a: object = (1.0, 0.0, 0.0),
        mat_axis_d: object = (0.0, 1.0, 0.0),
    ) -> None:
        self.c = parameter(self.name, "c", c, positive=True)
        k = parameter(self.name, "k", k, positive=True, meaning="bulk modulus")
        self.bulk_kind = _pressure_model(self.name, pressure_model)
        super().__init__(
            E1=E1,
            E2=E2,
            E3=E3,
            G12=G12,
            G23=G23,
            G31=G31,
            v12=v12,
            v23=v23,
            v31=v31,
            mat_axis_a=mat_axis_a,
            mat_axis_d=mat_axis_d,
        )
        self.k = k
        self.lam = self.k - 2.0 * self.mu / 3.0
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        out = {**super().parameters(), "c": self.c, "k": self.k}
        out["pressure_model"] = PRESSURE_MODELS[BULK_KINDS.index(self.bulk_kind)]
        return out

    def bulk(self, J: np.ndarray, lnJ: np.ndarray) -> tuple:
        return bulk_energy(self.bulk_kind, self.k, J, lnJ)

    def w(self, x: np.ndarray, order: int) -> tuple:
        wo, go, ho = super().w(x, order)
        eQ = np.exp(2.0 * wo / self.c)
        w = 0.5 * self.c * (eQ - 1.0)
        g = eQ[:, None] * go
        h = eQ[:, None, None] * (ho + 2.0 / self.c * go[:, :, None] * go[:, None, :])
        return w, g, h


class FungOrthotropicCompressible(FungOrthotropic):
    """FEBio's Fung-ortho-compressible: c/2 (exp(Q) - 1) on E + k/2 (ln J)^2."""

    name = "fung_ortho_compressible"
    febio_name = "Fung-ortho-compressible"
    uncoupled = False

    def __init__(
        self,
        *,
        c: float | None = None,
        k: float | None = None,
        E1: float | None = None,
        E2: float | None = None,
        E3: float | None = None,
        G12: float | None = None,
        G23: float | None = None,
        G31: float | None = None,
        v12: float | None = None,
        v23: float | None = None,
        v31: float | None = None,
        mat_axis_a: object = (1.0, 0.0, 0.0),
        mat_axis_d: object = (0.0, 1.0, 0.0),
    ) -> None:
        super().__init__(
            c=c,
            k=k,
            E1=E1,
            E2=E2,
            E3=E3,
            G12=G12,
            G23=G23,
            G31=G31,
            v12=v12,
            v23=v23,
            v31=v31,
            mat_axis_a=mat_axis_a,
            mat_axis_d=mat_axis_d,
        )

    def parameters(self) -> dict[str, object]:
        out = super().parameters()
        del out["pressure_model"]
        return out
