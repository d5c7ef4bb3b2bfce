"""Viscoelastic relaxation against the Prony series' closed form: a unit Q1 cube in
homogeneous uniaxial stress (three symmetry planes, one face pulled), a neo-Hookean law under
FEBio's ``viscoelastic`` with two terms.

Held stretch l after a ramp over the first step t_r: the elastic stress ramps linearly in time,
so the convolution gives S11(t) = Se11 [g0 + sum_i g_i tau_i / t_r (1 - exp(-t_r/tau_i))
exp(-(t - t_r)/tau_i)], with Se11 the law's uniaxial stress: P = mu F + (lam ln J - mu) F^-T,
the lateral stretch from P22 = 0 (solved to round-off), Se11 = P11 / l."""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

import tissuesim as ts
from tissuesim.verification.result import Check

__all__ = ["checks", "relaxation"]

G, TAU, MU, LAM, STRETCH, H = (0.6, 0.3), (0.05, 0.4), 400.0, 600.0, 1.2, 0.01
TOL = 1e-4


def _elastic_pk2(l1: float) -> float:
    l2 = brentq(lambda l: MU * l + (LAM * np.log(l1 * l * l) - MU) / l, 0.2, 2.0, xtol=1e-15)
    return (MU * l1 + (LAM * np.log(l1 * l2 * l2) - MU) / l1) / l1


def relaxation(times: tuple[float, ...] = (0.01, 0.05, 0.2, 0.6)) -> list[tuple[float, float]]:
    """(reference, computed) S11 (Pa) at ``times`` (multiples of the step 0.01 s)."""
    mesh = ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="hex")
    law = ts.Viscoelastic(ts.NeoHookean(shear_modulus=MU, lame_lambda=LAM), g=G, tau=TAU)
    sim = ts.Simulation(mesh, law, integrator="quasistatic", time_step=H)
    for axis in range(3):
        sim.add_dirichlet(ts.select.vertices_on_plane(mesh, axis=axis, value=0.0),
                          components=(axis,))  # fmt: skip
    right = ts.select.vertices_on_plane(mesh, axis=0, value=1.0)
    sim.add_dirichlet(right, [STRETCH - 1.0, 0.0, 0.0], components=(0,), name="pull")
    Se, out = _elastic_pk2(STRETCH), []
    for n in range(1, round(max(times) / H) + 1):
        record = sim.step()
        t = n * H
        if any(abs(t - s) < 1e-9 for s in times):
            decay = sum(g * tau / H * (1 - np.exp(-H / tau)) * np.exp(-(t - H) / tau)
                        for g, tau in zip(G, TAU, strict=True))  # fmt: skip
            out.append((Se * (1.0 + decay), record.extra["forces"]["pull"][0] / STRETCH))
    return out


def checks() -> list[Check]:
    """S11 at four times of the relaxation against the closed form (relative 1e-4)."""
    times = (0.01, 0.05, 0.2, 0.6)
    return [
        Check("viscoelastic relaxation, Q1 cube", f"S11 at t = {t:g} s", ref, got, TOL)
        for t, (ref, got) in zip(times, relaxation(times), strict=True)
    ]
