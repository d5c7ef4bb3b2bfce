"""FEBio's ``muscle material`` (``FEMuscleMaterial``, Blemker et al. 2005): an uncoupled law of
the isochoric invariants x1 = I1~, x4 = I4~ = a0 . C~ a0, x5 = I5~ = a0 . C~^2 a0 along the fibre
a0, plus the bulk term U(J) of ``k`` (``pressure_model``). FEBio's DevStress is built from
dW/dx1, dW/dx4, dW/dx5 (its W1, W4, W5), which are those of

    W = G1 (x5/x4^2 - 1) + G2 acosh(w)^2 + 9 G3/16 (ln x4)^2 + Ff(sqrt(x4)),
    w = (x1 x4 - x5) / (2 sqrt(x4)),
    Ff' = smax/Lofl (Fp + activation Fa):  Fp = 0 (l <= Lofl), P1 (exp(P2 (l/Lofl - 1)) - 1) up
    to lam_max, then linear (P3 l/Lofl + P4, continuous with its slope); Fa = 9 (y - 0.4)^2,
    1 - 4 (1 - y)^2, 9 (y - 1.6)^2 on y = l/Lofl in [0.4, 0.6], [0.6, 1.4], [1.4, 1.6], else 0

(Ff integrated piece by piece). acosh(w)^2 and its derivatives are taken from their series
2u - u^2/3 + 4u^3/45 (u = w - 1) near w = 1, where FEBio uses beta = 1, ksi = -1/3. The chain
rule from the isochoric invariants to P and dP/dF is ``fibres/_fibres.py``'s (exponents 2/3,
2/3, 4/3), with I5's gradient 2 (F a (x) C a + F C a (x) a) and its second derivative. 3D only.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import check_input, cofactor, det, det_hessian
from tissuesim.materials.soft_tissue._hyperelastic import (
    HyperelasticMaterial,
    bulk_energy,
    inverted_error,
    parameter,
)
from tissuesim.materials.soft_tissue._hyperelastic import pressure_model as _pressure_model

__all__ = ["MuscleMaterial"]

_I3 = np.eye(3)


def _acosh2(w: np.ndarray) -> tuple:
    """(h, h', h'') of h(w) = acosh(w)^2, by its series near w = 1."""
    u = w - 1.0
    near = u < 1e-3
    ws = np.where(near, 2.0, w)
    a = np.arccosh(ws)
    r = np.sqrt(ws * ws - 1.0)
    beta = a / r
    h = np.where(near, 2 * u - u**2 / 3 + 4 * u**3 / 45, a * a)
    dh = np.where(near, 2 - 2 * u / 3 + 4 * u**2 / 15, 2 * beta)
    ddh = np.where(near, -2 / 3 + 8 * u / 15, 2 * (1 - ws * beta) / (ws * ws - 1.0))
    return h, dh, ddh


class MuscleMaterial(HyperelasticMaterial):
    """FEBio's muscle material: g1, g2, g3, smax (Pa), p1, p2, Lofl, lam_max, activation, k
    (Pa), pressure_model and the fibre ``fiber`` (one vector or one per element)."""

    name = "muscle_material"
    febio_name = "muscle material"
    uncoupled = True

    def __init__(
        self,
        *,
        g1: float = 0.0,
        g2: float = 0.0,
        g3: float = 0.0,
        p1: float | None = None,
        p2: float | None = None,
        Lofl: float | None = None,
        smax: float | None = None,
        lam_max: float | None = None,
        activation: float = 0.0,
        k: float | None = None,
        pressure_model: str | int = "default",
        fiber: object = (1.0, 0.0, 0.0),
    ) -> None:
        from tissuesim.materials.fibres._fibres import unit_vectors

        law = self.name
        self.g1, self.g2, self.g3 = (parameter(law, n, v) for n, v in
                                     (("g1", g1), ("g2", g2), ("g3", g3)))  # fmt: skip
        self.p1 = parameter(law, "p1", p1)
        self.p2 = parameter(law, "p2", p2, unit="")
        self.Lofl = parameter(law, "Lofl", Lofl, positive=True, unit="")
        self.smax = parameter(law, "smax", smax)
        self.lam_max = parameter(law, "lam_max", lam_max, unit="")
        self.activation = parameter(law, "activation", activation, unit="")
        self.k = parameter(law, "k", k, positive=True, meaning="bulk modulus")
        self.bulk_kind = _pressure_model(law, pressure_model)
        if self.lam_max < self.Lofl:
            raise MaterialError(f"{law}: lam_max must be >= Lofl")
        self.fiber = unit_vectors(law, "fiber", fiber)
        # small strain: the G2 term's shear (the G1 term is along the fibre only)
        self.mu = max(self.g2, self.g1, 1e-12 * self.k)
        self.lam = self.k - 2.0 * self.mu / 3.0

    def parameters(self) -> dict[str, object]:
        keys = ("g1", "g2", "g3", "p1", "p2", "Lofl", "smax", "lam_max", "activation", "k")
        return {**{n: getattr(self, n) for n in keys}, "fiber": self.fiber.tolist()}

    def __repr__(self) -> str:
        args = ", ".join(f"{n}={v!r}" for n, v in self.parameters().items())
        return f"{type(self).__name__}({args})"

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> MuscleMaterial:
        """This law with per-element fibres expanded to the integration points."""
        m = 1 if self.fiber.ndim == 1 else self.fiber.shape[0]
        if m in (1, n_points):
            return self
        if (n_cells is not None and m != n_cells) or n_points % m:
            raise MaterialError(f"{self.name}: {m} fibres given, read as one per element, but "
                                f"the body has {n_cells} elements")  # fmt: skip
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__)
        out.fiber = np.repeat(self.fiber, n_points // m, axis=0)
        return out

    def fibre(self, lam: np.ndarray) -> tuple:
        """(Ff, Ff', Ff'') of the fibre's stretch l."""
        L, lm, P1, P2 = self.Lofl, self.lam_max, self.p1, self.p2
        c = self.smax / L
        P3 = P1 * P2 * np.exp(P2 * (lm / L - 1))
        P4 = P1 * (np.exp(P2 * (lm / L - 1)) - 1) - P3 * lm / L
        mid = np.clip(lam, L, lm)
        e = np.exp(P2 * (mid / L - 1))
        ip = P1 * (L / P2 * (e - 1) - (mid - L))  # the integral of Fp up to min(l, lam_max)
        hi = np.maximum(lam - lm, 0.0)
        ip = ip + P3 / (2 * L) * ((lm + hi) ** 2 - lm**2) + P4 * hi
        fp = np.where(lam <= L, 0.0, np.where(lam < lm, P1 * (e - 1), P3 * lam / L + P4))
        dfp = np.where(lam <= L, 0.0, np.where(lam < lm, P1 * P2 / L * e, P3 / L))
        y = lam / L
        y1, y2, y3 = np.clip(y, 0.4, 0.6), np.clip(y, 0.6, 1.4), np.clip(y, 1.4, 1.6)
        ia = 3 * (y1 - 0.4) ** 3 + (y2 - 0.6) + 4 / 3 * ((1 - y2) ** 3 - 0.4**3)
        ia = L * (ia + 3 * ((y3 - 1.6) ** 3 + 0.2**3))
        fa = np.select(
            [(y > 0.4) & (y <= 0.6), (y > 0.6) & (y < 1.4), (y >= 1.4) & (y < 1.6)],
            [9 * (y - 0.4) ** 2, 1 - 4 * (1 - y) ** 2, 9 * (y - 1.6) ** 2],
            0.0,
        )
        dfa = (
            np.select(
                [(y > 0.4) & (y <= 0.6), (y > 0.6) & (y < 1.4), (y >= 1.4) & (y < 1.6)],
                [18 * (y - 0.4), 8 * (1 - y), 18 * (y - 1.6)],
                0.0,
            )
            / L
        )
        a = self.activation
        return c * (ip + a * ia), c * (fp + a * fa), c * (dfp + a * dfa)

    def w(self, x: np.ndarray, order: int) -> tuple:
        """(w, dw/dx (q, 3), d2w/dx2 (q, 3, 3)) at x = (x1, x4, x5)."""
        x1, x4, x5 = x[:, 0], x[:, 1], x[:, 2]
        G1, G2, G3 = self.g1, self.g2, self.g3
        s4 = np.sqrt(x4)
        om = (x1 * x4 - x5) / (2 * s4)
        h, dh, ddh = _acosh2(om)
        Ff, dF, ddF = self.fibre(s4)
        ln4 = np.log(x4)
        w = G1 * (x5 / x4**2 - 1) + G2 * h + 9 * G3 / 16 * ln4**2 + Ff
        q = x.shape[0]
        dom = np.stack([s4 / 2, (x1 * x4 + x5) / (4 * s4**3), -1 / (2 * s4)], 1)
        g = G2 * dh[:, None] * dom
        g[:, 1] += -2 * G1 * x5 / x4**3 + 9 * G3 / 8 * ln4 / x4 + dF / (2 * s4)
        g[:, 2] += G1 / x4**2
        hs = np.zeros((q, 3, 3))
        if order >= 2:
            ddom = np.zeros((q, 3, 3))
            ddom[:, 0, 1] = ddom[:, 1, 0] = 1 / (4 * s4)
            ddom[:, 1, 1] = -(x1 * x4 + 3 * x5) / (8 * s4**5)
            ddom[:, 1, 2] = ddom[:, 2, 1] = 1 / (4 * s4**3)
            hs = G2 * (ddh[:, None, None] * dom[:, :, None] * dom[:, None, :]
                       + dh[:, None, None] * ddom)  # fmt: skip
            hs[:, 1, 1] += 6 * G1 * x5 / x4**4 + 9 * G3 / 8 * (1 - ln4) / x4**2
            hs[:, 1, 1] += (ddF - dF / s4) / (4 * x4)
            hs[:, 1, 2] += -2 * G1 / x4**3
            hs[:, 2, 1] += -2 * G1 / x4**3
        return w, g, hs

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        q = F.shape[0]
        if F.shape[-1] != 3:
            raise MaterialError(f"{self.name} is 3D only")
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0
        if order > 0 and not ok.all():
            raise inverted_error(self.name, J, ok)
        Js = np.where(ok, J, 1.0)
        Fs = np.where(ok[:, None, None], F, _I3)
        a = np.broadcast_to(self.fiber, (q, 3))
        C = np.swapaxes(Fs, 1, 2) @ Fs
        Ca = np.einsum("qij,qj->qi", C, a)
        Fa = np.einsum("qij,qj->qi", Fs, a)
        FCa = np.einsum("qij,qj->qi", Fs, Ca)
        inv = np.stack(
            [np.einsum("qij,qij->q", Fs, Fs), np.einsum("qi,qi->q", a, Ca),
             np.einsum("qi,qi->q", Ca, Ca)], 1
        )  # fmt: skip
        e = np.array([2.0 / 3.0, 2.0 / 3.0, 4.0 / 3.0])
        s = Js[:, None] ** (-e)
        xb = inv * s
        w, g, hs = self.w(xb, order)
        U, dU, ddU = bulk_energy(self.bulk_kind, self.k, Js, np.log(Js))
        psi = np.where(ok, w + U, np.inf)
        if order == 0:
            return MaterialResponse(psi)
        eib = e * xb
        Wa = g * s
        WJ = -np.einsum("qa,qa->q", g, eib) / Js + dU
        G = np.stack(
            [2 * Fs, 2 * np.einsum("qi,qj->qij", Fa, a),
             2 * (np.einsum("qi,qj->qij", Fa, Ca) + np.einsum("qi,qj->qij", FCa, a))], 1
        )  # fmt: skip
        P = np.einsum("qa,qaij->qij", Wa, G) + WJ[:, None, None] * cof
        if order == 1:
            return MaterialResponse(psi, P)
        Wab = hs * s[:, :, None] * s[:, None, :]
        WaJ = -s * (np.einsum("qab,qb->qa", hs, eib) + e * g) / Js[:, None]
        WJJ = np.einsum("qab,qa,qb->q", hs, eib, eib) + np.einsum("qa,qa->q", g, e * (e + 1) * xb)
        WJJ = WJJ / Js**2 + ddU
        d = np.einsum("ik,jl->ijkl", _I3, _I3)
        H1 = 2 * d
        H4 = 2 * np.einsum("ik,qj,ql->qijkl", _I3, a, a)
        FFt = Fs @ np.swapaxes(Fs, 1, 2)
        H5 = np.einsum("ik,ql,qj->qijkl", _I3, a, Ca) + np.einsum("ik,ql,qj->qijkl", _I3, Ca, a)
        H5 = H5 + np.einsum("qi,qk,lj->qijkl", Fa, Fa, _I3)
        H5 = H5 + np.einsum("qi,qkj,ql->qijkl", Fa, Fs, a)
        H5 = H5 + np.einsum("qil,qk,qj->qijkl", Fs, Fa, a)
        H5 = 2 * (H5 + np.einsum("qik,ql,qj->qijkl", FFt, a, a))
        A = Wa[:, 0, None, None, None, None] * H1 + Wa[:, 1, None, None, None, None] * H4
        A = A + Wa[:, 2, None, None, None, None] * H5
        A = A + np.einsum("qab,qaij,qbkl->qijkl", Wab, G, G)
        A = A + np.einsum("qa,qaij,qkl->qijkl", WaJ, G, cof)
        A = A + np.einsum("qa,qij,qakl->qijkl", WaJ, cof, G)
        A = A + WJJ[:, None, None, None, None] * np.einsum("qij,qkl->qijkl", cof, cof)
        A = A + WJ[:, None, None, None, None] * det_hessian(Fs)
        return MaterialResponse(psi, P, A)
