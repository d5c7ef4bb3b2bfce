"""Elastic damage against its softening curve's closed form: a unit Q1 cube in uniaxial stress
(three symmetry planes, one face pulled), FEBio's ``elastic damage`` on a neo-Hookean law with
lambda = 0 (no lateral strain: F = diag(l, 1, 1), P11 = mu (l - 1/l)), the criterion the largest
Lagrange strain X = (l^2 - 1)/2 and a Weibull CDF, D = Dmax (1 - exp(-(X/m)^a)).

Loaded to l = 1.3, unloaded to 1.1, reloaded to 1.4 (0.01 per step) and held a step: FEBio's
force at step n is (1 - D(max_{m<=n} X_m)) P11(l_n); tissuesim freezes D over a step at the
accepted state's (``materials/reactive/damage.py``), so its force is (1 - D(max_{m<n} X_m))
P11(l_n), the same after a held step. The checks: the lagged curve to round-off, and FEBio's at
the held end."""

from __future__ import annotations

import numpy as np

import tissuesim as ts
from tissuesim.verification.result import Check

__all__ = ["checks", "softening", "stretch_path"]

MU, ALPHA, M, DMAX, STEP = 100.0, 2.0, 0.15, 0.8, 0.01
TOL = 1e-8


def stretch_path() -> np.ndarray:
    """The stretch at the end of each step: 1 -> 1.3 -> 1.1 -> 1.4, then one step held."""
    up = np.arange(1.01, 1.3 + 1e-9, STEP)
    down = np.arange(1.29, 1.1 - 1e-9, -STEP)
    again = np.arange(1.11, 1.4 + 1e-9, STEP)
    return np.concatenate([up, down, again, [1.4]])


def damage(X: np.ndarray) -> np.ndarray:
    """D of the Weibull CDF at the criterion's maximum X."""
    return DMAX * -np.expm1(-((np.maximum(X, 0.0) / M) ** ALPHA))


def closed_form(stretches: np.ndarray, lagged: bool) -> np.ndarray:
    """P11 at each step's end: FEBio's (D of the maximum up to this step) or tissuesim's (D of
    the maximum up to the step before)."""
    X = 0.5 * (stretches**2 - 1.0)
    xmax = np.maximum.accumulate(X)
    if lagged:
        xmax = np.concatenate([[0.0], xmax[:-1]])
    return (1.0 - damage(xmax)) * MU * (stretches - 1.0 / stretches)


def softening() -> tuple[np.ndarray, np.ndarray]:
    """(stretches, tissuesim's pull force per unit area) along ``stretch_path``."""
    path = stretch_path()
    mesh = ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="hex")
    law = ts.materials.make_material(
        "elastic_damage",
        elastic={"model": "neo_hookean", "shear_modulus": MU, "lame_lambda": 0.0},
        damage={"model": "weibull", "alpha": ALPHA, "mu": M, "Dmax": DMAX},
        criterion="max_normal_lagrange_strain",
    )
    sim = ts.Simulation(mesh, law, integrator="quasistatic", time_step=1.0)
    for axis in range(3):
        sim.add_dirichlet(ts.select.vertices_on_plane(mesh, axis=axis, value=0.0),
                          components=(axis,))  # fmt: skip
    right = ts.select.vertices_on_plane(mesh, axis=0, value=1.0)

    def pull(X: np.ndarray, t: float) -> np.ndarray:
        u = np.zeros_like(X)
        u[:, 0] = path[min(max(round(t) - 1, 0), path.size - 1)] - 1.0
        return u

    sim.add_dirichlet(right, pull, components=(0,), name="pull")
    forces = [sim.step().extra["forces"]["pull"][0] for _ in path]
    return path, np.asarray(forces)


def checks() -> list[Check]:
    """The force at the peak, after unloading, at the end of reloading (lagged closed form) and
    held (FEBio's), relative 1e-8."""
    path, got = softening()
    lagged, febio = closed_form(path, True), closed_form(path, False)
    name = "elastic damage softening, Q1 cube"
    peak = int(np.argmax(path > 1.3 - 1e-9))
    picks = {"P11 at the first peak l = 1.3": peak, "P11 unloaded to l = 1.1": 2 * peak - 9,
             "P11 reloaded to l = 1.4": path.size - 2}  # fmt: skip
    out = [Check(name, what, lagged[i], got[i], TOL) for what, i in picks.items()]
    out.append(Check(name, "P11 held at l = 1.4 (FEBio's D)", febio[-1], got[-1], TOL))
    return out
