"""FEBio's damage functions: the cumulative distribution functions (``CDF ...``,
``FEDamageCDF.cpp``) that turn a damage criterion's running maximum into the damage D, and the
damage criteria (``DC ...``, ``FEDamageCriterion.cpp``) evaluated on the undamaged law.

CDFs (X the criterion's maximum; D = Dmax F(X), 0 <= Dmax <= 1):

    simo        a > 0, 0 <= b <= 1   F = 1 - b - (1 - b)(1 - exp(-X/a)) a / X (X > 1e-12),
                                     (1 - b) X / (2 a) below, 0 for X < 0
    log_normal  mu > 0, sigma > 0    F = erfc(-ln(X/mu) / (sigma sqrt 2)) / 2, 0 for X <= 0
    weibull     alpha >= 0, mu >= 0, ploc   F = 1 - exp(-((X - ploc)/mu)^alpha), X > ploc
    step        mu >= 0              F = 1 for X > mu, else 0
    quintic     mumin >= 0, mumax    x = (X - mumin)/(mumax - mumin), F = x^3 (10 - 15 x + 6 x^2)
                                     clamped to 0 and 1 outside
    gamma       alpha > 0, mu >= 0   F = P(alpha, X/mu) (the regularised lower incomplete gamma)

Criteria (sigma the Cauchy stress of the undamaged law, E the Green strain, h = ln V):

    simo                      sqrt(2 psi)          strain_energy_density  psi
    specific_strain_energy    psi / density
    von_mises_stress          sqrt(3/2 s:s), s = dev sigma
    max_shear_stress          (sigma_max - sigma_min)/2        max_normal_stress  sigma_max
    max_normal_lagrange_strain  the largest eigenvalue of E
    octahedral_shear_strain   sqrt(2/3 dev E : dev E)
    octahedral_natural_strain sqrt(2/3 dev h : dev h)
    drucker_shear_stress      (J2^3 - c J3^2)^(1/6)         (c in [-27/8, 9/4])
    drucker_prager            sigma_e - b sigma_m            deshpande_fleck  sqrt((sigma_e^2 +
                              (3 beta sigma_m)^2)/(1 + beta^2))
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.special import erfc, gammainc

from tissuesim.errors import MaterialError
from tissuesim.validate import short

__all__ = ["CDFS", "CRITERIA", "DamageCDF", "DamageCriterion", "febio_key"]


def febio_key(name: object, prefix: str) -> str:
    """FEBio's ``CDF log-normal`` / ``DC max normal Lagrange strain`` (or tissuesim's
    ``log_normal``) as the table key."""
    text = str(name).strip()
    if text.lower().startswith(prefix.lower() + " "):
        text = text[len(prefix) + 1 :]
    return text.lower().replace("-", "_").replace(" ", "_")


def _simo(X: np.ndarray, p: dict) -> np.ndarray:
    a, b = p["a"], p["b"]
    Xs = np.where(X > 1e-12, X, 1.0)
    big = 1.0 - b - (1.0 - b) * (-np.expm1(-Xs / a)) * a / Xs
    return np.where(X > 1e-12, big, np.where(X >= 0.0, 0.5 * (1.0 - b) / a * X, 0.0))


def _log_normal(X: np.ndarray, p: dict) -> np.ndarray:
    ok = X > 0.0
    z = -np.log(np.where(ok, X, 1.0) / p["mu"]) / (p["sigma"] * math.sqrt(2.0))
    return np.where(ok, 0.5 * erfc(z), 0.0)


def _weibull(X: np.ndarray, p: dict) -> np.ndarray:
    ok = X > p["ploc"]
    x = np.where(ok, X - p["ploc"], 0.0) / p["mu"]
    return np.where(ok, -np.expm1(-(x ** p["alpha"])), 0.0)


def _step(X: np.ndarray, p: dict) -> np.ndarray:
    return np.where(X > p["mu"], 1.0, 0.0)


def _quintic(X: np.ndarray, p: dict) -> np.ndarray:
    x = np.clip((X - p["mumin"]) / (p["mumax"] - p["mumin"]), 0.0, 1.0)
    return x**3 * (10.0 - 15.0 * x + 6.0 * x * x)


def _gamma(X: np.ndarray, p: dict) -> np.ndarray:
    return np.where(X > 0.0, gammainc(p["alpha"], np.maximum(X, 0.0) / p["mu"]), 0.0)


#: name -> (function, {parameter: (FEBio's default or None: required, low, low open)})
CDFS: dict[str, tuple[Callable, dict[str, tuple]]] = {
    "simo": (_simo, {"a": (None, 0.0, True), "b": (None, 0.0, False)}),
    "log_normal": (_log_normal, {"mu": (1.0, 0.0, True), "sigma": (1.0, 0.0, True)}),
    "weibull": (
        _weibull,
        {"alpha": (1.0, 0.0, False), "mu": (1.0, 0.0, True), "ploc": (0.0, None, False)},
    ),  # fmt: skip
    "step": (_step, {"mu": (1.0, 0.0, False)}),
    "quintic": (_quintic, {"mumin": (0.0, 0.0, False), "mumax": (1.0, None, False)}),
    "gamma": (_gamma, {"alpha": (2.0, 0.0, True), "mu": (4.0, 0.0, True)}),
}


def _real(law: str, key: str, value: object) -> float:
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise MaterialError(f"{law}: {key} must be a number, not {short(value)}") from None
    if not math.isfinite(x):
        raise MaterialError(f"{law}: {key} must be finite, got {x!r}")
    return x


def _parameters(law: str, what: str, table: dict, spec: dict[str, tuple]) -> dict[str, float]:
    out = {}
    for key in table:
        if key not in spec:
            raise MaterialError(f"{law}: {what} takes {', '.join(spec) or 'no parameters'}, "
                                f"not {short(key)}")  # fmt: skip
    for key, (default, low, open_) in spec.items():
        if key not in table and default is None:
            raise MaterialError(f"{law}: {what} needs {key}")
        x = _real(law, f"{what} {key}", table.get(key, default))
        if low is not None and (x < low or (open_ and x == low)):
            raise MaterialError(f"{law}: {what} {key} must be {'>' if open_ else '>='} {low:g}, "
                                f"got {x!r}")  # fmt: skip
        out[key] = x
    return out


class DamageCDF:
    """D = Dmax F(X): ``DamageCDF("log_normal", {"mu": 0.3, "sigma": 0.1, "Dmax": 1.0})``."""

    def __init__(self, law: str, spec: object) -> None:
        table = _table(law, "damage", spec)
        kind = febio_key(table.pop("model"), "CDF")
        if kind not in CDFS:
            raise MaterialError(f"{law}: damage {short(kind)} is not a damage CDF tissuesim "
                                f"has; it has {', '.join(CDFS)}")  # fmt: skip
        dmax = _real(law, "damage Dmax", table.pop("Dmax", 1.0))
        if not 0.0 <= dmax <= 1.0:
            raise MaterialError(f"{law}: damage Dmax must be in [0, 1], got {dmax!r}")
        self.kind, self.dmax = kind, dmax
        self.function, spec_ = CDFS[kind]
        self.parameters = _parameters(law, f"damage {kind}", table, spec_)
        if kind == "simo" and not self.parameters["b"] <= 1.0:
            raise MaterialError(f"{law}: damage simo b must be <= 1, got {self.parameters['b']}")
        if kind == "quintic" and not self.parameters["mumax"] > self.parameters["mumin"]:
            raise MaterialError(f"{law}: damage quintic needs mumax > mumin")

    def as_table(self) -> dict:
        return {"model": self.kind, "Dmax": self.dmax, **self.parameters}

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """D at the criterion's values X (n,)."""
        return self.dmax * self.function(np.asarray(X, dtype=float), self.parameters)


def _table(law: str, what: str, spec: object) -> dict:
    if isinstance(spec, str):
        spec = {"model": spec}
    if not isinstance(spec, dict) or "model" not in spec:
        raise MaterialError(
            f"{law} needs {what} as a table with its model (e.g. {{ model = 'log_normal', "
            f"mu = 0.3, sigma = 0.1 }}), not {short(spec)}"
        )
    return dict(spec)


def _eig(S: np.ndarray) -> np.ndarray:
    return np.linalg.eigvalsh(0.5 * (S + np.swapaxes(S, -1, -2)))


def _dev(S: np.ndarray) -> np.ndarray:
    d = S.shape[-1]
    return S - np.einsum("...ii->...", S)[..., None, None] / d * np.eye(d)


def _von_mises(s: np.ndarray) -> np.ndarray:
    dv = _dev(s)
    return np.sqrt(1.5 * np.einsum("...ij,...ij->...", dv, dv))


#: criterion -> (what it needs: "sed", "cauchy", "green", "hencky"; extra parameters)
CRITERIA: dict[str, tuple[str, dict[str, tuple]]] = {
    "simo": ("sed", {}),
    "strain_energy_density": ("sed", {}),
    "specific_strain_energy": ("sed", {}),
    "von_mises_stress": ("cauchy", {}),
    "max_shear_stress": ("cauchy", {}),
    "max_normal_stress": ("cauchy", {}),
    "drucker_shear_stress": ("cauchy", {"c": (0.0, -27.0 / 8.0, False)}),
    "drucker_prager": ("cauchy", {"b": (0.0, None, False)}),
    "deshpande_fleck": ("cauchy", {"beta": (0.0, None, False)}),
    "max_normal_lagrange_strain": ("green", {}),
    "octahedral_shear_strain": ("green", {}),
    "octahedral_natural_strain": ("hencky", {}),
}


class DamageCriterion:
    """A damage criterion X(F) of the undamaged law: ``DamageCriterion("von_mises_stress")``."""

    def __init__(self, law: str, spec: object) -> None:
        table = _table(law, "criterion", spec)
        kind = febio_key(table.pop("model"), "DC")
        if kind not in CRITERIA:
            raise MaterialError(f"{law}: criterion {short(kind)} is not a damage criterion "
                                f"tissuesim has; it has {', '.join(CRITERIA)}")  # fmt: skip
        self.kind = kind
        self.needs, spec_ = CRITERIA[kind]
        self.parameters = _parameters(law, f"criterion {kind}", table, spec_)
        if kind == "drucker_shear_stress" and self.parameters["c"] > 9.0 / 4.0:
            raise MaterialError(f"{law}: criterion drucker_shear_stress c must be <= 9/4")

    def as_table(self) -> dict:
        return {"model": self.kind, **self.parameters}

    def __call__(self, F: np.ndarray, psi: np.ndarray, P: np.ndarray, density: float) -> np.ndarray:
        """X at deformation gradients F (n, d, d), with the undamaged law's energy psi (n,) and
        first Piola stress P (n, d, d)."""
        k = self.kind
        if self.needs == "sed":
            sed = psi if k != "simo" else np.sqrt(2.0 * np.maximum(psi, 0.0))
            return sed / density if k == "specific_strain_energy" else sed
        if self.needs == "green":
            E = 0.5 * (np.swapaxes(F, -1, -2) @ F - np.eye(F.shape[-1]))
            if k == "max_normal_lagrange_strain":
                return _eig(E)[..., -1]
            dE = _dev(E)
            return np.sqrt(2.0 / 3.0 * np.einsum("...ij,...ij->...", dE, dE))
        if self.needs == "hencky":
            w, v = np.linalg.eigh(F @ np.swapaxes(F, -1, -2))
            h = np.einsum("...ik,...k,...jk->...ij", v, 0.5 * np.log(w), v)
            dh = _dev(h)
            return np.sqrt(2.0 / 3.0 * np.einsum("...ij,...ij->...", dh, dh))
        J = np.linalg.det(F)
        s = P @ np.swapaxes(F, -1, -2) / J[..., None, None]
        if k == "max_normal_stress":
            return _eig(s)[..., -1]
        if k == "max_shear_stress":
            ev = _eig(s)
            return 0.5 * (ev[..., -1] - ev[..., 0])
        se = _von_mises(s)
        sm = np.einsum("...ii->...", s) / 3.0
        if k == "von_mises_stress":
            return se
        if k == "drucker_prager":
            return se - self.parameters["b"] * sm
        if k == "deshpande_fleck":
            beta = self.parameters["beta"]
            return np.sqrt((se**2 + (3.0 * beta * sm) ** 2) / (1.0 + beta**2))
        sd = _dev(s)  # drucker_shear_stress
        J2 = 0.5 * np.einsum("...ij,...ij->...", sd, sd)
        J3 = np.linalg.det(sd)
        return np.maximum(J2**3 - self.parameters["c"] * J3**2, 0.0) ** (1.0 / 6.0)
