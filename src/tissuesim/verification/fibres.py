"""Homogeneous stress of the fibre-reinforced laws (and, from ``orthotropic.py``, the
orthotropic ones) against closed forms derived by hand from
FEBio's energies (not from the code): uniaxial stretch along and across the fibres (across: the
fibres shorten and carry nothing), equibiaxial stretch and simple shear.

The deformations are isochoric (J = 1, so the isochoric invariants are the plain ones), and each
check is a stress combination from which the pressure-like term W_J cof F drops, as in
``laws.py``:

    uniaxial     F = diag(l, l^-1/2, l^-1/2)   s = P11 - P22 l^-3/2
    equibiaxial  F = diag(l, l, l^-2)          s = P11 - P33 l^-3
    shear        F = I + g e1 (x) e2           s = P12

With W(I1, I2, I4_f) and a fibre a_f (unit, reference), P = 2 W1 F + 2 W2 (I1 F - F C)
+ sum_f 2 W4_f (F a_f) (x) a_f + W_J cof F, and I4_f = |F a_f|^2, so

    uniaxial     s = 2 (l - l^-2) (W1 + W2 / l)     + sum_f 2 W4_f (l a1^2 - l^-2 a2^2)
    equibiaxial  s = 2 (l - l^-5) (W1 + l^2 W2)     + sum_f 2 W4_f (l a1^2 - l^-5 a3^2)
    shear        s = 2 g (W1 + W2)                  + sum_f 2 W4_f (a1 + g a2) a2

(a = (a1, a2, a3) of each fibre). The laws' derivatives:

* Holzapfel-Gasser-Ogden (both variants): W = c/2 (I1 - 3) + sum_f phi(E_f), E_f = kappa
  (I1 - 3) + (1 - 3 kappa) (I4_f - 1), phi = k1 / (2 k2) (exp(k2 E^2) - 1) for E >= 0, else 0;
  W1 = c/2 + kappa sum_f phi'(E_f), W4_f = (1 - 3 kappa) phi'(E_f), phi'(E) = k1 E exp(k2 E^2)
  (0 for E < 0), W2 = 0. The families are a = e1 cos(gamma) +- e2 sin(gamma) of the local axes
  (``mat_axis_a`` = e1; e2 in the plane of ``mat_axis_a`` and ``mat_axis_d``).
* trans-iso Mooney-Rivlin: W1 = c1, W2 = c2, W4 = s(lb) / (2 lb^2), lb = sqrt(I4), with lb dWf/dlb
  = s(lb) = 0 (lb < 1), c3 (exp(c4 (lb - 1)) - 1) (1 <= lb < lam_max), c5 lb + c6 past lam_max,
  c6 = c3 (exp(c4 (lam_max - 1)) - 1) - c5 lam_max.
* coupled trans-iso Mooney-Rivlin: the same W1, W2, W4 on I1, I2, I4 (J = 1 here).
* TC nonlinear orthotropic: W1 = c1, W2 = c2 and a family along each axis with
  W4_a = beta_a ksi_a (l_a - 1)^(beta_a - 1) / (2 l_a), l_a = sqrt(I4_a) > 1 (else 0).
* trans-iso Veronda-Westmann: W1 = c1 c2 exp(c2 (I1 - 3)), W2 = -c1 c2 / 2, W4 the fibre of
  trans-iso Mooney-Rivlin.
* FEBio's fibre laws alone (a solid mixture's components; J = 1, so the uncoupled forms' I4b is
  I4), W1 = W2 = 0 and, for a taut fibre (0 when slack):
  fiber-exp-pow, W = ksi / (alpha beta) (exp(alpha x^beta) - 1), x = I4 - lam0^2 (uncoupled:
  I4 - 1): W4 = ksi x^(beta - 1) exp(alpha x^beta) (its shear term mu is 0 here);
  fiber-pow-linear, I0 = lam0^2, ksi = E / (4 (beta - 1)) I0^-3/2 (I0 - 1)^(2 - beta):
  W4 = ksi (I4 - 1)^(beta - 1) for 1 <= I4 < I0, else b - E / (2 sqrt(I4)) with
  b = ksi (I0 - 1)^(beta - 1) + E / (2 lam0);
  fiber-exp-linear: trans-iso Mooney-Rivlin's fibre, W4 = s(lb) / (2 lb^2).
"""

from __future__ import annotations

import math

import numpy as np

from tissuesim.materials import make_material
from tissuesim.verification.laws import TOL, G, L
from tissuesim.verification.result import Check

__all__ = ["CASES", "checks", "combination"]

_HGO = {"c": 200.0, "k1": 1000.0, "k2": 2.0, "kappa": 0.1, "gamma": 30.0, "k": 3000.0}
_TIMR = {"c1": 150.0, "c2": 40.0, "c3": 20.0, "c4": 8.0, "c5": 600.0, "lam_max": 1.25}
_ACROSS = {"mat_axis_a": (0.0, 1.0, 0.0), "mat_axis_d": (1.0, 0.0, 0.0)}  # families about e2
_SQ = 1.0 / math.sqrt(2.0)


def _hgo(fibres, i1, i4s):
    """(W1, W2, [W4_f]) of HGO at I1 and each family's I4 (closed form above)."""
    c, k1, k2, kappa = _HGO["c"], _HGO["k1"], _HGO["k2"], _HGO["kappa"]
    d = []
    for i4 in i4s:
        E = kappa * (i1 - 3.0) + (1.0 - 3.0 * kappa) * (i4 - 1.0)
        d.append(k1 * E * math.exp(k2 * E * E) if E >= 0.0 else 0.0)
    return c / 2 + kappa * sum(d), 0.0, [(1.0 - 3.0 * kappa) * v for v in d]


def _timr(fibres, i1, i4s):
    """(W1, W2, [W4]) of trans-iso Mooney-Rivlin (closed form above)."""
    c3, c4, c5, lm = _TIMR["c3"], _TIMR["c4"], _TIMR["c5"], _TIMR["lam_max"]
    c6 = c3 * (math.exp(c4 * (lm - 1.0)) - 1.0) - c5 * lm
    lb = math.sqrt(i4s[0])
    s = 0.0 if lb < 1.0 else c3 * (math.exp(c4 * (lb - 1.0)) - 1.0) if lb < lm else c5 * lb + c6
    return _TIMR["c1"], _TIMR["c2"], [s / (2.0 * lb * lb)]


_TIVW = {"c1": 150.0, "c2": 1.5, **{k: _TIMR[k] for k in ("c3", "c4", "c5", "lam_max")}}


def _tivw(fibres, i1, i4s):
    """(W1, W2, [W4]) of trans-iso Veronda-Westmann (closed form above)."""
    c1, c2 = _TIVW["c1"], _TIVW["c2"]
    return c1 * c2 * math.exp(c2 * (i1 - 3.0)), -0.5 * c1 * c2, _timr(fibres, i1, i4s)[2]


_TC = {"c1": 150.0, "c2": 40.0, "beta": [2.5, 3.0, 4.0], "ksi": [800.0, 300.0, 500.0]}


def _tc(fibres, i1, i4s):
    """(W1, W2, [W4_a]) of TC nonlinear orthotropic, families along the global axes."""
    w4 = []
    for i4, b, ksi in zip(i4s, _TC["beta"], _TC["ksi"], strict=True):
        lam = math.sqrt(i4)
        w4.append(b * ksi * (lam - 1.0) ** (b - 1.0) / (2.0 * lam) if lam > 1.0 else 0.0)
    return _TC["c1"], _TC["c2"], w4


_EXP_POW = {"ksi": 500.0, "alpha": 2.0, "beta": 2.5}
_POW_LINEAR = {"E": 1000.0, "lam0": 1.2, "beta": 3.0}
_EXP_LINEAR = {k: _TIMR[k] for k in ("c3", "c4", "c5", "lam_max")}


def _exp_pow(lam0: float):
    """(W1, W2, [W4]) of fiber-exp-pow with x = I4 - lam0^2 (closed form above)."""

    def derivatives(fibres, i1, i4s):
        ksi, alpha, beta = _EXP_POW["ksi"], _EXP_POW["alpha"], _EXP_POW["beta"]
        x = i4s[0] - lam0 * lam0
        w4 = ksi * x ** (beta - 1.0) * math.exp(alpha * x**beta) if x > 0.0 else 0.0
        return 0.0, 0.0, [w4]

    return derivatives


def _pow_linear(fibres, i1, i4s):
    """(W1, W2, [W4]) of fiber-pow-linear (closed form above)."""
    E, lam0, beta = _POW_LINEAR["E"], _POW_LINEAR["lam0"], _POW_LINEAR["beta"]
    i0, i4 = lam0 * lam0, i4s[0]
    ksi = E / (4.0 * (beta - 1.0)) * i0**-1.5 * (i0 - 1.0) ** (2.0 - beta)
    if i4 < 1.0:
        return 0.0, 0.0, [0.0]
    if i4 < i0:
        return 0.0, 0.0, [ksi * (i4 - 1.0) ** (beta - 1.0)]
    b = ksi * (i0 - 1.0) ** (beta - 1.0) + E / (2.0 * lam0)
    return 0.0, 0.0, [b - E / (2.0 * math.sqrt(i4))]


def _exp_linear(fibres, i1, i4s):
    """(W1, W2, [W4]) of fiber-exp-linear: trans-iso Mooney-Rivlin's fibre alone."""
    _, _, w4 = _timr(fibres, i1, i4s)
    return 0.0, 0.0, w4


def _families(gamma: float, across: bool) -> list[tuple[float, float, float]]:
    """HGO's two fibres by hand: about e1 (default axes) or about e2 (``_ACROSS``: e1 = y,
    e3 = y x x = -z, e2 = e3 x e1 = x)."""
    cg, sg = math.cos(math.radians(gamma)), math.sin(math.radians(gamma))
    if across:
        return [(sg, cg, 0.0), (-sg, cg, 0.0)]
    return [(cg, sg, 0.0), (cg, -sg, 0.0)]


def _closed(derivatives, fibres, kind: str) -> float:
    """The combination s of ``kind`` for fibres ``fibres`` and a law's W1, W2, W4_f."""
    l = L
    if kind == "uniaxial":
        stretch = (l, l**-0.5, l**-0.5)
    elif kind == "equibiaxial":
        stretch = (l, l, l**-2)
    else:
        i1 = 3.0 + G**2
        i4s = [(a1 + G * a2) ** 2 + a2**2 + a3**2 for a1, a2, a3 in fibres]
        W1, W2, W4 = derivatives(fibres, i1, i4s)
        return 2 * G * (W1 + W2) + sum(
            2 * w * (a1 + G * a2) * a2 for w, (a1, a2, a3) in zip(W4, fibres, strict=True)
        )
    i1 = sum(v * v for v in stretch)
    i4s = [sum((s * a) ** 2 for s, a in zip(stretch, f, strict=True)) for f in fibres]
    W1, W2, W4 = derivatives(fibres, i1, i4s)
    pairs = list(zip(W4, fibres, strict=True))
    if kind == "uniaxial":
        fib = sum(2 * w * (l * a1**2 - l**-2 * a2**2) for w, (a1, a2, _) in pairs)
        return 2 * (l - l**-2) * (W1 + W2 / l) + fib
    fib = sum(2 * w * (l * a1**2 - l**-5 * a3**2) for w, (a1, _, a3) in pairs)
    return 2 * (l - l**-5) * (W1 + l**2 * W2) + fib


def combination(law, kind: str) -> float:
    """The law's stress combination s of ``kind`` (uniaxial, equibiaxial or shear)."""
    if kind == "uniaxial":
        t = L**-0.5
        P = law.stress(np.diag([L, t, t])[None])[0]
        return float(P[0, 0] - P[1, 1] * t / L)
    if kind == "equibiaxial":
        b = L**-2
        P = law.stress(np.diag([L, L, b])[None])[0]
        return float(P[0, 0] - P[2, 2] * b / L)
    F = np.eye(3)
    F[0, 1] = G
    return float(law.stress(F[None])[0, 0, 1])


def _cases() -> list[tuple[str, str, str, dict, object, list]]:
    """(law, label, kind, parameters, derivatives, fibres by hand) of every check."""
    out = []
    for name, extra in (("holzapfel_gasser_ogden", {}), ("hgo_unconstrained", {})):
        fam, across = _families(_HGO["gamma"], False), _families(0.0, True)
        out += [
            (name, f"uniaxial along the fibres (l = {L})", "uniaxial", {**_HGO, **extra},
             _hgo, fam),
            (name, f"uniaxial across, fibres compressed (l = {L})", "uniaxial",
             {**_HGO, **extra, **_ACROSS, "gamma": 0.0}, _hgo, across),
            (name, f"equibiaxial (l = {L})", "equibiaxial", {**_HGO, **extra}, _hgo, fam),
            (name, f"shear, one family compressed (g = {G})", "shear", {**_HGO, **extra},
             _hgo, fam),
        ]  # fmt: skip
    timr = {**_TIMR, "k": 3000.0}
    out += [
        ("trans_iso_mooney_rivlin", f"uniaxial along the fibre (l = {L}, linear part)",
         "uniaxial", {**timr, "fiber": (1.0, 0.0, 0.0)}, _timr, [(1.0, 0.0, 0.0)]),
        ("trans_iso_mooney_rivlin", f"uniaxial across, fibre compressed (l = {L})", "uniaxial",
         {**timr, "fiber": (0.0, 1.0, 0.0)}, _timr, [(0.0, 1.0, 0.0)]),
        ("trans_iso_mooney_rivlin", f"equibiaxial, fibre (1, 0, 1) (l = {L})", "equibiaxial",
         {**timr, "fiber": (1.0, 0.0, 1.0)}, _timr, [(_SQ, 0.0, _SQ)]),
        ("trans_iso_mooney_rivlin", f"shear, fibre (1, 1, 0) (g = {G}, exponential part)",
         "shear", {**timr, "fiber": (1.0, 1.0, 0.0)}, _timr, [(_SQ, _SQ, 0.0)]),
    ]  # fmt: skip
    ctimr = {**timr, "fiber": (1.0, 1.0, 0.0)}
    out += [
        ("coupled_trans_iso_mooney_rivlin", f"uniaxial along the fibre (l = {L}, linear part)",
         "uniaxial", {**ctimr, "fiber": (1.0, 0.0, 0.0)}, _timr, [(1.0, 0.0, 0.0)]),
        ("coupled_trans_iso_mooney_rivlin", f"shear, fibre (1, 1, 0) (g = {G}, exponential part)",
         "shear", ctimr, _timr, [(_SQ, _SQ, 0.0)]),
    ]  # fmt: skip
    tc, axes = {**_TC, "k": 3000.0}, [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    out += [
        ("tc_nonlinear_orthotropic", f"uniaxial along a_1, a_2 and a_3 compressed (l = {L})",
         "uniaxial", tc, _tc, axes),
        ("tc_nonlinear_orthotropic", f"equibiaxial, a_3 compressed (l = {L})", "equibiaxial",
         tc, _tc, axes),
        ("tc_nonlinear_orthotropic", f"shear, a_2 stretched (g = {G})", "shear", tc, _tc, axes),
    ]  # fmt: skip
    tivw = {**_TIVW, "k": 3000.0}
    out += [
        ("trans_iso_veronda_westmann", f"uniaxial along the fibre (l = {L}, linear part)",
         "uniaxial", {**tivw, "fiber": (1.0, 0.0, 0.0)}, _tivw, [(1.0, 0.0, 0.0)]),
        ("trans_iso_veronda_westmann", f"uniaxial across, fibre compressed (l = {L})",
         "uniaxial", {**tivw, "fiber": (0.0, 1.0, 0.0)}, _tivw, [(0.0, 1.0, 0.0)]),
        ("trans_iso_veronda_westmann", f"equibiaxial, fibre (1, 0, 1) (l = {L})", "equibiaxial",
         {**tivw, "fiber": (1.0, 0.0, 1.0)}, _tivw, [(_SQ, 0.0, _SQ)]),
        ("trans_iso_veronda_westmann", f"shear, fibre (1, 1, 0) (g = {G}, exponential part)",
         "shear", {**tivw, "fiber": (1.0, 1.0, 0.0)}, _tivw, [(_SQ, _SQ, 0.0)]),
    ]  # fmt: skip
    single = (
        ("fiber_exp_pow", {**_EXP_POW, "lam0": 1.05}, _exp_pow(1.05)),
        ("fiber_exp_pow_uncoupled", _EXP_POW, _exp_pow(1.0)),
        ("fiber_pow_linear", _POW_LINEAR, _pow_linear),
        ("fiber_pow_linear_uncoupled", _POW_LINEAR, _pow_linear),
        ("fiber_exp_linear", _EXP_LINEAR, _exp_linear),
        ("fiber_exp_linear_uncoupled", _EXP_LINEAR, _exp_linear),
    )
    for name, params, derivatives in single:
        out += [
            (name, f"uniaxial along the fibre (l = {L})", "uniaxial",
             {**params, "fiber": (1.0, 0.0, 0.0)}, derivatives, [(1.0, 0.0, 0.0)]),
            (name, f"uniaxial across, fibre slack (l = {L})", "uniaxial",
             {**params, "fiber": (0.0, 1.0, 0.0)}, derivatives, [(0.0, 1.0, 0.0)]),
            (name, f"equibiaxial, fibre (1, 0, 1) (l = {L})", "equibiaxial",
             {**params, "fiber": (1.0, 0.0, 1.0)}, derivatives, [(_SQ, 0.0, _SQ)]),
            (name, f"shear, fibre (1, 1, 0) (g = {G})", "shear",
             {**params, "fiber": (1.0, 1.0, 0.0)}, derivatives, [(_SQ, _SQ, 0.0)]),
        ]  # fmt: skip
    return out


def _orthotropic_cases() -> list:
    from tissuesim.verification.orthotropic import CASES as ORTHOTROPIC

    return list(ORTHOTROPIC)


#: (law, quantity, deformation, parameters, derivatives W1, W2, W4_f, fibres by hand); the
#: orthotropic laws' (``orthotropic.py``) with their closed form and no fibres
CASES = _cases() + _orthotropic_cases()


def checks(cases: list | None = None) -> list[Check]:
    """One check per case of ``cases`` (default ``CASES``): the law built by name, its stress
    combination against the closed form (relative 1e-8); a case without fibres (the
    orthotropic laws, ``orthotropic.py``) carries its closed form as a function, and its
    small-strain cases ("hooke") compare to 1e-5."""
    from tissuesim.verification import orthotropic

    out = []
    for name, what, kind, params, derivatives, fibres in cases or CASES:
        law = make_material(name, **params)
        if fibres is None:
            small = kind.startswith("hooke")
            result = orthotropic.hooke(law, kind) if small else combination(law, kind)
            out.append(Check(name, what, float(derivatives()), result, 1e-5 if small else TOL))
            continue
        ref = _closed(derivatives, fibres, kind)
        out.append(Check(name, what, float(ref), combination(law, kind), TOL))
    return out
