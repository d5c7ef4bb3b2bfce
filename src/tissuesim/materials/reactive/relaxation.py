"""FEBio's bond relaxation functions (``FEBondRelaxation.cpp``) for the reactive
viscoelastic laws: g(t), the fraction of a generation of bonds still intact a time t after
it started breaking, g(0) = 1. The ``_distortion`` and ``_dist_user`` forms take their times
from K2 = |dev ln U| (Frobenius norm), U the right stretch when the generation started breaking
(FEBio evaluates them at that stored stretch, so a generation's g depends on time only):

    exponential          tau                 exp(-t/tau)
    exp_distortion       tau0, tau1, alpha   exponential with tau = tau0 + tau1 K2^alpha
    exp_dist_user        tau(K2)
    fung                 tau1, tau2          (tau2 e^(-t/tau2) - tau1 e^(-t/tau1)
                                              + t (Ei(-t/tau2) - Ei(-t/tau1))) / (tau2 - tau1)
    park                 tau, beta           1 / (1 + (t/tau)^beta)
    park_distortion      tau0, tau1, beta0, beta1, alpha   (tau, beta = x0 + x1 K2^alpha)
    park_dist_user       tau(K2), beta(K2)
    power                tau, beta           (1 + t/tau)^-beta
    power_distortion     tau0, tau1, beta0, beta1, alpha
    power_dist_user      tau(K2), beta(K2)
    prony                g1..g6, t1..t6      sum g_i exp(-t/t_i) / sum g_i
    malkin               tau1, tau2, beta    (beta - 1) t^(1-beta) (G(beta-1, t/tau2)
                                              - G(beta-1, t/tau1))
                                              / (tau1^(1-beta) - tau2^(1-beta)),
                                              G the upper incomplete gamma function; beta = 1:
                                              (Ei(-t/tau2) - Ei(-t/tau1)) / ln(tau1/tau2)
    malkin_distortion    t1c0, t1c1, t1s0, t2c0, t2c1, t2s0, beta
                                             tau_i = ti c0 + ti c1 exp(-K2 / ti s0)
    malkin_dist_user     tau1(K2), tau2(K2), beta(K2)
    csexp                tau                 s K1(s), s = 2 sqrt(t/tau) (K1 the modified Bessel
                                              function of the second kind)
    csexp_dist_user      tau(K2)

A ``(K2)`` parameter is a number or an expression of K2 (``"1 + 10*K2**2"``, the functions of
scene expressions). Differences from FEBio's code: its incomplete gamma function is a series
to 3e-7 and returns 0 for a negative first argument (so its Malkin function with beta < 1 is
0 for t > 0); tissuesim evaluates the function itself (SciPy, the recurrence
G(a, x) = (G(a + 1, x) - x^a e^-x) / a below a = 0). FEBio's Carreau relaxation (a function of
the rate of deformation) is not here.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable

import numpy as np
from scipy.special import expi, gamma, gammaincc, k1

from tissuesim.errors import InputError, MaterialError
from tissuesim.validate import short

__all__ = ["RELAXATIONS", "Relaxation", "function_of", "model_table"]

Fn = Callable[[np.ndarray], np.ndarray]


def _upper_gamma(a: float, x: np.ndarray) -> np.ndarray:
    """G(a, x) = int_x^inf s^(a-1) e^-s ds for x > 0, any real a (not 0, -1, ...)."""
    if a > 0.0:
        return gammaincc(a, x) * gamma(a)
    return (_upper_gamma(a + 1.0, x) - x**a * np.exp(-x)) / a


def _malkin(t: np.ndarray, tau1: np.ndarray, tau2: np.ndarray, beta: np.ndarray) -> np.ndarray:
    out = np.ones_like(t)
    for i in np.flatnonzero(t > 0.0):
        ti, t1, t2, b = t.flat[i], tau1.flat[i], tau2.flat[i], beta.flat[i]
        if b == 1.0:
            g = (expi(-ti / t2) - expi(-ti / t1)) / math.log(t1 / t2)
        else:
            bm1 = b - 1.0
            q = _upper_gamma(bm1, np.array(ti / t2)) - _upper_gamma(bm1, np.array(ti / t1))
            g = bm1 * ti**-bm1 * q / (t1**-bm1 - t2**-bm1)
        out.flat[i] = g
    return out


def _fung(t: np.ndarray, tau1: float, tau2: float) -> np.ndarray:
    ts = np.where(t > 0.0, t, 1.0)
    g = (tau2 * np.exp(-ts / tau2) - tau1 * np.exp(-ts / tau1)
         + ts * (expi(-ts / tau2) - expi(-ts / tau1))) / (tau2 - tau1)  # fmt: skip
    return np.where(t > 0.0, np.maximum(g, 0.0), 1.0)


def _csexp(t: np.ndarray, tau: np.ndarray) -> np.ndarray:
    s = 2.0 * np.sqrt(np.where(t > 0.0, t, 1.0) / tau)
    return np.where(t > 0.0, s * k1(s), 1.0)


def _exp(t, p):
    return np.exp(-t / p["tau"])


def _power(t, p):
    return (1.0 + t / p["tau"]) ** -p["beta"]


def _park(t, p):
    return 1.0 / (1.0 + (t / p["tau"]) ** p["beta"])


def _prony(t, p):
    g, tt = p["g"], p["t"]
    return sum(gi * np.exp(-t / ti) for gi, ti in zip(g, tt, strict=True)) / sum(g)


def _dist(p, K2):
    """tau and beta of the _distortion forms: x0 + x1 K2^alpha."""
    Ka = K2 ** p["alpha"]
    beta = p.get("beta0", 0.0) + p.get("beta1", 0.0) * Ka
    return {"tau": p["tau0"] + p["tau1"] * Ka, "beta": beta}


#: name -> (g(t, parameters, K2), {parameter: (default or None, low, open, a function of K2)})
_REQ, _FN = None, True
RELAXATIONS: dict[str, tuple[Callable, dict[str, tuple]]] = {
    "exponential": (lambda t, p, K: _exp(t, p), {"tau": (_REQ, 0.0, True, False)}),
    "exp_distortion": (lambda t, p, K: _exp(t, _dist(p, K)),
                       {"tau0": (_REQ, 0.0, True, False), "tau1": (0.0, 0.0, False, False),
                        "alpha": (1.0, 0.0, False, False)}),
    "exp_dist_user": (lambda t, p, K: np.exp(-t / p["tau"](K)), {"tau": (_REQ, 0, True, _FN)}),
    "fung": (lambda t, p, K: _fung(t, p["tau1"], p["tau2"]),
             {"tau1": (_REQ, 0.0, True, False), "tau2": (_REQ, 0.0, True, False)}),
    "park": (lambda t, p, K: _park(t, p),
             {"tau": (_REQ, 0.0, True, False), "beta": (_REQ, 0.0, True, False)}),
    "park_distortion": (lambda t, p, K: _park(t, _dist(p, K)),
                        {"tau0": (_REQ, 0.0, True, False), "tau1": (0.0, 0.0, False, False),
                         "beta0": (_REQ, 0.0, True, False), "beta1": (0.0, 0.0, False, False),
                         "alpha": (1.0, 0.0, False, False)}),
    "park_dist_user": (lambda t, p, K: _park(t, {"tau": p["tau"](K), "beta": p["beta"](K)}),
                       {"tau": (_REQ, 0, True, _FN), "beta": (_REQ, 0, True, _FN)}),
    "power": (lambda t, p, K: _power(t, p),
              {"tau": (_REQ, 0.0, True, False), "beta": (_REQ, 0.0, True, False)}),
    "power_distortion": (lambda t, p, K: _power(t, _dist(p, K)),
                         {"tau0": (_REQ, 0.0, True, False), "tau1": (0.0, 0.0, False, False),
                          "beta0": (_REQ, 0.0, True, False), "beta1": (0.0, 0.0, False, False),
                          "alpha": (1.0, 0.0, False, False)}),
    "power_dist_user": (lambda t, p, K: _power(t, {"tau": p["tau"](K), "beta": p["beta"](K)}),
                        {"tau": (_REQ, 0, True, _FN), "beta": (_REQ, 0, True, _FN)}),
    "prony": (lambda t, p, K: _prony(t, p), {"g": (_REQ, 0.0, False, False),
                                             "t": (_REQ, 0.0, True, False)}),
    "malkin": (lambda t, p, K: _malkin(t, *np.broadcast_arrays(
                   np.asarray(p["tau1"]), np.asarray(p["tau2"]), np.asarray(p["beta"]), t)[:3]),
               {"tau1": (_REQ, 0.0, True, False), "tau2": (_REQ, 0.0, True, False),
                "beta": (1.0, 1.0, False, False)}),
    "malkin_distortion": (
        lambda t, p, K: _malkin(t, *np.broadcast_arrays(
            p["t1c0"] + p["t1c1"] * np.exp(-K / p["t1s0"]),
            p["t2c0"] + p["t2c1"] * np.exp(-K / p["t2s0"]), np.asarray(p["beta"]), t)[:3]),
        {"t1c0": (_REQ, 0.0, True, False), "t1c1": (0.0, None, False, False),
         "t1s0": (1.0, 0.0, True, False), "t2c0": (_REQ, 0.0, True, False),
         "t2c1": (0.0, None, False, False), "t2s0": (1.0, 0.0, True, False),
         "beta": (1.0, 0.0, True, False)}),
    "malkin_dist_user": (
        lambda t, p, K: _malkin(t, *np.broadcast_arrays(
            p["tau1"](K), p["tau2"](K), p["beta"](K), t)[:3]),
        {"tau1": (_REQ, 0, True, _FN), "tau2": (_REQ, 0, True, _FN), "beta": (_REQ, 0, True, _FN)}),
    "csexp": (lambda t, p, K: _csexp(t, p["tau"]), {"tau": (_REQ, 0.0, True, False)}),
    "csexp_dist_user": (lambda t, p, K: _csexp(t, p["tau"](K)), {"tau": (_REQ, 0, True, _FN)}),
}  # fmt: skip


def function_of(
    law: str, key: str, value: object, variable: str = "K2", what: str = "relaxation"
) -> tuple[object, Fn]:
    """A number or an expression of ``variable`` (K2; a recruitment's X) -> (as given,
    f(values (n,)) -> (n,)), compiled as a scene expression."""
    from tissuesim.scene.expressions import compile_expression

    if isinstance(value, (int, float)) and not isinstance(value, bool):
        x = float(value)
        return x, lambda K: np.full(np.shape(K), x)
    if not isinstance(value, str):
        raise MaterialError(f"{law}: {what} {key} must be a number or an expression of "
                            f"{variable}, not {short(value)}")  # fmt: skip
    if re.search(r"\b[xyzt]\b", value):
        raise MaterialError(f"{law}: {what} {key} {short(value)}: its variable is {variable}")
    text = re.sub(rf"\b{variable}\b", "x", value)  # evaluated as a scene expression of x
    try:
        f = compile_expression(text, f"{law}: {what} {key}")
    except InputError as exc:
        raise MaterialError(str(exc)) from None

    def of_variable(K: np.ndarray) -> np.ndarray:
        K = np.asarray(K, dtype=float)
        X = np.zeros((K.size, 3))
        X[:, 0] = K.ravel()
        return np.asarray(f(X, 0.0), dtype=float).reshape(K.shape)

    return value, of_variable


def model_table(law: str, what: str, spec: object, known: dict, example: str) -> tuple[str, dict]:
    """(the model's name, the rest of the table) of a ``{"model": ..., ...}`` table of the
    functions ``known`` (name -> (function, {parameter: ...})); FEBio's names ("relaxation-
    Malkin-dist-user", "recruitment power") taken as tissuesim's. One-line errors naming
    ``law`` and ``what`` (``example``: a table to show)."""
    if not isinstance(spec, dict) or "model" not in spec:
        raise MaterialError(f"{law} needs {what} as a table with its model (e.g. {example}), "
                            f"not {short(spec)}")  # fmt: skip
    table = dict(spec)
    kind = str(table.pop("model")).strip().lower().replace("-", "_").replace(" ", "_")
    kind = kind.removeprefix(f"{what}_")
    if kind not in known:
        raise MaterialError(f"{law}: {what} {short(kind)} is not one tissuesim has; it has "
                            f"{', '.join(known)}")  # fmt: skip
    parameters = known[kind][1]
    for key in table:
        if key not in parameters:
            raise MaterialError(f"{law}: {what} {kind} takes {', '.join(parameters)}, not "
                                f"{short(key)}")  # fmt: skip
    return kind, table


class Relaxation:
    """g(t, K2): ``Relaxation("law", {"model": "exponential", "tau": 0.2})``."""

    def __init__(self, law: str, spec: object) -> None:
        if isinstance(spec, str):
            spec = {"model": spec}
        example = "{ model = 'exponential', tau = 0.2 }"
        kind, table = model_table(law, "relaxation", spec, RELAXATIONS, example)
        self.kind = kind
        self.function, spec_ = RELAXATIONS[kind]
        self.given: dict[str, object] = {}
        self.parameters: dict[str, object] = {}
        for key, (default, low, open_, is_fn) in spec_.items():
            if key not in table and default is None:
                raise MaterialError(f"{law}: relaxation {kind} needs {key}")
            value = table.get(key, default)
            if is_fn:
                self.given[key], self.parameters[key] = function_of(law, key, value)
                continue
            values = value if kind == "prony" else [value]
            try:
                xs = [float(v) for v in (values if isinstance(values, (list, tuple)) else [values])]
            except (TypeError, ValueError):
                raise MaterialError(f"{law}: relaxation {kind} {key} must be a number, not "
                                    f"{short(value)}") from None  # fmt: skip
            for x in xs:
                if not math.isfinite(x) or (low is not None and (x < low or (open_ and x == low))):
                    raise MaterialError(f"{law}: relaxation {kind} {key} must be "
                                        f"{'>' if open_ else '>='} {low}, got {x!r}")  # fmt: skip
            self.given[key] = xs if kind == "prony" else xs[0]
            self.parameters[key] = np.array(xs) if kind == "prony" else xs[0]
        if kind == "prony":
            g, t = self.parameters["g"], self.parameters["t"]
            if len(g) != len(t) or not g.sum() > 0.0:
                raise MaterialError(f"{law}: relaxation prony needs g and t of the same length "
                                    "and sum(g) > 0")  # fmt: skip

    def as_table(self) -> dict:
        return {"model": self.kind, **self.given}

    def __call__(self, t: np.ndarray, K2: np.ndarray) -> np.ndarray:
        """g at elapsed times t and distortions K2 (same shapes)."""
        t = np.asarray(t, dtype=float)
        K2 = np.broadcast_to(np.asarray(K2, dtype=float), t.shape)
        with np.errstate(over="ignore", under="ignore"):
            g = np.asarray(self.function(np.maximum(t, 0.0), self.parameters, K2), float)
        return np.broadcast_to(g, t.shape).copy()
