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
forward). FEBio's fibre shear term, ``mu`` (Pa) >= 0, adds where the fibre is taut

    mu / 4 (I5 - 2 I4 + 1),   I5 = a . C^2 a   (uncoupled: I5b = J^(-4/3) I5 and I4b)

(its Cauchy stress mu / J sym(N (B - I)), N = (F a) (x) (F a), FEBio's; it is >= 0 and jumps
where the fibre goes slack in shear, as FEBio's does). Its derivatives, with G5 = dI5/dF =
2 (F C a (x) a + F a (x) C a) and

    d2I5/dF_ij dF_kl = 2 [delta_ik S_lj + (Fa)_i (Fa)_k delta_jl + (Fa)_i F_kj a_l
                          + F_il (Fa)_k a_j + B_ik a_j a_l],   S = a (x) C a + C a (x) a,

and for the uncoupled law the chain rule through J^(-4/3) and J^(-2/3) (``_scaled``). Parameters
as FEBio's: ``ksi`` (Pa) >= 0, ``alpha`` >= 0, ``beta`` >= 2, ``mu`` >= 0, ``lam0`` >= 1 (the
coupled law's slack stretch; the uncoupled law has none).
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.fibres._single_fibre import SingleFibre, exponent
from tissuesim.materials.isotropic._common import bcast, cofactor, det, det_hessian, outer
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
        self.fibre_mu = parameter(law, "mu", mu)
        if self.fibre_mu < 0.0:
            raise MaterialError(f"{law}: mu (the fibre's shear modulus) must be >= 0")
        self._set_fibre(fiber)

    def parameters(self) -> dict[str, object]:
        out: dict[str, object] = dict(ksi=self.ksi, alpha=self.alpha, beta=self.beta)
        if self.fibre_mu:
            out["mu"] = self.fibre_mu
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

    def _taut(self, I4: np.ndarray) -> np.ndarray:
        x = I4 - self.lam0**2
        return x >= 0.0 if self.uncoupled else x >= _EPS

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        res = super().evaluate(F, order)
        if self.fibre_mu == 0.0:
            return res
        F = np.asarray(F, dtype=float)
        q, d = F.shape[0], F.shape[-1]
        a = np.broadcast_to(self.fibres[:, 0, :], (q, 3))
        ain, a3sq = a[:, :d], (a[:, 2] ** 2 if d == 2 else np.zeros(q))
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0
        Js = np.where(ok, J, 1.0)
        C = np.swapaxes(F, 1, 2) @ F
        Fa = np.einsum("qij,qj->qi", F, ain)
        Ca = np.einsum("qij,qj->qi", C, ain)
        FCa = np.einsum("qij,qj->qi", F, Ca)
        I4 = np.einsum("qi,qi->q", Fa, Fa) + a3sq
        I5 = np.einsum("qi,qi->q", Ca, Ca) + a3sq
        e4, e5 = (2.0 / 3.0, 4.0 / 3.0) if self.uncoupled else (0.0, 0.0)
        taut = self._taut(I4 * Js**-e4) & ok
        c = np.where(taut, self.fibre_mu / 4.0, 0.0)
        G4 = 2.0 * Fa[:, :, None] * ain[:, None, :]
        G5 = 2.0 * (FCa[:, :, None] * ain[:, None, :] + Fa[:, :, None] * Ca[:, None, :])
        terms = [(c, e5, I5, G5), (-2.0 * c, e4, I4, G4)]
        psi = sum(k * Js**-e * inv for k, e, inv, _ in terms) + c
        psi = res.energy + np.where(ok, psi, 0.0)
        if order == 0:
            return MaterialResponse(psi)
        P = res.stress + sum(
            _scaled(k, e, inv, G, None, Js, cof, F, 1)[0] for k, e, inv, G in terms
        )
        if order == 1:
            return MaterialResponse(psi, P)
        eye = np.eye(d)
        B = F @ np.swapaxes(F, 1, 2)
        S = ain[:, :, None] * Ca[:, None, :] + Ca[:, :, None] * ain[:, None, :]
        H5 = 2.0 * (
            eye[None, :, None, :, None] * S[:, None, :, None, :]
            + Fa[:, :, None, None, None] * Fa[:, None, None, :, None] * eye[None, None, :, None, :]
            + Fa[:, :, None, None, None]
            * np.swapaxes(F, 1, 2)[:, None, :, :, None]
            * ain[:, None, None, None, :]
            + F[:, :, None, None, :] * Fa[:, None, None, :, None] * ain[:, None, :, None, None]
            + B[:, :, None, :, None] * ain[:, None, :, None, None] * ain[:, None, None, None, :]
        )
        H4 = (
            2.0
            * eye[None, :, None, :, None]
            * (ain[:, :, None] * ain[:, None, :])[:, None, :, None, :]
        )
        A = res.tangent
        for (k, e, inv, G), H in zip(terms, (H5, H4), strict=True):
            A = A + _scaled(k, e, inv, G, H, Js, cof, F, 2)[1]
        return MaterialResponse(psi, P, A)


def _scaled(
    k: np.ndarray,
    e: float,
    inv: np.ndarray,
    G: np.ndarray,
    H: np.ndarray | None,
    J: np.ndarray,
    cof: np.ndarray,
    F: np.ndarray,
    order: int,
) -> tuple:
    """P and (order 2) dP/dF of k J^(-e) I for an invariant I with gradient G, Hessian H."""
    g, dg, ddg = J**-e, -e * J ** (-e - 1.0), e * (e + 1.0) * J ** (-e - 2.0)
    P = bcast(k * g, 3) * G + bcast(k * dg * inv, 3) * cof
    if order == 1:
        return P, None
    A = bcast(k * g, 5) * H + bcast(k * dg, 5) * (outer(G, cof) + outer(cof, G))
    A += bcast(k * ddg * inv, 5) * outer(cof, cof) + bcast(k * dg * inv, 5) * det_hessian(F)
    return P, A


class FiberExpPowUncoupled(FiberExpPow):
    """FEBio's ``fiber-exp-pow-uncoupled``: the same law on the isochoric I4b = J^(-2/3) I4,
    active for I4b > 1 (no lam0)."""

    name = "fiber_exp_pow_uncoupled"
    febio_name = "fiber-exp-pow-uncoupled"
    uncoupled = True
