"""Fit a simulation's parameters to measured forces and displacements: least squares
(``scipy.optimize.least_squares``, trust region within bounds) with the Jacobian of the run's
observations from one differentiated run per iteration (``sensitivity.py``), not one run per
parameter as finite differences take.

The residual is (simulated - measured) / scale over every step and observation (NaN in the
data: not measured); ``scale`` defaults to each observation's largest measured magnitude, so
forces in newtons and displacements in metres weigh alike. The parameters' standard errors come
from the Jacobian at the fit, s^2 (J^T J)^-1 with s^2 the residual variance (the data's noise
if it is white and the model fits).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from tissuesim.errors import ConvergenceError, InputError
from tissuesim.identification.sensitivity import sensitivities

__all__ = ["Identification", "identify"]


@dataclass
class Identification:
    """The fit: ``parameters`` and their ``std`` (standard errors, same units), ``rms`` of
    the scaled residual, ``runs`` (simulations run), ``success`` and ``message``, ``values``
    (steps, m) simulated at the fit, ``jacobian`` (steps, m, p) there."""

    parameters: dict[str, float]
    std: dict[str, float]
    rms: float
    runs: int
    success: bool
    message: str
    values: np.ndarray
    jacobian: np.ndarray
    optimizer: object = field(default=None, repr=False)


def _data(data, steps: int) -> np.ndarray:
    d = np.asarray(data, dtype=float)
    if d.ndim == 1:
        d = d[:, None]
    if d.ndim != 2 or d.shape[0] != steps:
        raise InputError(
            f"identify: data must be (steps, values) = ({steps}, m): one row per step, one "
            f"column per observed value; got shape {np.shape(data)}"
        )
    if not np.isfinite(d).any():
        raise InputError("identify: data holds no finite value (NaN marks what was not measured)")
    return d


def identify(
    build: Callable[[dict], object],
    initial: Mapping[str, float],
    observations: Sequence,
    data,
    steps: int,
    *,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    scale: Sequence[float] | None = None,
    max_runs: int = 50,
) -> Identification:
    """Fit the parameters ``initial`` (name -> starting value) of ``build(params) ->
    Simulation`` so that its ``observations`` after each of ``steps`` steps match ``data``
    (steps, m): module docstring. ``bounds``: name -> (low, high). ``max_runs``: at most this
    many differentiated runs."""
    from scipy.optimize import least_squares

    names = list(initial)
    x0 = np.array([float(initial[k]) for k in names])
    bounds = dict(bounds or {})
    unknown = set(bounds) - set(names)
    if unknown:
        raise InputError(f"identify: bounds for parameters not fitted: {sorted(unknown)}")
    lower = np.array([float(bounds.get(k, (-np.inf, np.inf))[0]) for k in names])
    upper = np.array([float(bounds.get(k, (-np.inf, np.inf))[1]) for k in names])
    if np.any(lower >= upper) or np.any(x0 <= lower) or np.any(x0 >= upper):
        raise InputError("identify: each bound must be low < initial value < high")
    d = _data(data, steps)
    measured = np.isfinite(d)
    if scale is None:
        top = np.nanmax(np.abs(np.where(measured, d, np.nan)), axis=0)
        scale = np.where(np.isfinite(top) & (top > 0), top, 1.0)
    scale = np.broadcast_to(np.asarray(scale, dtype=float), (d.shape[1],))
    if measured.sum() < len(names):
        raise InputError(
            f"identify: {int(measured.sum())} measured values for {len(names)} parameters: the "
            "fit is underdetermined"
        )
    cache: dict = {}
    runs = 0

    def evaluate(x: np.ndarray):
        nonlocal runs
        key = tuple(x.tolist())
        if key not in cache:
            runs += 1
            try:
                r = sensitivities(build, dict(zip(names, x.tolist(), strict=True)),
                                  observations, steps)  # fmt: skip
            except ConvergenceError:
                cache[key] = None
            else:
                if r.values.shape != d.shape:
                    raise InputError(
                        f"identify: data has {d.shape[1]} columns, the observations give "
                        f"{r.values.shape[1]} values a step"
                    )
                cache.clear()
                cache[key] = r
        return cache[key]

    def residual(x: np.ndarray) -> np.ndarray:
        r = evaluate(x)
        if r is None:  # a run that did not converge: far from the data
            return np.full(int(measured.sum()), 1e3)
        return ((r.values - d) / scale)[measured]

    def jacobian(x: np.ndarray) -> np.ndarray:
        r = evaluate(x)
        if r is None:
            return np.zeros((int(measured.sum()), len(names)))
        return (r.jacobian / scale[None, :, None])[measured]

    result = least_squares(residual, x0, jac=jacobian, bounds=(lower, upper), x_scale="jac",
                           max_nfev=max_runs)  # fmt: skip
    best = evaluate(result.x)
    if best is None:
        raise ConvergenceError("identify: the run at the fitted parameters does not converge")
    J = result.jac
    dof = max(int(measured.sum()) - len(names), 1)
    s2 = float(result.fun @ result.fun) / dof
    try:
        cov = np.linalg.inv(J.T @ J) * s2
        std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        std = np.full(len(names), np.inf)
    return Identification(
        parameters=dict(zip(names, result.x.tolist(), strict=True)),
        std=dict(zip(names, std.tolist(), strict=True)),
        rms=float(np.sqrt(np.mean(result.fun**2))),
        runs=runs,
        success=bool(result.success),
        message=str(result.message),
        values=best.values,
        jacobian=best.jacobian,
        optimizer=result,
    )
