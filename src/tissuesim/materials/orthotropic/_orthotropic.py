"""The engine of FEBio's orthotropic laws: W on the Green-Lagrange strain E = (C - I)/2 through
its components along three orthonormal reference axes a_1, a_2, a_3 (FEBio's ``mat_axis``:
a_1 = e1, a_2 = e2, a_3 = e3 of the local axes):

    x = (A_a : E, A_a : E^2) for a = 1, 2, 3,   A_a = a_a (x) a_a

    dx/dE:   G_a = A_a,   G2_a = A_a E + E A_a          (symmetric)
    S = sum_k w_k G_k,   dS = sum_kl w_kl G_k (G_l : dE) + sum_a w2_a (A_a dE + dE A_a)
    P = F S,   dP_iJ / dF_mL = delta_im S_LJ + F_iI C_IJKL F_mK

with C_IJKL the dS/dE above made symmetric in K, L (dE = sym(F^T dF)). An uncoupled law
evaluates W on F~ = J^(-1/3) F (E~ = (C~ - I)/2, C~ = J^(-2/3) C) and adds U(J): with
D = dF~/dF = J^(-1/3) (I - F (x) F^-T / 3) and P~, A~ the derivatives at F~,

    P = D^T P~ = J^(-1/3) P~ - (P~ : F~) H / 3,   H = F^-T
    A = D^T A~ D - (P (x) H + H (x) P) / 3 - (P~ : F~) (H (x) H / 9 - H_kn H_ml / 3)

(the last term's indices: A_klmn). Every law is evaluated in 3D; a 2D F is its plane-strain
restriction (F_33 = 1), the in-plane components taken from the 3D stress and tangent.

FEBio's moduli from E1, E2, E3, G12, G23, G31, v12, v23, v31 (``lame_moduli``): mu_1 = G12 +
G31 - G23, mu_2 = G12 - G31 + G23, mu_3 = G31 + G23 - G12, and lam_ab + 2 mu_a delta_ab the
inverse of the compliance [[1/E1, -v12/E1, -v31/E3], [-v12/E1, 1/E2, -v23/E2],
[-v31/E3, -v23/E2, 1/E3]], which must be positive definite.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.fibres._fibres import FibreLaw, local_axes, planar_keys
from tissuesim.materials.isotropic._common import check_input, cofactor, det, det_hessian
from tissuesim.materials.soft_tissue._hyperelastic import inverted_error, parameter

__all__ = ["OrthotropicLaw", "lame_moduli", "ENGINEERING"]

#: FEBio's engineering constants of the orthotropic laws
ENGINEERING = ("E1", "E2", "E3", "G12", "G23", "G31", "v12", "v23", "v31")
_I3 = np.eye(3)


def lame_moduli(law: str, values: dict) -> tuple[np.ndarray, np.ndarray, dict]:
    """(mu (3,), lam (3, 3), the checked constants) from FEBio's E1..v31 (``values``)."""
    c = {}
    for key in ENGINEERING:
        positive = key[0] == "E"
        c[key] = parameter(
            law, key, values.get(key), positive=positive, unit="" if key[0] == "v" else "Pa"
        )
        if key[0] == "G" and c[key] < 0.0:
            raise MaterialError(f"{law}: {key} must be >= 0 Pa, got {c[key]!r}")
    for v, (a, b) in (("v12", ("E1", "E2")), ("v23", ("E2", "E3")), ("v31", ("E3", "E1"))):
        if c[v] > np.sqrt(c[a] / c[b]):
            raise MaterialError(f"{law}: {v} must be <= sqrt({a}/{b}) = {np.sqrt(c[a] / c[b]):.6g}")
    E1, E2, E3 = c["E1"], c["E2"], c["E3"]
    G12, G23, G31 = c["G12"], c["G23"], c["G31"]
    mu = np.array([G12 + G31 - G23, G12 - G31 + G23, G31 + G23 - G12])
    S = np.array(
        [
            [1.0 / E1, -c["v12"] / E1, -c["v31"] / E3],
            [-c["v12"] / E1, 1.0 / E2, -c["v23"] / E2],
            [-c["v31"] / E3, -c["v23"] / E2, 1.0 / E3],
        ]
    )
    if np.linalg.eigvalsh(S).min() <= 0.0:
        raise MaterialError(
            f"{law}: E1..E3 and v12, v23, v31 give a compliance that is not positive definite"
        )
    lam = np.linalg.inv(S)
    lam -= np.diag(2.0 * mu)
    return mu, lam, c


class OrthotropicLaw(FibreLaw):
    """A law W(x) of x = (A_a : E, A_a : E^2), a = 1..3 (E~ when ``uncoupled``), plus ``bulk``
    U(J) (None: none); subclasses give ``w``."""

    uncoupled = False
    has_bulk = False

    def _set_axes(self, mat_axis_a: object, mat_axis_d: object) -> None:
        e1, e2 = local_axes(self.name, mat_axis_a, mat_axis_d)
        self.mat_axis_a, self.mat_axis_d = e1, e2
        self.planar = planar_keys(mat_axis_a=mat_axis_a, mat_axis_d=mat_axis_d)
        e1, e2 = np.atleast_2d(e1), np.atleast_2d(e2)
        self.fibres = np.stack([e1, e2, np.cross(e1, e2)], axis=1)  # (p, 3, 3): rows a_a

    def _axes_parameters(self) -> dict[str, object]:
        return {"mat_axis_a": self.mat_axis_a.tolist(), "mat_axis_d": self.mat_axis_d.tolist()}

    def w(self, x: np.ndarray, order: int) -> tuple:
        """(w (q,), dw/dx (q, 6), d2w/dx2 (q, 6, 6)) at x (q, 6): A_a : E then A_a : E^2."""
        raise NotImplementedError

    def _strain_response(self, F: np.ndarray, a: np.ndarray, order: int) -> tuple:
        """(psi, P, A) of w(x(E(F))) for 3D F (q, 3, 3) and axes a (q, 3, 3) (rows)."""
        q = F.shape[0]
        E = 0.5 * (np.swapaxes(F, 1, 2) @ F - _I3)
        E2 = E @ E
        x = np.concatenate(
            [np.einsum("qai,qij,qaj->qa", a, E, a), np.einsum("qai,qij,qaj->qa", a, E2, a)], 1
        )
        w, g, h = self.w(x, order)
        if order == 0:
            return w, None, None
        A0 = a[:, :, :, None] * a[:, :, None, :]  # (q, 3, 3, 3): A_a
        G2 = A0 @ E[:, None] + E[:, None] @ A0
        Gs = np.concatenate([A0, G2], 1)  # (q, 6, 3, 3)
        S = np.einsum("qk,qkij->qij", g, Gs)
        P = F @ S
        if order == 1:
            return w, P, None
        Gm = Gs.reshape(q, 6, 9)
        C = (np.swapaxes(Gm, 1, 2) @ (h @ Gm)).reshape(q, 3, 3, 3, 3)
        # sum_a w2_a (A_a dE + dE A_a), symmetric in K, L
        Aw = np.einsum("qa,qaij->qij", g[:, 3:], A0)
        T = np.einsum("qik,jl->qijkl", Aw, _I3) + np.einsum("ik,qlj->qijkl", _I3, Aw)
        C += 0.5 * (T + np.swapaxes(T, 3, 4))
        A = np.einsum("im,qlj->qijml", _I3, S) + np.einsum(
            "qiI,qIJKL,qmK->qiJmL", F, C, F, optimize=True
        )
        return w, P, A

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        q, d = F.shape[0], F.shape[-1]
        if self.fibres.shape[0] not in (1, q):
            raise MaterialError(
                f"{self.name} has {self.fibres.shape[0]} local axes (one per element or point) "
                f"but was given {q} deformation gradients"
            )
        F3 = F if d == 3 else np.broadcast_to(_I3, (q, 3, 3)).copy()
        if d == 2:
            F3[:, :2, :2] = F
        cof = cofactor(F3)
        J = det(F3, cof)
        ok = J > 0.0
        needs_j = self.uncoupled or self.has_bulk
        if needs_j and order > 0 and not ok.all():
            raise inverted_error(self.name, J, ok)
        Js = np.where(ok, J, 1.0)
        a = np.broadcast_to(self.fibres, (q, 3, 3))
        if self.uncoupled:
            s = Js ** (-1.0 / 3.0)
            Ft = s[:, None, None] * F3
            psi, Pt, At = self._strain_response(Ft, a, order)
        else:
            psi, P, A = self._strain_response(F3, a, order)
        if self.has_bulk:
            U, dU, ddU = self.bulk(Js, np.log(Js))
            psi = psi + U
        if needs_j:
            psi = np.where(ok, psi, np.inf)
        if order == 0:
            return MaterialResponse(psi)
        H = cof / Js[:, None, None]
        if self.uncoupled:
            PF = np.einsum("qij,qij->q", Pt, Ft)
            P = s[:, None, None] * Pt - PF[:, None, None] * H / 3.0
        if self.has_bulk:
            P = P + dU[:, None, None] * cof
        if order == 1:
            return MaterialResponse(psi, P[:, :d, :d].copy())
        if self.uncoupled:
            D = s[:, None, None, None, None] * (
                np.einsum("ik,jl->ijkl", _I3, _I3)[None] - np.einsum("qij,qkl->qijkl", F3, H) / 3.0
            )
            Pu = P - (dU[:, None, None] * cof if self.has_bulk else 0.0)
            Dm = D.reshape(q, 9, 9)
            A = (np.swapaxes(Dm, 1, 2) @ At.reshape(q, 9, 9) @ Dm).reshape(q, 3, 3, 3, 3)
            A -= (np.einsum("qkl,qmn->qklmn", Pu, H) + np.einsum("qkl,qmn->qklmn", H, Pu)) / 3.0
            A -= PF[:, None, None, None, None] * (
                np.einsum("qkl,qmn->qklmn", H, H) / 9.0 - np.einsum("qkn,qml->qklmn", H, H) / 3.0
            )
        if self.has_bulk:
            A = A + ddU[:, None, None, None, None] * np.einsum("qij,qkl->qijkl", cof, cof)
            A = A + dU[:, None, None, None, None] * det_hessian(F3)
        return MaterialResponse(psi, P[:, :d, :d].copy(), A[:, :d, :d, :d, :d].copy())
