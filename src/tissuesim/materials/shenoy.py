"""FEBio's ``Shenoy`` material (``FEShenoyMaterial``: Wang, Shenoy et al.'s fibrous matrix that
stiffens along its principal stretches): a neo-Hookean matrix with a bulk term and a fibre term
on each principal stretch lambda_a. FEBio's Cauchy stress

    sigma = mu/J dev(B_bar) + k (J - 1) I + 1/J sum_a lambda_a f'(lambda_a) n_a (x) n_a

is the derivative of

    W = mu/2 (I1_bar - 3) + k/2 (J - 1)^2 + sum_a f(lambda_a)

(the matrix: an uncoupled Mooney-Rivlin with c1 = mu/2, c2 = 0 and the Abaqus bulk term), with
f' FEBio's fiberStress, lambda1 = lam_c - lam_t/2, lambda2 = lam_c + lam_t/2, D = lambda2 -
lambda1:

    lambda < lambda1             f = 0
    lambda1 <= lambda <= lambda2 f = Ef (lambda - lambda1)^(n+2) / ((n+1)(n+2) D^n)
    lambda > lambda2             f = f(lambda2) + Ef (D/(n+1) (lambda - lambda2)
                                     + ((1 + lambda - lambda2)^(m+2) - 1) / ((m+1)(m+2))
                                     - (lambda - lambda2)/(m+1))

The fibre term is a spectral energy sum_a g(x_a) of the eigenvalues x_a = lambda_a^2 of C:
S = 2 V diag(g') V^T and the tangent with the divided differences (g'_a - g'_b)/(x_a - x_b)
(g'' where x_a and x_b nearly coincide), as ``soft_tissue/ogden.py`` writes them. 3D only.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import check_input
from tissuesim.materials.soft_tissue._hyperelastic import parameter

__all__ = ["Shenoy"]


class Shenoy(Material):
    """FEBio's Shenoy: ``mu``, ``k``, ``Ef`` (Pa), ``lam_c``, ``lam_t``, ``n``, ``m``.

    ``Shenoy(mu=0.77, k=1.67, Ef=134.6, lam_c=1.02, lam_t=0.255, n=5, m=30)``"""

    name = "shenoy"
    febio_name = "Shenoy"

    def __init__(
        self,
        *,
        mu: float | None = None,
        k: float | None = None,
        Ef: float = 0.0,
        lam_c: float = 1.0,
        lam_t: float | None = None,
        n: float = 5.0,
        m: float = 1.0,
    ) -> None:
        from tissuesim.materials.soft_tissue.mooney_rivlin import MooneyRivlin

        law = self.name
        self.fibre_mu = parameter(law, "mu", mu)
        self.k = parameter(law, "k", k)
        self.Ef = parameter(law, "Ef", Ef)
        self.lam_c = parameter(law, "lam_c", lam_c, unit="")
        self.lam_t = parameter(law, "lam_t", lam_t, unit="")
        self.n = parameter(law, "n", n, unit="")
        self.m = parameter(law, "m", m, unit="")
        if min(self.fibre_mu, self.k, self.Ef) < 0.0 or self.lam_c < 1.0 or self.lam_t <= 0.0:
            raise MaterialError(f"{law}: mu, k, Ef must be >= 0, lam_c >= 1 and lam_t > 0")
        if self.n < 1.0 or self.m < 1.0:
            raise MaterialError(f"{law}: n and m must be >= 1")
        self.matrix = MooneyRivlin(c1=0.5 * self.fibre_mu, c2=0.0, k=self.k,
                                   pressure_model="Abaqus")  # fmt: skip
        self.mu, self.lam = self.matrix.mu, self.matrix.lam

    def parameters(self) -> dict[str, object]:
        keys = ("Ef", "lam_c", "lam_t", "n", "m")
        return {"mu": self.fibre_mu, "k": self.k, **{k: getattr(self, k) for k in keys}}

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.parameters().items())
        return f"{type(self).__name__}({args})"

    def fibre(self, lam: np.ndarray) -> tuple:
        """(f, f', f'') of the fibre term at principal stretches ``lam``."""
        l1 = self.lam_c - 0.5 * self.lam_t
        l2 = self.lam_c + 0.5 * self.lam_t
        D, n, m, Ef = l2 - l1, self.n, self.m, self.Ef
        u = np.clip(lam - l1, 0.0, D)  # the middle branch (0 below lambda1)
        f = Ef * u ** (n + 2) / ((n + 1) * (n + 2) * D**n)
        df = Ef * u ** (n + 1) / ((n + 1) * D**n)
        ddf = np.where(lam > l1, Ef * (u / D) ** n, 0.0)
        v = np.maximum(lam - l2, 0.0)  # beyond lambda2
        high = lam > l2
        f = f + Ef * (
            D / (n + 1) * v + ((1 + v) ** (m + 2) - 1) / ((m + 1) * (m + 2)) - v / (m + 1)
        )
        df = df + np.where(high, Ef * (((1 + v) ** (m + 1) - 1) / (m + 1)), 0.0)
        ddf = np.where(high, Ef * (1 + v) ** m, ddf)
        return f, df, ddf

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        if F.shape[-1] != 3:
            raise MaterialError(f"{self.name} is 3D only")
        res = self.matrix.evaluate(F, order)
        ok = np.isfinite(res.energy)
        Fs = np.where(ok[:, None, None], F, np.eye(3))
        if order == 0:
            lam = np.linalg.svd(Fs, compute_uv=False)
            return MaterialResponse(res.energy + self.fibre(lam)[0].sum(axis=1))
        U, lam, Vt = np.linalg.svd(Fs)
        V, f = np.swapaxes(Vt, 1, 2), U * lam[:, None, :]
        fl, dfl, ddfl = self.fibre(lam)
        psi = res.energy + fl.sum(axis=1)
        x = lam**2
        g1 = dfl / (2.0 * lam)  # dg/dx
        S = 2.0 * (V * g1[:, None, :]) @ Vt
        P = res.stress + F @ S
        if order == 1:
            return MaterialResponse(psi, P)
        g2 = (ddfl - dfl / lam) / (4.0 * x)  # d2g/dx2
        xa, xb = x[:, :, None], x[:, None, :]
        close = np.abs(xa - xb) <= 1e-8 * np.maximum(xa, xb)
        G = np.where(
            close,
            0.5 * (g2[:, :, None] + g2[:, None, :]),
            (g1[:, :, None] - g1[:, None, :]) / np.where(close, 1.0, xa - xb),
        )
        # dP_ij/dF_kl = delta_ik S_lj + 2 sum_ab G_ab f_ia V_jb (f_kb V_la + f_ka V_lb)
        T = np.einsum("qia,qjb->qabij", f, V)
        A = 2.0 * np.einsum("qab,qabij,qabkl->qijkl", G, T, T + np.swapaxes(T, 1, 2))
        A += np.einsum("ik,qlj->qijkl", np.eye(3), S)
        return MaterialResponse(psi, P, res.tangent + A)
