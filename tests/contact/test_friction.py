"""IPC's smoothed, lagged Coulomb friction (contact/model.py): its gradient against finite
differences, and a block on an incline that sticks for tan(theta) < mu and slides with
a = g (sin theta - mu cos theta) otherwise."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts

pytest.importorskip("ipctk")

from tissuesim.contact.obstacles import plane  # noqa: E402

G = 9.81


def block_on_incline(tan_theta: float, mu: float, h: float = 0.01) -> ts.Simulation:
    theta = np.arctan(tan_theta)
    mesh = ts.box((0, 0, 5e-5), (0.1, 0.1, 0.05 + 5e-5), (3, 3, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="backward_euler", time_step=h)
    # the incline as tilted gravity on a horizontal plane
    sim.add_gravity([G * np.sin(theta), 0.0, -G * np.cos(theta)])
    sim.add_obstacle("ramp", plane((0.05, 0.05, 0.0), (0, 0, 1), 8.0))
    sim.set_contact(dhat=1e-4, friction=mu)
    return sim


def _slide(sim: ts.Simulation, steps: int) -> tuple[np.ndarray, list]:
    velocities, records = [], []
    for _ in range(steps):
        records.append(sim.step())
        velocities.append(sim.state.v.reshape(-1, 3)[:, 0].mean())
    return np.array(velocities), records


def test_friction_gradient_matches_finite_differences():
    """The friction term alone (contact energy with the friction lagged minus without), through
    the map from the system's DOFs to the collision mesh."""
    sim = block_on_incline(0.8, 0.5)
    for _ in range(3):
        sim.step()
    contact = sim.system.contact
    x0 = sim.state.x.copy()
    V0 = contact.vertices(x0)
    rng = np.random.default_rng(0)
    x = x0.copy()
    x[0::3] += 2e-4 * rng.random(x.size // 3)  # slide a little: the friction is active

    def friction(y: np.ndarray, order: int):
        contact.lag_friction(V0, V0, sim.time_step)
        value, grad, _ = contact.evaluate(y, order)
        contact.clear_friction()
        value0, grad0, _ = contact.evaluate(y, order)
        return value - value0, (None if grad is None else grad - grad0)

    value, grad = friction(x, 1)
    assert value > 0 and np.abs(grad).max() > 0
    h = 1e-8
    for _ in range(5):
        d = rng.standard_normal(x.size)
        fd = (friction(x + h * d, 0)[0] - friction(x - h * d, 0)[0]) / (2 * h)
        # relative to |grad| |d|: a direction nearly normal to the gradient has a small
        # derivative next to the curvature's O(h^2) term
        assert abs(fd - grad @ d) <= 1e-6 * np.linalg.norm(grad) * np.linalg.norm(d)


def test_a_block_sticks_below_the_friction_angle():
    sim = block_on_incline(0.3, 0.5)
    v, records = _slide(sim, 40)
    assert abs(v[-1]) < 1e-3  # below eps_v: static (IPC's smoothed stick)
    assert all(r.converged and r.extra["contact"]["friction_solves"] == 2 for r in records)


def test_a_block_slides_above_it_with_coulombs_acceleration():
    tan_theta, mu = 0.8, 0.5
    theta = np.arctan(tan_theta)
    sim = block_on_incline(tan_theta, mu)
    v, records = _slide(sim, 60)
    t = sim.time_step * np.arange(1, 61)
    a = np.polyfit(t[30:], v[30:], 1)[0]
    expected = G * (np.sin(theta) - mu * np.cos(theta))
    assert a == pytest.approx(expected, rel=0.02)
    frictionless = block_on_incline(tan_theta, 0.0)
    v0, _ = _slide(frictionless, 30)
    a0 = np.polyfit(t[15:30], v0[15:], 1)[0]
    assert a0 == pytest.approx(G * np.sin(theta), rel=0.02)


def test_friction_hessian_matches_differences_of_its_gradient():
    sim = block_on_incline(0.8, 0.5)
    for _ in range(3):
        sim.step()
    contact = sim.system.contact
    x0 = sim.state.x.copy()
    V0 = contact.vertices(x0)
    rng = np.random.default_rng(1)
    x = x0.copy()
    x[0::3] += 2e-4 * rng.random(x.size // 3)

    def friction(y: np.ndarray):
        contact.lag_friction(V0, V0, sim.time_step)
        _, grad, hess = contact.evaluate(y, 2, project=False)
        contact.clear_friction()
        _, grad0, hess0 = contact.evaluate(y, 2, project=False)
        return grad - grad0, hess - hess0

    _, H = friction(x)
    h = 1e-9
    for _ in range(3):
        d = rng.standard_normal(x.size)
        fd = (friction(x + h * d)[0] - friction(x - h * d)[0]) / (2 * h)
        assert np.linalg.norm(fd - H @ d) <= 1e-4 * np.linalg.norm(H @ d)
