"""FEBio's bond recruitment functions (``FEBondRecruitment.cpp``) for the reactive
viscoelastic laws: each generation of weak bonds is weighted by brf(X), X the trigger's scalar
strain of the total deformation when the generation forms (|E|, |dev ln V| or |ln J| for
``trigger`` 0, 1, 2: FEBio's ``ScalarStrain``), so bonds formed at larger strains carry more
(FEBio's ``m_wv``):

    user           function            a function of X (an expression; FEBio's point curve)
    power          alpha, mu0, mu1, scale   mu0 + mu1 (X / scale)^alpha          (X > 0, else 0)
    exponential    alpha, mu0, mu1, scale   mu0 exp(mu1 (X / scale)^alpha)       (X > 0, else 0)
    polynomial     mu0, mu1, mu2            mu0 + mu1 X + mu2 X^2                (X > 0, else 0)
    log-normal     mu, sigma, max           1 + max Phi(ln(X / mu) / sigma)      (X >= 0, else 0)
    Weibull        alpha, mu, ploc, max     1 + max (1 - exp(-((X - ploc) / mu)^alpha))
                                                                              (X > ploc, else 0)
    quintic        mumin, mumax, max        1 + max x^3 (10 - 15 x + 6 x^2),
                                            x = (X - mumin) / (mumax - mumin) clipped to [0, 1]
    gamma          alpha, mu, max           1 + max P(alpha, X / mu)             (X > 0, else 1)

(the zeros below the ranges are FEBio's: its functions return 0 there). Defaults as FEBio's.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import erfc, gammainc

from tissuesim.errors import MaterialError
from tissuesim.materials.reactive.relaxation import function_of, model_table
from tissuesim.validate import short

__all__ = ["RECRUITMENTS", "Recruitment"]


def _power(X, p):
    Xs = np.where(X > 0, X, 1.0) / p["scale"]
    return np.where(X > 0, p["mu0"] + p["mu1"] * Xs ** p["alpha"], 0.0)


def _exponential(X, p):
    Xs = np.where(X > 0, X, 1.0) / p["scale"]
    return np.where(X > 0, p["mu0"] * np.exp(p["mu1"] * Xs ** p["alpha"]), 0.0)


def _polynomial(X, p):
    return np.where(X > 0, p["mu0"] + p["mu1"] * X + p["mu2"] * X * X, 0.0)


def _log_normal(X, p):
    with np.errstate(divide="ignore"):
        z = -np.log(np.maximum(X, 0.0) / p["mu"]) / p["sigma"] / math.sqrt(2.0)
    return np.where(X >= 0, 1.0 + p["max"] * 0.5 * erfc(z), 0.0)


def _weibull(X, p):
    s = np.where(X > p["ploc"], X - p["ploc"], 0.0) / p["mu"]
    return np.where(X > p["ploc"], 1.0 + p["max"] * (1.0 - np.exp(-(s ** p["alpha"]))), 0.0)


def _quintic(X, p):
    x = np.clip((X - p["mumin"]) / (p["mumax"] - p["mumin"]), 0.0, 1.0)
    return 1.0 + p["max"] * x**3 * (10.0 - 15.0 * x + 6.0 * x * x)


def _gamma(X, p):
    return np.where(X > 0, 1.0 + p["max"] * gammainc(p["alpha"], np.maximum(X, 0.0) / p["mu"]),
                    1.0)  # fmt: skip


#: name -> (brf(X, parameters), {parameter: (FEBio's default, lower bound, bound open)})
RECRUITMENTS = {
    "power": (_power, {"alpha": (2.0, None, False), "mu0": (1.0, None, False),
                       "mu1": (0.0, None, False), "scale": (1.0, 0.0, True)}),
    "exponential": (_exponential, {"alpha": (1.0, 0.0, False), "mu0": (1.0, 0.0, False),
                                   "mu1": (0.0, None, False), "scale": (1.0, 0.0, True)}),
    "polynomial": (_polynomial, {"mu0": (1.0, 0.0, False), "mu1": (0.0, None, False),
                                 "mu2": (0.0, None, False)}),
    "log_normal": (_log_normal, {"mu": (1.0, 0.0, True), "sigma": (1.0, 0.0, True),
                                 "max": (0.0, 0.0, False)}),
    "weibull": (_weibull, {"alpha": (1.0, 0.0, False), "mu": (1.0, 0.0, True),
                           "ploc": (0.0, None, False), "max": (0.0, 0.0, False)}),
    "quintic": (_quintic, {"mumin": (0.0, 0.0, False), "mumax": (1.0, None, False),
                           "max": (0.0, 0.0, False)}),
    "gamma": (_gamma, {"alpha": (2.0, 0.0, True), "mu": (4.0, 0.0, True),
                       "max": (0.0, 0.0, False)}),
    "user": (None, {"function": (None, None, False)}),
}  # fmt: skip


class Recruitment:
    """brf(X): ``Recruitment("law", {"model": "power", "mu1": 2.0})`` or
    ``{"model": "user", "function": "1 + 10*X"}``."""

    def __init__(self, law: str, spec: object) -> None:
        example = "{ model = 'power', mu1 = 2 } or { model = 'user', function = '1 + 10*X' }"
        kind, table = model_table(law, "recruitment", spec, RECRUITMENTS, example)
        self.kind = kind
        function, spec_ = RECRUITMENTS[kind]
        self.given = dict(table)
        if kind == "user":
            if "function" not in table:
                raise MaterialError(f"{law}: recruitment user needs function (of X)")
            _, self._f = function_of(law, "function", table["function"], "X", "recruitment")
            return
        params = {}
        for key, (default, low, open_) in spec_.items():
            value = table.get(key, default)
            try:
                x = float(value)
            except (TypeError, ValueError):
                raise MaterialError(f"{law}: recruitment {kind} {key} must be a number, not "
                                    f"{short(value)}") from None  # fmt: skip
            if not math.isfinite(x) or (low is not None and (x < low or (open_ and x == low))):
                raise MaterialError(f"{law}: recruitment {kind} {key} must be "
                                    f"{'>' if open_ else '>='} {low}, got {x!r}")  # fmt: skip
            params[key] = x
        if kind == "quintic" and not params["mumax"] > params["mumin"]:
            raise MaterialError(f"{law}: recruitment quintic needs mumax > mumin")
        self._f = lambda X: function(X, params)

    def as_table(self) -> dict:
        return {"model": self.kind, **self.given}

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """brf at scalar strains X."""
        X = np.asarray(X, dtype=float)
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            return np.broadcast_to(np.asarray(self._f(X), dtype=float), X.shape).copy()
