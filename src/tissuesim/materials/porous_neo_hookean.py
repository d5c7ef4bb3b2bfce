"""FEBio's ``porous neo-Hookean`` (``FEPorousNeoHookean``, FEBioMix): a neo-Hookean solid
whose pores close, with phi0 the referential solid volume fraction: the solid matrix's own
volume ratio is J_bar = (J - phi0) / (1 - phi0) (the pores take the rest), and

    W = mu ((I1_bar - 3) / 2 - ln J_bar),   I1_bar = I1 (J_bar / J)^(2/3),
    mu = E / 3 (1 + (1 - phi0)^2 / 2)

(FEBio's lambda is 0: not a parameter). Written W(I1, J) = mu/2 (I1 r(J) - 3) - mu ln J_bar(J)
with r = (J_bar / J)^(2/3):

    P = mu r F + W_J cof F,    W_J = mu/2 I1 r' - mu / (J - phi0)
    dP/dF = mu r I + mu r' (F (x) cof + cof (x) F) + W_JJ cof (x) cof + W_J d2J/dF2,
    W_JJ = mu/2 I1 r'' + mu / (J - phi0)^2

Defined for J > phi0 (+inf energy elsewhere, and an error asked for stress there). In 2D the
plane-strain restriction (I1 = |F|^2 + 1).
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import (
    IDENTITY,
    check_input,
    cofactor,
    det,
    det_hessian,
)
from tissuesim.materials.soft_tissue._hyperelastic import inverted_error, parameter

__all__ = ["PorousNeoHookean"]


class PorousNeoHookean(Material):
    """FEBio's porous neo-Hookean: ``E`` (Pa) and ``phi0`` (the solid volume fraction, 0..1).

    ``PorousNeoHookean(E=1e4, phi0=0.2)``"""

    name = "porous_neo_hookean"
    febio_name = "porous neo-Hookean"

    def __init__(self, *, E: float | None = None, phi0: float = 1.0) -> None:
        self.E = parameter(self.name, "E", E, positive=True)
        self.phi0 = parameter(self.name, "phi0", phi0, unit="")
        if not 0.0 <= self.phi0 < 1.0:
            raise MaterialError(f"{self.name}: phi0 must be in [0, 1), got {self.phi0!r}")
        self.mu = self.E / 3.0 * (1.0 + 0.5 * (1.0 - self.phi0) ** 2)
        # the small-strain lam: a dilation s I gives dP11/ds = 2 mu + 3 lam at s = 1, which is
        # -mu + 6 mu r'(1) + 3 W_JJ(1) (r(1) = 1, W_J(1) = -mu)
        _, dr, ddr = self._r(np.array(1.0))
        wjj = 1.5 * self.mu * ddr + self.mu / (1.0 - self.phi0) ** 2
        self.lam = float(-self.mu + 2.0 * self.mu * dr + wjj)

    def parameters(self) -> dict[str, object]:
        return {"E": self.E, "phi0": self.phi0}

    def __repr__(self) -> str:
        return f"{type(self).__name__}(E={self.E!r}, phi0={self.phi0!r})"

    def _r(self, J: np.ndarray) -> tuple:
        """(r, r', r'') of r(J) = (J_bar / J)^(2/3) = c (1 - phi0/J)^(2/3)."""
        phi = self.phi0
        c = (1.0 - phi) ** (-2.0 / 3.0)
        u = 1.0 - phi / J
        du = phi / J**2
        ddu = -2.0 * phi / J**3
        r = c * u ** (2.0 / 3.0)
        dr = c * (2.0 / 3.0) * u ** (-1.0 / 3.0) * du
        ddr = c * (2.0 / 3.0) * ((-1.0 / 3.0) * u ** (-4.0 / 3.0) * du**2 + u ** (-1.0 / 3.0) * ddu)
        return r, dr, ddr

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        d = F.shape[-1]
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > self.phi0
        if order > 0 and not ok.all():
            raise inverted_error(self.name, J, ok)
        Js = np.where(ok, J, 1.0)
        mu, phi = self.mu, self.phi0
        I1 = np.einsum("qij,qij->q", F, F) + (3.0 - d)
        r, dr, ddr = self._r(Js)
        Jbar = (Js - phi) / (1.0 - phi)
        psi = np.where(ok, 0.5 * mu * (I1 * r - 3.0) - mu * np.log(Jbar), np.inf)
        if order == 0:
            return MaterialResponse(psi)
        WJ = 0.5 * mu * I1 * dr - mu / (Js - phi)
        P = (mu * r)[:, None, None] * F + WJ[:, None, None] * cof
        if order == 1:
            return MaterialResponse(psi, P)
        WJJ = 0.5 * mu * I1 * ddr + mu / (Js - phi) ** 2
        b = (None, None, None, None)
        A = (mu * r)[(slice(None), *b)] * IDENTITY[d][None]
        A = A + (mu * dr)[(slice(None), *b)] * (
            np.einsum("qij,qkl->qijkl", F, cof) + np.einsum("qij,qkl->qijkl", cof, F)
        )
        A = A + WJJ[(slice(None), *b)] * np.einsum("qij,qkl->qijkl", cof, cof)
        A = A + WJ[(slice(None), *b)] * det_hessian(F)
        return MaterialResponse(psi, P, A)
