"""Fitting a law's parameters to stress-stretch data, by least squares on homogeneous tests.

The model side is the law itself at homogeneous deformations (3D, nominal = first
Piola-Kirchhoff stress, force per reference area):

    uniaxial      F = diag(l, t, t)       P11 with P22 = P33 = 0
    equibiaxial   F = diag(l, l, t)       P11 with P33 = 0
    shear         F = I + g e1 (x) e2     P12 (simple shear, J = 1)

Incompressible (default): t = l^(-1/2) (uniaxial), l^(-2) (equibiaxial), and the pressure that
keeps the free faces traction-free is eliminated: P11 - P22 t / l, P11 - P33 t / l; the
simple-shear P12 needs none. The bulk term then plays no part. Compressible
(``incompressible=False``, the bulk parameter given): t solves P22 = 0 (P33 = 0) by a batched
Newton iteration.

``fit_material`` minimises sum (P_model - P_data)^2 / s^2, s the largest |P_data|, with
``scipy.optimize.least_squares`` over the parameters given in ``initial`` (lists, such as
Ogden's c and m, are fitted entry by entry), the ones in ``fixed`` held.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tissuesim.errors import InputError, MaterialError
from tissuesim.materials.base import Material
from tissuesim.materials.registry import ALIASES, MATERIALS, make_material
from tissuesim.validate import short

__all__ = ["TESTS", "nominal_stress", "fit_material", "FitResult"]

#: the homogeneous tests, and the other names they go by
TESTS = ("uniaxial", "equibiaxial", "shear")
_TEST_NAMES = {"uniaxial": "uniaxial", "equibiaxial": "equibiaxial", "biaxial": "equibiaxial"}
_TEST_NAMES |= {"shear": "shear", "simple_shear": "shear"}


def _test_name(test: object) -> str:
    key = str(test).strip().lower().replace(" ", "_").replace("-", "_")
    if key not in _TEST_NAMES:
        raise InputError(f"unknown test {short(test)}; valid: {', '.join(TESTS)}")
    return _TEST_NAMES[key]


def _gradients(test: str, l: np.ndarray, t: np.ndarray) -> np.ndarray:
    F = np.zeros((l.size, 3, 3))
    if test == "shear":
        F[:, 0, 0] = F[:, 1, 1] = F[:, 2, 2] = 1.0
        F[:, 0, 1] = l
        return F
    F[:, 0, 0] = l
    F[:, 1, 1] = t if test == "uniaxial" else l
    F[:, 2, 2] = t
    return F


def _lateral(material: Material, test: str, l: np.ndarray) -> np.ndarray:
    """The free stretch t with zero lateral stress (compressible), by damped Newton."""
    t = l ** (-0.5) if test == "uniaxial" else l ** (-2.0)
    free = [1, 2] if test == "uniaxial" else [2]
    for _ in range(100):
        res = material.evaluate(_gradients(test, l, t), 2)
        r = res.stress[:, 2, 2]
        dr = sum(res.tangent[:, 2, 2, a, a] for a in free)
        step = -r / np.where(dr > 0.0, dr, np.nan)
        step = np.where(np.isfinite(step), step, -0.5 * t)
        step = np.maximum(step, -0.5 * t)  # keeps t > 0
        t = t + step
        if np.all(np.abs(step) <= 1e-14 * t):
            break
    return t


def nominal_stress(
    material: Material, test: str, stretch: np.ndarray, *, incompressible: bool = True
) -> np.ndarray:
    """The law's nominal stress (Pa) in a homogeneous ``test`` ("uniaxial", "equibiaxial" or
    "shear") at stretches (shear: amounts of shear gamma), shape of ``stretch``."""
    test = _test_name(test)
    l = np.asarray(stretch, dtype=float)
    shape, l = l.shape, l.ravel()
    if not np.all(np.isfinite(l)) or (test != "shear" and np.any(l <= 0.0)):
        raise InputError(f"stretches must be finite and > 0, got {short(stretch)}")
    if test == "shear":
        return material.stress(_gradients(test, l, l))[:, 0, 1].reshape(shape)
    if incompressible:
        t = l ** (-0.5) if test == "uniaxial" else l ** (-2.0)
        P = material.stress(_gradients(test, l, t))
        return (P[:, 0, 0] - P[:, 2, 2] * t / l).reshape(shape)
    t = _lateral(material, test, l)
    return material.stress(_gradients(test, l, t))[:, 0, 0].reshape(shape)


@dataclass(frozen=True)
class FitResult:
    """What ``fit_material`` returns: the fitted law and how well it fits."""

    model: str
    parameters: dict[str, Any]  # all of them, fitted and fixed, as make_material takes them
    material: Material
    rms: float  # root-mean-square residual / largest |stress| of the data
    success: bool
    message: str
    optimizer: Any = field(repr=False, default=None)  # scipy's OptimizeResult


def _data(data: object) -> list[tuple[str, np.ndarray, np.ndarray]]:
    items = data.items() if isinstance(data, Mapping) else data
    out = []
    try:
        for test, curve in items:  # type: ignore[union-attr]
            x, y = (np.asarray(a, dtype=float).ravel() for a in curve)
            if x.size != y.size or x.size == 0:
                raise InputError(
                    f"data for {test!r}: stretch and stress need the same, non-zero length, "
                    f"got {x.size} and {y.size}"
                )
            if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
                raise InputError(f"data for {test!r}: stretches and stresses must be finite")
            out.append((_test_name(test), x, y))
    except (TypeError, ValueError) as exc:
        if isinstance(exc, InputError):
            raise
        raise InputError(
            "data must map a test to (stretch, stress) arrays, e.g. "
            "{'uniaxial': (stretch, stress), 'shear': (gamma, stress)}"
        ) from None
    if not out:
        raise InputError("no data to fit")
    return out


def fit_material(
    model: str,
    data: Mapping[str, tuple] | list[tuple],
    *,
    initial: Mapping[str, Any],
    fixed: Mapping[str, Any] | None = None,
    incompressible: bool = True,
    bounds: Mapping[str, tuple[float, float]] | None = None,
) -> FitResult:
    """Fit the parameters of law ``model`` to stress-stretch ``data``.

    ``data`` maps "uniaxial", "equibiaxial" (or "biaxial") and "shear" to (stretch, nominal
    stress in Pa) arrays (shear: amount of shear gamma and the shear stress). ``initial`` gives
    the parameters to fit with their starting values (a list, such as Ogden's c and m, fits
    each entry), ``fixed`` those held. ``incompressible`` (default) compares with the
    incompressible closed forms; the bulk parameter (k, or cp) may then be left out. ``bounds``
    maps a fitted parameter to (low, high). Least squares: ``scipy.optimize.least_squares``.

    ``fit_material("mooney_rivlin", {"uniaxial": (stretch, stress)},
    initial={"c1": 1e3, "c2": 1e2})`` returns a ``FitResult`` with ``.parameters`` and
    ``.material``."""
    from scipy.optimize import least_squares

    name = str(model).strip().lower().replace("-", "_").replace(" ", "_")
    name = ALIASES.get(name, name)
    if name not in MATERIALS:
        make_material(model)  # the registry's message, with suggestions
    curves = _data(data)
    fixed = dict(fixed or {})
    if not initial:
        raise InputError("initial must give at least one parameter to fit, with its start")
    both = set(initial) & set(fixed)
    if both:
        raise InputError(f"parameters both fitted and fixed: {', '.join(sorted(both))}")
    scale = max(float(np.max(np.abs(y))) for _, _, y in curves) or 1.0
    keywords = inspect.signature(MATERIALS[name].__init__).parameters
    bulk = next((b for b in ("k", "cp") if b in keywords), None)
    if bulk and bulk not in initial and bulk not in fixed:
        if not incompressible:
            raise InputError(f"a compressible fit of {name} needs {bulk} in fixed or initial")
        fixed[bulk] = 1e6 * scale  # any positive value: it does not act at J = 1
    # the fitted values as one vector, and back
    layout = []
    x0 = []
    for pname, value in initial.items():
        values = np.atleast_1d(np.asarray(value, dtype=float))
        layout.append((pname, values.size, np.ndim(value) > 0))
        x0.extend(values.tolist())
    unknown = set(bounds or {}) - set(initial)
    if unknown:
        raise InputError(f"bounds given for parameters not fitted: {', '.join(sorted(unknown))}")
    lower, upper = _bounds(layout, x0, bounds or {})
    n = sum(x.size for _, x, _ in curves)
    if n < len(x0):  # always underdetermined: any fit would be one of infinitely many
        raise InputError(
            f"{n} data point{'s' * (n != 1)} for {len(x0)} fitted parameters "
            f"({', '.join(p for p, _, _ in layout)}): the fit is underdetermined; give at "
            "least as many points as parameters, or hold some in fixed"
        )

    def parameters(x: np.ndarray) -> dict[str, Any]:
        out, start = dict(fixed), 0
        for pname, size, is_list in layout:
            chunk = x[start : start + size]
            out[pname] = chunk.tolist() if is_list else float(chunk[0])
            start += size
        return out

    make_material(name, **parameters(np.array(x0)))  # the start must be a valid law

    def residual(x: np.ndarray) -> np.ndarray:
        try:
            law = make_material(name, **parameters(x))
            r = np.concatenate(
                [nominal_stress(law, t, s, incompressible=incompressible) - y for t, s, y in curves]
            )
        except MaterialError:
            return np.full(n, 1e3)  # outside the law's valid parameters
        return np.where(np.isfinite(r), r / scale, 1e3)

    result = least_squares(
        residual, np.array(x0), bounds=(lower, upper), x_scale="jac", xtol=1e-14, ftol=1e-14,
        gtol=1e-14, max_nfev=2000 * max(1, len(x0)),
    )  # fmt: skip
    params = parameters(result.x)
    success, message = bool(result.success), str(result.message)
    rank = _rank(result.jac)
    if rank < len(x0):  # enough points, but they do not tell the parameters apart
        success = False
        message = (
            f"underdetermined: the data determine only {rank} combination"
            f"{'s' * (rank != 1)} of the {len(x0)} fitted parameters (points at too few "
            "stretches, or a test that does not tell them apart); the values returned are one "
            f"fit of many. Add data or hold some parameters in fixed. ({message})"
        )
    return FitResult(
        model=name,
        parameters=params,
        material=make_material(name, **params),
        rms=float(np.sqrt(np.mean(result.fun**2))),
        success=success,
        message=message,
        optimizer=result,
    )


def _bounds(layout: list, x0: list, bounds: Mapping) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) per fitted value; InputError naming the parameter whose bounds are
    not a pair, inverted, or exclude its initial value."""
    lower, upper = np.full(len(x0), -np.inf), np.full(len(x0), np.inf)
    start = 0
    for pname, size, _ in layout:
        if pname in bounds:
            try:
                low, high = (float(v) for v in bounds[pname])
            except (TypeError, ValueError):
                raise InputError(
                    f"bounds for {pname}: expected (low, high), got {short(bounds[pname])}"
                ) from None
            if not low < high:
                raise InputError(
                    f"bounds for {pname}: low {low:g} must be below high {high:g} (swap them)"
                )
            outside = [v for v in x0[start : start + size] if not low <= v <= high]
            if outside:
                raise InputError(
                    f"initial {pname} = {outside[0]:g} is outside its bounds ({low:g}, {high:g})"
                )
            lower[start : start + size], upper[start : start + size] = low, high
        start += size
    return lower, upper


def _rank(jac: np.ndarray) -> int:
    """The numerical rank of the residual's Jacobian at the fit (columns scaled to unit norm,
    so parameters of different units compare)."""
    jac = np.asarray(jac, dtype=float)
    norms = np.linalg.norm(jac, axis=0)
    if not np.all(np.isfinite(jac)):
        return jac.shape[1]  # nothing to judge by
    scaled = jac[:, norms > 0] / norms[norms > 0]
    if scaled.size == 0:
        return 0
    s = np.linalg.svd(scaled, compute_uv=False)
    return int(np.sum(s > 1e-8 * s[0]))
