"""FEBio's ``isotropic Hencky`` (``FEIsoHencky``): the logarithmic strain h = ln V with Hooke's
law, W = mu tr(h^2) + lam/2 (tr h)^2, in the principal stretches lambda_a = sqrt(x_a) (x_a the
eigenvalues of C):

    W = mu/4 sum_a (ln x_a)^2 + lam/2 (ln J)^2,   mu = E / (2 (1 + v)),
    lam = E v / ((1 + v)(1 - 2 v))

(its Kirchhoff stress 2 mu h + lam ln J I, FEBio's). A spectral energy sum_a g(x_a) +
U(J) with g = mu/4 (ln x)^2, g' = mu ln x / (2 x), g'' = mu (1 - ln x) / (2 x^2) (``ogden.py``
writes out the spectral stress and tangent, Daleckii-Krein):

    S = 2 V diag(g'(x)) V^T,   P = F S + U' cof F
    dP_ij/dF_kl = delta_ik S_lj + 2 sum_ab G_ab f_ia V_jb (f_kb V_la + f_ka V_lb)
                  + U'' cof (x) cof + U' d2J,   f = F V
    G_ab = (g'(x_a) - g'(x_b)) / (x_a - x_b), g''((x_a + x_b)/2) where they nearly coincide

(the midpoint's error is of the order of (x_a - x_b)^2, below round-off at the 1e-6 switch).
Parameters ``E`` (Pa) > 0, ``v`` in (-1, 0.5): Hooke's law at small strain. In 2D plane strain
x_3 = 1 adds nothing. J <= 0: energy +inf, stress and tangent raise InvertedElementError.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import bcast, check_input, cofactor, det, det_hessian
from tissuesim.materials.soft_tissue._hyperelastic import (
    HyperelasticMaterial,
    inverted_error,
    parameter,
)

__all__ = ["IsotropicHencky"]


class IsotropicHencky(HyperelasticMaterial):
    """FEBio's isotropic Hencky: mu tr(h^2) + lam/2 (tr h)^2, h = ln V; E (Pa), v."""

    name = "isotropic_hencky"
    febio_name = "isotropic Hencky"
    bulk_kind = "log"  # lam/2 (ln J)^2 (``volumetric.py``)

    def __init__(self, *, E: float | None = None, v: float | None = None) -> None:
        self.E = parameter(self.name, "E", E, positive=True)
        self.v = parameter(self.name, "v", v, unit="")
        if not -1.0 < self.v < 0.5:
            raise MaterialError(f"{self.name}: v must be in (-1, 0.5), got {self.v!r}")
        self.mu = 0.5 * self.E / (1.0 + self.v)
        self.lam = self.v * self.E / ((1.0 + self.v) * (1.0 - 2.0 * self.v))
        self.k = self.lam
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        return {"E": self.E, "v": self.v}

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        q, d = F.shape[0], F.shape[-1]
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0
        if order > 0 and not ok.all():
            raise inverted_error(self.name, J, ok)
        Fs = np.where(bcast(ok, 3), F, np.eye(d))
        Js = np.where(ok, J, 1.0)
        lnJ = np.log(Js)
        mu, lam = self.mu, self.lam
        if order == 0:
            x = np.linalg.svd(Fs, compute_uv=False) ** 2
        else:
            U, s, Vt = np.linalg.svd(Fs)
            x, V, f = s**2, np.swapaxes(Vt, 1, 2), U * s[:, None, :]
        lnx = np.log(x)
        psi = np.where(ok, 0.25 * mu * np.sum(lnx**2, 1) + 0.5 * lam * lnJ**2, np.inf)
        if order == 0:
            return MaterialResponse(psi)
        g1 = 0.5 * mu * lnx / x
        S = 2.0 * (V * g1[:, None, :]) @ np.swapaxes(V, 1, 2)
        UJ = lam * lnJ / Js
        P = F @ S + bcast(UJ, 3) * cof
        if order == 1:
            return MaterialResponse(psi, P)
        xa, xb = x[:, :, None], x[:, None, :]
        near = np.abs(xa - xb) <= 1e-6 * np.maximum(xa, xb)
        mid = 0.5 * (xa + xb)
        g2 = 0.5 * mu * (1.0 - np.log(mid)) / mid**2
        gap = np.where(near, 1.0, xa - xb)
        G = np.where(near, g2, (g1[:, :, None] - g1[:, None, :]) / gap)
        n = d * d
        T = f.transpose(0, 2, 1)[:, :, None, :, None] * V.transpose(0, 2, 1)[:, None, :, None, :]
        Tm = T.reshape(q, n, n)  # rows (a, b): f_ia V_jb
        Ts = np.swapaxes(T, 1, 2).reshape(q, n, n)
        A = np.swapaxes(Tm, 1, 2) @ (2.0 * G.reshape(q, n, 1) * (Tm + Ts))
        A = A.reshape(q, d, d, d, d)
        A += np.eye(d)[None, :, None, :, None] * np.swapaxes(S, 1, 2)[:, None, :, None, :]
        UJJ = lam * (1.0 - lnJ) / Js**2
        A += bcast(UJJ, 5) * np.einsum("qij,qkl->qijkl", cof, cof)
        A += bcast(UJ, 5) * det_hessian(F)
        return MaterialResponse(psi, P, A)
