"""FEBio's three-field (mean-dilatation) element at rhoi = 1 (time/integrators/
three_field_midpoint.py): the end-pressure energy's derivatives, the step's internal work, and
the energy a free swing keeps."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.energies.accumulator import Accumulator
from tissuesim.time.integrators.three_field_midpoint import (
    EndPressure,
    end_pressure_correction,
    takes_end_pressure,
)

MATERIAL = ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.45)


def _body(divisions=(3, 2, 2)):
    """A hex8 block with the mean-dilatation (three-field) energy, and its model."""
    mesh = ts.box((0, 0, 0), (1, 0.5, 0.5), divisions, element="hex")
    sim = ts.Simulation(integrator="generalized_alpha", generalized_alpha=1.0, time_step=0.01)
    sim.add_body("block", mesh, MATERIAL, density=1000.0, formulation="mean_dilatation")
    return sim, mesh, sim.body("block").model


def _configurations(mesh, seed=3):
    rng = np.random.default_rng(seed)
    x0 = mesh.points.ravel() + 0.02 * rng.standard_normal(mesh.points.size)
    x1 = x0 + 0.03 * rng.standard_normal(mesh.points.size)
    return x0, x1


def _evaluate(model, energy, y, order, project=False):
    acc = Accumulator(model.pattern, order, project)
    energy.accumulate(y, acc)
    return acc


def test_the_end_pressure_energy_has_its_gradient_and_hessian():
    """EndPressure's value, gradient and Hessian (not projected) against central differences
    at a deformed y, with x_n elsewhere (alpha_f = 1/2: x_{n+1} = 2 y - x_n)."""
    _, mesh, model = _body()
    assert takes_end_pressure(model.elastic)
    x0, x1 = _configurations(mesh)
    energy = EndPressure(model.elastic, x0, 0.5)
    y = 0.5 * (x0 + x1)
    d = np.random.default_rng(7).standard_normal(y.size)
    eps = 1e-6
    acc = _evaluate(model, energy, y, 2)
    e_p, e_m = (_evaluate(model, energy, y + s * d, 0).value for s in (eps, -eps))
    assert (e_p - e_m) / (2 * eps) == pytest.approx(acc.gradient @ d, rel=1e-6)
    g_p, g_m = (_evaluate(model, energy, y + s * d, 1).gradient for s in (eps, -eps))
    Hd = model.pattern.matrix(acc.hessian) @ d
    assert np.allclose(Hd, (g_p - g_m) / (2 * eps), rtol=0, atol=1e-6 * np.abs(Hd).max())


def test_the_steps_internal_work_is_the_change_of_the_points_energy():
    """FEBio's force at y = x_{n+1/2} (the element pressure at x_{n+1}, the correction c D):
    its work over x_{n+1} - x_n is sum_q w_q (W(F_{n+1}) - W(F_n)) with W the law's energy at
    each point, to round-off; the plain mean-dilatation force at y misses by far more."""
    _, mesh, model = _body()
    x0, x1 = _configurations(mesh)
    h, y = 0.01, 0.5 * (x0 + x1)
    K, law = model.kinematics, model.material
    W0, W1 = (K.weights @ law.evaluate(K.deformation_gradients(x), 0).energy for x in (x0, x1))
    f_step = model.evaluate(y, 1, False).gradient
    f_swap = _evaluate(model, EndPressure(model.elastic, x0, 0.5), y, 1).gradient
    f_c = end_pressure_correction(model.elastic, x0, x1, h)
    assert (x1 - x0) @ (f_step + f_swap + f_c) == pytest.approx(W1 - W0, rel=1e-10)
    assert abs((x1 - x0) @ f_step - (W1 - W0)) > 1e-3 * abs(W1 - W0)


def _pointwise_energy(model, x) -> float:
    K = model.kinematics
    return float(K.weights @ model.material.evaluate(K.deformation_gradients(x), 0).energy)


def _stretching_cube(steps: int) -> np.ndarray:
    """A unit hex8 cube (mean dilatation, neo-Hookean, nu = 0.45) on rollers at x, y, z = 0,
    let go with v = (-0.15 x, 0, 0.5 z) (homogeneous: J the same at every point): kinetic +
    sum_q w_q W(F_q) after each step."""
    mesh = ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="hex")
    sim = ts.Simulation(integrator="generalized_alpha", generalized_alpha=1.0, time_step=0.05)
    law = ts.NeoHookean(youngs_modulus=10.0, poisson_ratio=0.45)
    sim.add_body("cube", mesh, law, density=1.0, formulation="mean_dilatation")
    for axis in range(3):
        sim.add_dirichlet(ts.select.vertices_on_plane(mesh, axis=axis, value=0.0),
                          components=(axis,))  # fmt: skip
    v = np.zeros((mesh.n_points, 3))
    v[:, 0], v[:, 2] = -0.15 * mesh.points[:, 0], 0.5 * mesh.points[:, 2]
    sim.set_velocity(v)
    model = sim.body("cube").model
    energy = []
    for _ in range(steps):
        record = sim.step()
        energy.append(record.energies["kinetic"] + _pointwise_energy(model, sim.state.x))
    return np.array(energy)


def test_a_stretching_cube_keeps_the_kinetic_plus_the_points_energy(monkeypatch):
    """rho_inf = 1: FEBio's three-field scheme is a discrete gradient of the points' energy
    (the work test above), so kinetic + sum_q w_q W(F_q) stays at the start's, the kinetic
    energy given, rho/2 int |v|^2 = (0.15^2 + 0.5^2) / 6 (the consistent mass is exact for
    the linear field), to 1e-8 over 60 steps; the plain midpoint rule on the mean-dilatation
    energy (the correction switched off) drifts by more than 1e-4."""
    import tissuesim.time.integrators.generalized_alpha as ga

    energy = _stretching_cube(60)
    assert energy[0] == pytest.approx((0.15**2 + 0.5**2) / 6.0, rel=1e-8)
    assert np.abs(energy - energy[0]).max() < 1e-8 * energy[0]
    monkeypatch.setattr(ga, "takes_end_pressure", lambda elastic: False)
    plain = _stretching_cube(60)
    assert np.abs(plain - plain[0]).max() > 1e-4 * plain[0]


def test_a_correction_that_does_not_settle_leaves_the_plain_midpoint_step(monkeypatch):
    """Without updates (MIDPOINT_UPDATES = 0) the three-field correction cannot settle: every
    step falls back to the plain midpoint rule, the same steps as with the correction off (to
    the round-off of the solver's reused factors)."""
    import tissuesim.time.integrators.generalized_alpha as ga

    monkeypatch.setattr(ga, "MIDPOINT_UPDATES", 0)
    unsettled = _stretching_cube(10)
    monkeypatch.setattr(ga, "takes_end_pressure", lambda elastic: False)
    np.testing.assert_allclose(unsettled, _stretching_cube(10), rtol=1e-10)
