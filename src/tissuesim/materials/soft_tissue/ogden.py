"""Ogden, FEBio's uncoupled ``Ogden`` and its coupled ``Ogden unconstrained``, N terms.

    ogden                  W = sum_i c_i / m_i^2 (lb1^m_i + lb2^m_i + lb3^m_i - 3) + k/2 (ln J)^2
                           lb_a = J^(-1/3) lambda_a, the isochoric principal stretches
    ogden_unconstrained    W = sum_i c_i / m_i^2 (l1^m_i + l2^m_i + l3^m_i - 3 - m_i ln J)
                               + cp/2 (J - 1)^2

Written on T_i = sum_a x_a^(p_i), x_a the eigenvalues of C = F^T F, p_i = m_i / 2 (in 2D the
out-of-plane x_3 = 1 adds 1): sum_a lb_a^m_i = J^(-m_i/3) T_i, so W = W(T_1..T_N, J). With
C = V diag(x) V^T (from the SVD of F = U diag(s) V^T, x = s^2) and f = F V = U diag(s), a
spectral energy sum_a g(x_a) with per-point weights (g = sum_i w_i x^(p_i)) has

    S = 2 V diag(g'(x)) V^T,   P = F S = 2 f diag(g'(x)) V^T
    dP_ij/dF_kl = delta_ik S_lj + 2 sum_ab G_ab f_ia V_jb (f_kb V_la + f_ka V_lb)
    G_ab = (g'(x_a) - g'(x_b)) / (x_a - x_b),   G_aa = g''(x_a)  (Daleckii-Krein)

The divided differences of the powers are taken as x_a^(r-1) expm1(r t) / expm1(t),
t = ln(x_b / x_a), with its Taylor series for |t| < 1e-5: exact at equal stretches (F = I,
equibiaxial) and without cancellation when they nearly coincide, so no eigenvector choice matters.
The J terms add psi_J cof, psi_JJ cof (x) cof + psi_J d2J and the mixed d2psi/dT_i dJ terms.

Small strain: mu = sum_i c_i / 2; lam = k - 2 mu / 3 (ogden), cp (ogden_unconstrained).
J <= 0: energy +inf, stress and tangent raise InvertedElementError.
Shapes: F (q, d, d) -> psi (q,), P (q, d, d), A (q, d, d, d, d); 2D is plane strain.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import (
    bcast,
    check_input,
    cofactor,
    det,
    det_hessian,
)
from tissuesim.materials.soft_tissue._hyperelastic import (
    HyperelasticMaterial,
    bulk_energy,
    inverted_error,
    parameter,
    parameter_list,
)
from tissuesim.materials.soft_tissue._hyperelastic import pressure_model as _pressure_model

__all__ = ["Ogden", "OgdenUnconstrained", "power_divided_difference"]

_MAX_TERMS = 6  # FEBio's c1..c6, m1..m6; the list form takes any number


def power_divided_difference(xa: np.ndarray, xb: np.ndarray, r: np.ndarray) -> np.ndarray:
    """(xb^r - xa^r) / (xb - xa) for positive xa, xb (broadcast), r x^(r-1) where they are
    equal; accurate to round-off for nearly equal arguments."""
    t = np.log(xb) - np.log(xa)
    small = np.abs(t) < 1e-5
    ts = np.where(small, 1.0, t)
    ratio = np.where(
        small,
        r * (1.0 + (r - 1.0) * t / 2.0 + (r - 1.0) * (r - 2.0) * t * t / 6.0),
        np.expm1(r * ts) / np.expm1(ts),
    )
    return xa ** (r - 1.0) * ratio


def _terms(law: str, c, m, indexed: dict[str, object]) -> tuple[np.ndarray, np.ndarray]:
    """(c, m) arrays from the list form (c = [...], m = [...]) or FEBio's c1..c6, m1..m6."""
    given = {key: value for key, value in indexed.items() if value is not None}
    if c is not None or m is not None:
        if given:
            raise MaterialError(
                f"{law}: give the terms either as lists c = [...], m = [...] or as FEBio's "
                f"c1..c6, m1..m6, not both (got c/m and {', '.join(sorted(given))})"
            )
        if c is None or m is None:
            raise MaterialError(f"{law} needs both lists c (Pa) and m, of the same length")
        cs, ms = parameter_list(law, "c", c), parameter_list(law, "m", m, unit="")
        if len(cs) != len(ms):
            raise MaterialError(
                f"{law}: c and m must have the same length (one c_i and m_i per term), "
                f"got {len(cs)} and {len(ms)}"
            )
    else:
        cs = [parameter(law, f"c{i}", given.get(f"c{i}", 0.0)) for i in range(1, _MAX_TERMS + 1)]
        ms = [
            parameter(law, f"m{i}", given.get(f"m{i}", 1.0), unit="")  # FEBio's default m_i = 1
            for i in range(1, _MAX_TERMS + 1)
        ]
        if not any(f"c{i}" in given for i in range(1, _MAX_TERMS + 1)):
            raise MaterialError(f"{law} needs its terms: c = [...], m = [...] or c1, m1, ...")
    keep = [i for i, ci in enumerate(cs) if ci != 0.0] or [0]
    for i in keep:
        if ms[i] == 0.0:
            raise MaterialError(f"{law}: m{i + 1} (exponent of term {i + 1}) must not be 0")
    return np.array([cs[i] for i in keep]), np.array([ms[i] for i in keep])


class _OgdenBase(HyperelasticMaterial):
    c: np.ndarray
    m: np.ndarray

    def _init_terms(self, c, m, indexed: dict[str, object]) -> None:
        self.c, self.m = _terms(self.name, c, m, indexed)
        self.mu = 0.5 * float(self.c.sum())

    def _weights(self, J, T, lnJ, order):
        """(psi, w (q, N) = dpsi/dT_i, psi_J, v (q, N) = d2psi/dT_i dJ or None, psi_JJ)."""
        raise NotImplementedError

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        d = F.shape[-1]
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0  # also False for NaN
        if order > 0 and not ok.all():
            raise inverted_error(self.name, J, ok)
        Fs = np.where(bcast(ok, 3), F, np.eye(d))
        Js = np.where(ok, J, 1.0)
        p = 0.5 * self.m  # (N,) exponents of x = lambda^2
        if order == 0:
            x = np.linalg.svd(Fs, compute_uv=False) ** 2
        else:
            U, s, Vt = np.linalg.svd(Fs)
            x, V, f = s**2, np.swapaxes(Vt, 1, 2), U * s[:, None, :]
        X = x[:, None, :] ** (p[None, :, None] - 1.0)  # (q, N, d): x_a^(p_i - 1)
        T = np.einsum("qna,qa->qn", X, x) + (3.0 - d)
        psi, w, psi_J, v, psi_JJ = self._weights(Js, T, np.log(Js), order)
        psi = np.where(ok, psi, np.inf)
        if order == 0:
            return MaterialResponse(psi)
        g1 = np.einsum("qn,qna->qa", w * p, X)  # g'(x_a)
        S = 2.0 * (V * g1[:, None, :]) @ np.swapaxes(V, 1, 2)  # 2 V diag(g') V^T
        P = F @ S + bcast(psi_J, 3) * cof
        if order == 1:
            return MaterialResponse(psi, P)
        xa, xb = x[:, None, :, None], x[:, None, None, :]
        D = power_divided_difference(xa, xb, p[None, :, None, None] - 1.0)  # (q, N, d, d)
        G = np.einsum("qn,qnab->qab", w * p, D)
        G = 0.5 * (G + np.swapaxes(G, 1, 2))
        q, n = F.shape[0], d * d
        # T[q, a, b, i, j] = f_ia V_jb; A = sum_ab T_ab (x) 2 G_ab (T_ab + T_ba) + the J terms,
        # all as one batched product of (rows) x (rows)
        T = f.transpose(0, 2, 1)[:, :, None, :, None] * V.transpose(0, 2, 1)[:, None, :, None, :]
        Tm = T.reshape(q, n, n)  # rows (a, b), columns (i, j)
        Ts = np.swapaxes(T, 1, 2).reshape(q, n, n)  # row (a, b) holds T_ba
        hJ = bcast(psi_JJ, 3) * cof
        rows, cols = [Tm, cof.reshape(q, 1, n)], [2.0 * G.reshape(q, n, 1) * (Tm + Ts)]
        if v is not None:  # d2psi/dT_i dJ: Pv (x) cof + cof (x) Pv
            gv = np.einsum("qn,qna->qa", v * p, X)
            Pv = 2.0 * (f * gv[:, None, :]) @ np.swapaxes(V, 1, 2)
            rows.append(Pv.reshape(q, 1, n))
            hJ = hJ + Pv
            cols += [hJ.reshape(q, 1, n), cof.reshape(q, 1, n)]
        else:
            cols.append(hJ.reshape(q, 1, n))
        A = np.swapaxes(np.concatenate(rows, 1), 1, 2) @ np.concatenate(cols, 1)
        A = A.reshape(q, d, d, d, d)
        A += np.eye(d)[None, :, None, :, None] * np.swapaxes(S, 1, 2)[:, None, :, None, :]
        A += bcast(psi_J, 5) * det_hessian(F)
        return MaterialResponse(psi, P, A)

    def _term_parameters(self) -> dict[str, object]:
        return {"c": self.c.tolist(), "m": self.m.tolist()}


class Ogden(_OgdenBase):
    """FEBio's (uncoupled) Ogden: sum_i c_i/m_i^2 (sum_a lb_a^m_i - 3) + k/2 (ln J)^2 on the
    isochoric stretches; c_i and k in Pa, m_i != 0. Terms as lists ``c``, ``m`` or as FEBio's
    ``c1``..``c6``, ``m1``..``m6`` (an m_i not given is 1, as in FEBio)."""

    name = "ogden"
    febio_name = "Ogden"

    def __init__(
        self,
        *,
        c: list[float] | None = None,
        m: list[float] | None = None,
        k: float | None = None,
        c1: float | None = None,
        c2: float | None = None,
        c3: float | None = None,
        c4: float | None = None,
        c5: float | None = None,
        c6: float | None = None,
        m1: float | None = None,
        m2: float | None = None,
        m3: float | None = None,
        m4: float | None = None,
        m5: float | None = None,
        m6: float | None = None,
        pressure_model: str | int = "default",
    ) -> None:
        indexed = dict(c1=c1, c2=c2, c3=c3, c4=c4, c5=c5, c6=c6)
        indexed.update(m1=m1, m2=m2, m3=m3, m4=m4, m5=m5, m6=m6)
        self._init_terms(c, m, indexed)
        self.k = parameter(self.name, "k", k, positive=True, meaning="bulk modulus")
        self.bulk_kind = _pressure_model(self.name, pressure_model)
        self.lam = self.k - 2.0 * self.mu / 3.0
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        return {**self._term_parameters(), "k": self.k, **self._bulk_parameter()}

    def _weights(self, J, T, lnJ, order):
        c, m, k = self.c, self.m, self.k
        e = J[:, None] ** (-m / 3.0)  # (q, N)
        U, dU, ddU = bulk_energy(self.bulk_kind, k, J, lnJ)
        psi = (c / m**2 * (e * T - 3.0)).sum(axis=1) + U
        w = c / m**2 * e
        cT = (c / (3.0 * m) * e * T).sum(axis=1)
        psi_J = dU - cT / J
        v = -c / (3.0 * m) * e / J[:, None]
        cTT = (c / (3.0 * m) * (m / 3.0 + 1.0) * e * T).sum(axis=1)
        psi_JJ = ddU + cTT / J**2
        return psi, w, psi_J, v, psi_JJ


class OgdenUnconstrained(_OgdenBase):
    """FEBio's coupled ``Ogden unconstrained``: sum_i c_i/m_i^2 (sum_a l_a^m_i - 3 - m_i ln J)
    + cp/2 (J - 1)^2; c_i and cp in Pa, m_i != 0 (terms as for ``Ogden``)."""

    name = "ogden_unconstrained"
    febio_name = "Ogden unconstrained"
    bulk_kind = "quadratic_J"  # cp/2 (J - 1)^2

    def __init__(
        self,
        *,
        c: list[float] | None = None,
        m: list[float] | None = None,
        cp: float | None = None,
        c1: float | None = None,
        c2: float | None = None,
        c3: float | None = None,
        c4: float | None = None,
        c5: float | None = None,
        c6: float | None = None,
        m1: float | None = None,
        m2: float | None = None,
        m3: float | None = None,
        m4: float | None = None,
        m5: float | None = None,
        m6: float | None = None,
    ) -> None:
        indexed = dict(c1=c1, c2=c2, c3=c3, c4=c4, c5=c5, c6=c6)
        indexed.update(m1=m1, m2=m2, m3=m3, m4=m4, m5=m5, m6=m6)
        self._init_terms(c, m, indexed)
        self.cp = parameter(self.name, "cp", cp, meaning="bulk-like modulus")
        self.k = self.lam = self.cp
        self._check_moduli()

    def parameters(self) -> dict[str, object]:
        return {**self._term_parameters(), "cp": self.cp}

    def _weights(self, J, T, lnJ, order):
        c, m, cp = self.c, self.m, self.cp
        psi = (c / m**2 * (T - 3.0)).sum(axis=1) - (c / m).sum() * lnJ + 0.5 * cp * (J - 1.0) ** 2
        w = np.broadcast_to(c / m**2, T.shape)
        s = (c / m).sum()
        psi_J = cp * (J - 1.0) - s / J
        psi_JJ = cp + s / J**2
        return psi, w, psi_J, None, psi_JJ
