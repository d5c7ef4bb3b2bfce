"""FEBio's ``TC nonlinear orthotropic`` (``FETCNonlinearOrthotropic``, uncoupled): a
Mooney-Rivlin matrix and three fibre families along the local axes a_1, a_2, a_3 that bear
tension only,

    W = c1 (I1b - 3) + c2 (I2b - 3) + sum_a Wf_a(lb_a) + U(J),   lb_a = sqrt(I4b_a)
    Wf_a = ksi_a (lb_a - 1)^beta_a  for lb_a > 1, else 0

(I4b_a = J^(-2/3) a_a . C a_a). In I4b (l = lb):

    dWf/dI4 = beta ksi (l - 1)^(beta - 1) / (2 l)
    d2Wf/dI4^2 = beta ksi (l - 1)^(beta - 2) ((beta - 1) l - (l - 1)) / (4 l^3)

``beta`` (>= 2, as FEBio requires) and ``ksi`` (>= 0, Pa) give the three families' values (or
one value for all); U = k/2 (ln J)^2 (FEBio's ``pressure_model`` picks another). The axes are
FEBio's ``mat_axis`` (``mat_axis_a``, ``mat_axis_d``: a_1 = e1, a_2 = e2, a_3 = e1 x e2), one
pair or one per element. ``.mu`` = 2 (c1 + c2), ``.lam`` = k - 2 mu / 3 (the matrix's).
J <= 0: energy +inf, stress and tangent raise InvertedElementError.
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
    parameter_list,
)
from tissuesim.materials.soft_tissue._hyperelastic import pressure_model as _pressure_model

__all__ = ["TCNonlinearOrthotropic"]


class TCNonlinearOrthotropic(FibreLaw):
    """FEBio's TC nonlinear orthotropic: c1 (I1b - 3) + c2 (I2b - 3) + sum_a ksi_a (lb_a -
    1)^beta_a (tension only) along the local axes + U(J); c1, c2, ksi, k in Pa."""

    name = "tc_nonlinear_orthotropic"
    febio_name = "TC nonlinear orthotropic"
    uncoupled = True
    uses_i2 = True

    def __init__(
        self,
        *,
        c1: float | None = None,
        c2: float = 0.0,
        beta: object = None,
        ksi: object = None,
        k: float | None = None,
        pressure_model: str | int = "default",
        mat_axis_a: object = (1.0, 0.0, 0.0),
        mat_axis_d: object = (0.0, 1.0, 0.0),
    ) -> None:
        law = self.name
        self.c1, self.c2 = parameter(law, "c1", c1), parameter(law, "c2", c2)
        values = {}
        for key, value in (("beta", beta), ("ksi", ksi)):
            if value is None:
                raise MaterialError(f"{law} needs {key} (one value or one per axis)")
            v = parameter_list(law, key, value, unit="" if key == "beta" else "Pa")
            if len(v) not in (1, 3):
                raise MaterialError(
                    f"{law}: {key} takes 1 or 3 values (one per axis), got {len(v)}"
                )
            values[key] = np.array(v * 3 if len(v) == 1 else v)
        self.beta, self.ksi = values["beta"], values["ksi"]
        if np.any(self.beta < 2.0) or np.any(self.ksi < 0.0):
            raise MaterialError(f"{law}: beta must be >= 2 and ksi >= 0 (FEBio's ranges)")
        self.k = parameter(law, "k", k, positive=True, meaning="bulk modulus")
        e1, e2 = local_axes(law, mat_axis_a, mat_axis_d)
        self.mat_axis_a, self.mat_axis_d = e1, e2
        self.planar = planar_keys(mat_axis_a=mat_axis_a, mat_axis_d=mat_axis_d)
        e1, e2 = np.atleast_2d(e1), np.atleast_2d(e2)
        self.fibres = np.stack([e1, e2, np.cross(e1, e2)], axis=1)
        self.bulk_kind = _pressure_model(law, pressure_model)
        self.mu = 2.0 * (self.c1 + self.c2)
        self.lam = self.k - 2.0 * self.mu / 3.0
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        out: dict[str, object] = dict(c1=self.c1, c2=self.c2, beta=self.beta.tolist())
        out.update(ksi=self.ksi.tolist(), k=self.k)
        out["pressure_model"] = PRESSURE_MODELS[BULK_KINDS.index(self.bulk_kind)]
        out.update(mat_axis_a=self.mat_axis_a.tolist(), mat_axis_d=self.mat_axis_d.tolist())
        return out

    def bulk(self, J: np.ndarray, lnJ: np.ndarray) -> tuple:
        return bulk_energy(self.bulk_kind, self.k, J, lnJ)

    def w(self, inv: np.ndarray, order: int) -> tuple:
        q = inv.shape[0]
        I1, I2, I4 = inv[:, 0], inv[:, 1], inv[:, 2:]
        l = np.sqrt(I4)
        taut = l > 1.0
        x = np.where(taut, l - 1.0, 0.0)  # (q, 3)
        b, ksi = self.beta, self.ksi
        Wf = np.where(taut, ksi * x**b, 0.0)
        dWf = np.where(taut, b * ksi * x ** (b - 1.0) / (2.0 * l), 0.0)
        w = self.c1 * (I1 - 3.0) + self.c2 * (I2 - 3.0) + Wf.sum(1)
        g = np.concatenate([np.full((q, 1), self.c1), np.full((q, 1), self.c2), dWf], 1)
        h = np.zeros((q, 5, 5))
        if order >= 2:
            dd = b * ksi * x ** (b - 2.0) * ((b - 1.0) * l - x) / (4.0 * l**3)
            h[:, 2:, 2:] = np.eye(3) * np.where(taut, dd, 0.0)[:, :, None]
        return w, g, h
