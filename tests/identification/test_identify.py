"""Fitting a run's parameters to measurements (identification/fit.py): a compressed block's
stiffness and Poisson's ratio from its force and its bulge with 1 % noise; the runs it takes;
its standard errors; bad data refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.mesh import select

STEPS = 4
TRUE = {"E": 5e4, "nu": 0.35}


def block(p):
    mesh = ts.box((0, 0, 0), (1.0, 1.0, 1.0), (2, 2, 2))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=p["nu"]),
                        integrator="quasistatic", time_step=0.25)  # fmt: skip
    bottom = select.vertices_on_plane(mesh, 2, 0.0)
    sim.add_dirichlet(bottom, (0.0, 0.0, 0.0), components=[2], name="table")
    sim.fix(bottom[:1], name="pin")  # no rigid drift in x, y
    top = select.vertices_on_plane(mesh, 2, 1.0)
    sim.add_dirichlet(top, lambda X, t: np.full(len(X), -0.1 * t)[:, None], components=[2],
                      name="platen")  # fmt: skip
    return sim


def observations():
    mesh = block(TRUE).bodies["body"].mesh
    side = np.flatnonzero(np.isclose(mesh.points[:, 0], 1.0) & np.isclose(mesh.points[:, 2], 0.5))
    return [ts.Reaction("platen", component=2), ts.Displacement(side[:1], component=0)]


def test_identify_recovers_stiffness_and_poisson_ratio_from_noisy_force_and_bulge():
    obs = observations()
    clean = ts.sensitivities(block, TRUE, obs, STEPS).values
    noisy = clean * (1 + 0.01 * np.random.default_rng(3).standard_normal(clean.shape))
    fit = ts.identify(block, {"E": 2e4, "nu": 0.2}, obs, noisy, STEPS,
                      bounds={"E": (1e3, 1e6), "nu": (0.0, 0.49)})  # fmt: skip
    assert fit.success
    for k, v in TRUE.items():
        assert fit.parameters[k] == pytest.approx(v, rel=0.02), (k, fit.parameters)
        assert 0 < fit.std[k] < 0.05 * v  # the noise's spread, not zero, not huge
    assert fit.runs <= 15  # one differentiated run per iteration
    # without noise, the fit is exact
    exact = ts.identify(block, {"E": 2e4, "nu": 0.2}, obs, clean, STEPS,
                        bounds={"E": (1e3, 1e6), "nu": (0.0, 0.49)})  # fmt: skip
    for k, v in TRUE.items():
        assert exact.parameters[k] == pytest.approx(v, rel=1e-6)


def test_bad_data_and_bounds_are_refused_in_one_line():
    obs = observations()
    with pytest.raises(InputError, match=r"data must be \(steps, values\)"):
        ts.identify(block, {"E": 2e4}, obs, np.zeros((STEPS + 1, 2)), STEPS)
    with pytest.raises(InputError, match="low < initial value < high"):
        ts.identify(block, {"E": 2e4}, obs, np.ones((STEPS, 2)), STEPS, bounds={"E": (3e4, 1e5)})
    with pytest.raises(InputError, match="bounds for parameters not fitted"):
        ts.identify(block, {"E": 2e4}, obs, np.ones((STEPS, 2)), STEPS, bounds={"nu": (0, 0.4)})
