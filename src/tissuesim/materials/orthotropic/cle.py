"""FEBio's conewise linear elastic laws, ``orthotropic CLE`` and ``cubic CLE``
(``FEOrthotropicCLE``, ``FECubicCLE``): St Venant-Kirchhoff-like along the local axes a_1, a_2,
a_3, with a diagonal modulus that is lp_aa in tension (A_a : E >= 0) and lm_aa in compression.
FEBio's second Piola-Kirchhoff stress S = sum_a mu_a sym(A_a E) + sum_ab lam_ab (A_a : E) A_b
is the derivative of

    W = sum_a mu_a / 2 A_a : E^2 + 1/2 sum_ab lam_ab (A_a : E)(A_b : E),   A_a = a_a (x) a_a

(lam_aa switching with the sign of A_a : E, where W and S are continuous and the tangent jumps).
In the invariants x = (A_a : E, A_a : E^2) of ``_orthotropic.py``: dW/dx = (lam x_1..3, mu / 2),
d2W/dx2 = lam on the first three. Cubic: lp11 = lp22 = lp33 = lp1, lm.. = lm1, lam_ab = l2
(a != b), mu_a = mu. ``.mu`` is the mean of mu_a / 2 and ``.lam`` the mean of the tensile
lam_ab (the small-strain moduli in tension).
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.orthotropic._orthotropic import OrthotropicLaw
from tissuesim.materials.soft_tissue._hyperelastic import parameter

__all__ = ["OrthotropicCLE", "CubicCLE"]


class OrthotropicCLE(OrthotropicLaw):
    """FEBio's orthotropic CLE: lp11, lm11, lp22, lm22, lp33, lm33, l12, l23, l31, mu1, mu2, mu3
    (Pa) along the local axes of ``mat_axis_a``, ``mat_axis_d``."""

    name = "orthotropic_cle"
    febio_name = "orthotropic CLE"

    def __init__(
        self,
        *,
        lp11: float | None = None,
        lm11: float | None = None,
        lp22: float | None = None,
        lm22: float | None = None,
        lp33: float | None = None,
        lm33: float | None = None,
        l12: float | None = None,
        l23: float | None = None,
        l31: float | None = None,
        mu1: float | None = None,
        mu2: float | None = None,
        mu3: float | None = None,
        mat_axis_a: object = (1.0, 0.0, 0.0),
        mat_axis_d: object = (0.0, 1.0, 0.0),
    ) -> None:
        given = dict(lp11=lp11, lm11=lm11, lp22=lp22, lm22=lm22, lp33=lp33, lm33=lm33,
                     l12=l12, l23=l23, l31=l31, mu1=mu1, mu2=mu2, mu3=mu3)  # fmt: skip
        self._set_moduli(given)
        self._set_axes(mat_axis_a, mat_axis_d)

    def _set_moduli(self, given: dict) -> None:
        c = {k: parameter(self.name, k, v) for k, v in given.items()}
        self._constants = c
        if "lp1" in c:  # cubic
            lp, lm, off, mu = c["lp1"], c["lm1"], c["l2"], c["mu"]
            self._lp, self._lm = np.full(3, lp), np.full(3, lm)
            self._off = off * (1.0 - np.eye(3))
            self._mu = np.full(3, mu)
        else:
            self._lp = np.array([c["lp11"], c["lp22"], c["lp33"]])
            self._lm = np.array([c["lm11"], c["lm22"], c["lm33"]])
            self._off = np.array(
                [[0.0, c["l12"], c["l31"]], [c["l12"], 0.0, c["l23"]], [c["l31"], c["l23"], 0.0]]
            )
            self._mu = np.array([c["mu1"], c["mu2"], c["mu3"]])
        if (self._mu < 0.0).any():
            raise MaterialError(f"{self.name}: the shear moduli mu must be >= 0")
        for diag in (self._lp, self._lm):  # FEBio's Validate: lam + 2 mu positive definite
            C = self._off + np.diag(diag + 2.0 * self._mu)
            if np.linalg.eigvalsh(C).min() < 0.0:
                raise MaterialError(f"{self.name}: the stiffness matrix is not positive definite")
        self.mu = float(self._mu.mean()) / 2.0
        self.lam = float((self._off + np.diag(self._lp)).mean())
        self.k = self.lam + 2.0 * self.mu / 3.0
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        return {**self._constants, **self._axes_parameters()}

    def w(self, x: np.ndarray, order: int) -> tuple:
        e, e2 = x[:, :3], x[:, 3:]
        lam = np.broadcast_to(self._off, (x.shape[0], 3, 3)).copy()
        idx = np.arange(3)
        lam[:, idx, idx] = np.where(e >= 0.0, self._lp, self._lm)
        le = np.einsum("qab,qb->qa", lam, e)
        w = e2 @ (self._mu / 2.0) + 0.5 * np.einsum("qa,qa->q", le, e)
        g = np.concatenate([le, np.broadcast_to(self._mu / 2.0, e2.shape)], 1)
        h = np.zeros((x.shape[0], 6, 6))
        h[:, :3, :3] = lam
        return w, g, h


class CubicCLE(OrthotropicCLE):
    """FEBio's cubic CLE: lp1, lm1, l2, mu (Pa) along the local axes."""

    name = "cubic_cle"
    febio_name = "cubic CLE"

    def __init__(
        self,
        *,
        lp1: float | None = None,
        lm1: float | None = None,
        l2: float | None = None,
        mu: float | None = None,
        mat_axis_a: object = (1.0, 0.0, 0.0),
        mat_axis_d: object = (0.0, 1.0, 0.0),
    ) -> None:
        self._set_moduli(dict(lp1=lp1, lm1=lm1, l2=l2, mu=mu))
        self._set_axes(mat_axis_a, mat_axis_d)
