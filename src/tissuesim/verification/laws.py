"""Homogeneous uniaxial, equibiaxial and simple-shear stress of every registered law against
closed forms derived by hand from the deformation (not from the code).

Isochoric deformations (J = 1) with the pressure-like terms eliminated, as a traction-free
face does for an incompressible material:

    uniaxial     F = diag(l, l^-1/2, l^-1/2)   s = P11 - P22 l^-3/2
    equibiaxial  F = diag(l, l, l^-2)          s = P11 - P33 l^-3
    shear        F = I + g e1 (x) e2           s = P12

A law W(I1, I2, J) has P = 2 W1 F + 2 W2 (I1 F - F C) + WJ cof F; at J = 1 the WJ term is a
pressure (cof F = F^-T) that the combinations remove, leaving
    uniaxial 2 (l - l^-2) (W1 + W2 / l), equibiaxial 2 (l - l^-5) (W1 + l^2 W2),
    shear 2 g (W1 + W2) (I1 = I2 = 3 + g^2, (I1 F - F C)_12 = g).
W1, W2 of each law: neo-Hookean forms mu / 2, 0; St Venant-Kirchhoff (lam/8 (I1 - 3)^2 +
mu/4 (I1^2 - 2 I2 - 2 I1 + 3)) lam (I1 - 3)/4 + mu (I1 - 1)/2, -mu/2; Mooney-Rivlin c1, c2;
Yeoh sum i c_i (I1 - 3)^(i-1); Holmes-Mow (at J = 1) exp(Q) (2 mu - lam)/4, exp(Q) lam/4 with
Q = beta/Ha ((2 mu - lam)(I1 - 3) + lam (I2 - 3)), Ha = lam + 2 mu, and uncoupled mu/2
exp(beta (I1 - 3)), 0; Arruda-Boyce unconstrained ksi N beta / (2 sqrt(3 N I1)), 0 with beta
the inverse Langevin function of sqrt(I1 / (3 N)) (solved, not the law's series);
Veronda-Westmann c1 c2 exp(c2 (I1 - 3)), -c1 c2 / 2;
Arruda-Boyce (mu sum_i C_i (I1^i - 3^i) / N^(i-1), FEBio's C = 1/2, 1/10, 11/350, 19/1750,
519/134750) mu sum_i i C_i I1^(i-1) / N^(i-1). Ogden (principal stretches): uniaxial
sum c/m (l^(m-1) - l^(-m/2-1)), equibiaxial sum c/m (l^(m-1) - l^(-2m-1)), shear sum c/m (L^m -
L^-m)/(L + 1/L), L = g/2 + sqrt(1 + g^2/4).
Not invariant-based: linear (P = 2 mu eps + lam tr eps I, eps = sym F - I) and fixed corotated
(P = 2 mu (F - R) + lam (J - 1) cof F; diagonal R = I, shear R12 = g / sqrt(4 + g^2)).
"""

from __future__ import annotations

import numpy as np

from tissuesim.materials import make_material
from tissuesim.verification.result import Check

__all__ = ["LAWS", "checks"]

L, G = 1.3, 0.4  # the stretch and the shear of every check
MU, LAM = 400.0, 900.0
TOL = 1e-8
_OGDEN = {"c": [300.0, -40.0, 20.0], "m": [4.0, -2.0, 9.0]}


def _invariant(w):
    """Closed forms (uniaxial, equibiaxial, shear) from W1, W2 = w(I1, I2)."""
    W1, W2 = w(L**2 + 2 / L, 2 * L + L**-2)
    uni = 2 * (L - L**-2) * (W1 + W2 / L)
    W1, W2 = w(2 * L**2 + L**-4, L**4 + 2 * L**-2)
    bi = 2 * (L - L**-5) * (W1 + L**2 * W2)
    W1, W2 = w(3 + G**2, 3 + G**2)
    return uni, bi, 2 * G * (W1 + W2)


def _ab(mu, N):
    # W = mu sum_i C_i (I1^i - 3^i) / N^(i-1): W1 = mu sum_i i C_i I1^(i-1) / N^(i-1)
    C = (1 / 2, 1 / 10, 11 / 350, 19 / 1750, 519 / 134750)
    return lambda I1, I2: (mu * sum((i + 1) * c * I1**i / N**i for i, c in enumerate(C)), 0.0)


def _ogden():
    terms = list(zip(_OGDEN["c"], _OGDEN["m"], strict=True))
    Ls = G / 2 + np.sqrt(1 + G**2 / 4)
    return (
        sum(c / m * (L ** (m - 1) - L ** (-m / 2 - 1)) for c, m in terms),
        sum(c / m * (L ** (m - 1) - L ** (-2 * m - 1)) for c, m in terms),
        sum(c / m * (Ls**m - Ls**-m) / (Ls + 1 / Ls) for c, m in terms),
    )


def _hencky(mu):
    # Kirchhoff stress 2 mu ln(lambda_a) + lam ln J: at J = 1 the lam term is a pressure the
    # combinations drop; P_aa = tau_a / lambda_a; shear by the principal stretches of
    # F = I + g e1 (x) e2: Ls = g/2 + sqrt(1 + g^2/4) and 1/Ls, at angle theta from x with
    # tan(2 theta) = 2/g; P12 = sum_a tau_a (R_a . e1)(N_a . e2) / ..., written as
    # 2 mu ln(Ls) (Ls + 1/Ls)^-1 * 2 (from sigma_12 = 2 mu ln(Ls) sin(2 phi), sin(2 phi) =
    # 2 / (Ls + 1/Ls), and P = sigma at J = 1 for the 12 component of a shear)
    t, b = L**-0.5, L**-2
    uni = 2 * mu * np.log(L) / L - 2 * mu * np.log(t) / t * t / L
    bi = 2 * mu * np.log(L) / L - 2 * mu * np.log(b) / b * b / L
    Ls = G / 2 + np.sqrt(1 + G**2 / 4)
    return uni, bi, 2 * mu * np.log(Ls) * 2 / (Ls + 1 / Ls)


def _linear():
    t = L**-0.5
    tr = (L - 1) + 2 * (t - 1)
    uni = (2 * MU * (L - 1) + LAM * tr) - (2 * MU * (t - 1) + LAM * tr) * t / L
    b = L**-2
    tr = 2 * (L - 1) + (b - 1)
    bi = (2 * MU * (L - 1) + LAM * tr) - (2 * MU * (b - 1) + LAM * tr) * b / L
    return uni, bi, MU * G


def _corotated():
    t, b = L**-0.5, L**-2
    uni = 2 * MU * (L - 1) - 2 * MU * (t - 1) * t / L
    bi = 2 * MU * (L - 1) - 2 * MU * (b - 1) * b / L
    return uni, bi, 2 * MU * (G - G / np.sqrt(4 + G**2))


def _yeoh(c):
    return lambda I1, I2: (sum((i + 1) * ci * (I1 - 3) ** i for i, ci in enumerate(c)), 0.0)


def _vw(c1, c2):
    return lambda I1, I2: (c1 * c2 * np.exp(c2 * (I1 - 3)), -c1 * c2 / 2)


def _hm(E, v, beta):
    # Ha/(4 beta) exp(Q), Q = beta/Ha ((2 mu - lam)(I1 - 3) + lam (I2 - 3)) at J = 1:
    # W1 = Ha/(4 beta) exp(Q) beta (2 mu - lam)/Ha = exp(Q) (2 mu - lam)/4, W2 = exp(Q) lam/4
    mu, lam = E / (2 * (1 + v)), E * v / ((1 + v) * (1 - 2 * v))
    ha = lam + 2 * mu

    def w(I1, I2):
        eQ = np.exp(beta / ha * ((2 * mu - lam) * (I1 - 3) + lam * (I2 - 3)))
        return eQ * (2 * mu - lam) / 4, eQ * lam / 4

    return w


def _abu(ksi, N):
    # FEBio's Arruda-Boyce unconstrained: W1 = ksi N beta / (2 sqrt(3 N I1)), beta the inverse
    # Langevin function of the chain stretch sqrt(I1 / (3 N)) (coth(beta) - 1/beta = stretch,
    # solved here; the law sums its series)
    from scipy.optimize import brentq

    def w(I1, I2):
        a = np.sqrt(I1 / (3 * N))
        beta = brentq(lambda b: 1 / np.tanh(b) - 1 / b - a, 1e-9, 1e3, xtol=1e-15, rtol=1e-15)
        return ksi * N * beta / (2 * np.sqrt(3 * N * I1)), 0.0

    return w


_NEO = {"shear_modulus": MU, "lame_lambda": LAM}
_MR = {"c1": 150.0, "c2": 40.0, "k": 3000.0}
_YEOH = {"c1": 150.0, "c2": 30.0, "c3": 5.0, "k": 3000.0}
_VW = {"c1": 200.0, "c2": 1.5, "k": 3000.0}
_ABP = {"mu": 300.0, "N": 4.0, "k": 3000.0}

#: law name -> (parameters, closed forms (uniaxial, equibiaxial, shear))
LAWS = {
    "neo_hookean": (_NEO, lambda: _invariant(lambda I1, I2: (MU / 2, 0.0))),
    "course_neo_hookean": (_NEO, lambda: _invariant(lambda I1, I2: (MU / 2, 0.0))),
    "stvk": (
        _NEO,
        lambda: _invariant(lambda I1, I2: (LAM * (I1 - 3) / 4 + MU * (I1 - 1) / 2, -MU / 2)),
    ),  # fmt: skip
    "linear": (_NEO, _linear),
    "fixed_corotated": (_NEO, _corotated),
    "mooney_rivlin": (_MR, lambda: _invariant(lambda I1, I2: (150.0, 40.0))),
    "coupled_mooney_rivlin": (_MR, lambda: _invariant(lambda I1, I2: (150.0, 40.0))),
    "yeoh": (_YEOH, lambda: _invariant(_yeoh([150.0, 30.0, 5.0]))),
    "coupled_yeoh": (_YEOH, lambda: _invariant(_yeoh([150.0, 30.0, 5.0]))),
    "veronda_westmann": (_VW, lambda: _invariant(_vw(200.0, 1.5))),
    "coupled_veronda_westmann": (_VW, lambda: _invariant(_vw(200.0, 1.5))),
    "arruda_boyce": (_ABP, lambda: _invariant(_ab(300.0, 4.0))),
    "coupled_arruda_boyce": (_ABP, lambda: _invariant(_ab(300.0, 4.0))),
    "holmes_mow": ({"E": 1000.0, "v": 0.3, "beta": 0.5}, lambda: _invariant(_hm(1000.0, 0.3, 0.5))),
    "uncoupled_holmes_mow": (
        {"mu": 300.0, "beta": 2.0, "k": 3000.0},
        lambda: _invariant(lambda I1, I2: (150.0 * np.exp(2.0 * (I1 - 3)), 0.0)),
    ),
    "arruda_boyce_unconstrained": (
        {"ksi": 300.0, "N": 4.0, "kappa": 3000.0},
        lambda: _invariant(_abu(300.0, 4.0)),
    ),
    "isotropic_hencky": ({"E": 1000.0, "v": 0.3}, lambda: _hencky(1000.0 / 2.6)),
    "ogden": ({**_OGDEN, "k": 3000.0}, _ogden),
    "ogden_unconstrained": ({**_OGDEN, "cp": 3000.0}, _ogden),
}


def measured(law) -> tuple[float, float, float]:
    """The law's (uniaxial, equibiaxial, shear) combinations at the three deformations."""
    t, b = L**-0.5, L**-2
    F = np.zeros((3, 3, 3))
    F[0] = np.diag([L, t, t])
    F[1] = np.diag([L, L, b])
    F[2] = np.eye(3)
    F[2, 0, 1] = G
    P = law.stress(F)
    return (
        float(P[0, 0, 0] - P[0, 1, 1] * t / L),
        float(P[1, 0, 0] - P[1, 2, 2] * b / L),
        float(P[2, 0, 1]),
    )


def checks(laws: dict | None = None) -> list[Check]:
    """Three checks per law of ``laws`` (default ``LAWS``): the law built by name, its stress
    combinations against the closed forms (relative 1e-8)."""
    out = []
    for name, (params, closed) in (laws or LAWS).items():
        law = make_material(name, **params)
        for what, ref, got in zip(
            (f"uniaxial P (l = {L})", f"equibiaxial P (l = {L})", f"shear P12 (g = {G})"),
            closed(),
            measured(law),
            strict=True,
        ):
            out.append(Check(f"{name}", what, float(ref), got, TOL))
    return out
