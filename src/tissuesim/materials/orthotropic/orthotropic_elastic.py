"""FEBio's ``orthotropic elastic``: St Venant-Kirchhoff's energy with orthotropic moduli along
the local axes a_1, a_2, a_3 (FEBio's ``FEOrthoElastic``; coupled, no bulk term of its own):

    W = sum_a mu_a A_a : E^2 + 1/2 sum_ab lam_ab (A_a : E)(A_b : E),   A_a = a_a (x) a_a

mu_a and lam_ab from FEBio's engineering constants E1, E2, E3, G12, G23, G31, v12, v23, v31
(``_orthotropic.lame_moduli``), so that at small strain the law is the orthotropic Hooke law
with those constants. In the invariants x = (A_a : E, A_a : E^2): dW/dx = (lam x_1..3, mu),
d2W/dx2 = lam on the first three. ``mat_axis_a``, ``mat_axis_d``: FEBio's mat_axis (e1 = a/|a|,
e2 in the plane of a and d; default the global axes), one pair or one per element. ``.mu`` is
the mean of G12, G23, G31 and ``.lam`` the Reuss bulk modulus (1 / the sum of the compliance's
entries) less 2 mu / 3. Defined for any F (like St Venant-Kirchhoff it softens in strong
compression).
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials.orthotropic._orthotropic import ENGINEERING, OrthotropicLaw, lame_moduli

__all__ = ["OrthotropicElastic"]


class OrthotropicElastic(OrthotropicLaw):
    """FEBio's orthotropic elastic: E1, E2, E3, G12, G23, G31 (Pa), v12, v23, v31 along the
    local axes of ``mat_axis_a``, ``mat_axis_d``."""

    name = "orthotropic_elastic"
    febio_name = "orthotropic elastic"

    def __init__(
        self,
        *,
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
        given = dict(E1=E1, E2=E2, E3=E3, G12=G12, G23=G23, G31=G31, v12=v12, v23=v23, v31=v31)
        self._mu, self._lam, self._constants = lame_moduli(self.name, given)
        self._set_axes(mat_axis_a, mat_axis_d)
        self.mu = (self._constants["G12"] + self._constants["G23"] + self._constants["G31"]) / 3.0
        self.lam = (
            1.0 / (np.linalg.inv(self._lam + np.diag(2.0 * self._mu)).sum()) - 2 * self.mu / 3
        )
        self.k = self.lam + 2.0 * self.mu / 3.0
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        return {**{k: self._constants[k] for k in ENGINEERING}, **self._axes_parameters()}

    def w(self, x: np.ndarray, order: int) -> tuple:
        e, e2 = x[:, :3], x[:, 3:]
        le = e @ self._lam
        w = e2 @ self._mu + 0.5 * np.einsum("qa,qa->q", le, e)
        g = np.concatenate([le, np.broadcast_to(self._mu, e2.shape)], 1)
        h = np.zeros((x.shape[0], 6, 6))
        h[:, :3, :3] = self._lam
        return w, g, h
