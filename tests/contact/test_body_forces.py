"""Body-to-body contact forces (contact/readout/body_forces.py): what each body receives from each
other body, as a force sensor between them reads it: equal and opposite, carrying a resting block's
weight, split into the barrier's and the friction's parts on an incline where it sticks."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts

pytest.importorskip("ipctk")

MATERIAL = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
DENSITY = 100.0
G = 9.81


def resting_blocks(gravity, friction: float = 0.0) -> ts.Simulation:
    """A 0.6 x 0.6 x 0.3 m block set 4 mm above a fixed one (within dhat: on the barrier),
    Backward Euler until it rests."""
    sim = ts.Simulation(integrator="backward_euler", time_step=0.05)
    sim.add_body("low", ts.box((0, 0, 0), (1, 1, 0.3), (3, 3, 1)), MATERIAL, density=DENSITY)
    top = ts.box((0.2, 0.2, 0.304), (0.8, 0.8, 0.604), (2, 2, 1))
    sim.add_body("high", top, MATERIAL, density=DENSITY)
    sim.fix("low", ts.select.vertices_on_plane(sim.bodies["low"].mesh, axis=2, value=0.0))
    sim.add_gravity(gravity)
    sim.set_contact(dhat=0.01, friction=friction)
    return sim


def test_a_resting_block_receives_its_weight_from_the_block_below_and_gives_it_back():
    sim = resting_blocks([0.0, 0.0, -G])
    records = [sim.step() for _ in range(30)]
    assert all(r.converged for r in records)
    record = records[-1]
    forces = record.extra["forces"]
    up, down = np.array(forces["high.contact.low"]), np.array(forces["low.contact.high"])
    weight = DENSITY * 0.6 * 0.6 * 0.3 * G
    np.testing.assert_allclose(up, [0.0, 0.0, weight], rtol=1e-3, atol=1e-3 * weight)
    np.testing.assert_allclose(down, -up, rtol=1e-12, atol=1e-12 * weight)
    assert "high.contact.low.normal" not in forces  # frictionless: no parts


def test_on_an_incline_friction_holds_the_block_and_is_reported_apart():
    """Gravity tilted by 10 degrees, mu = 0.5 (it sticks): the force from below balances the
    weight, its friction part the weight's slope component."""
    theta = np.radians(10.0)
    sim = resting_blocks([G * np.sin(theta), 0.0, -G * np.cos(theta)], friction=0.5)
    records = [sim.step() for _ in range(30)]
    assert all(r.converged for r in records)
    forces = records[-1].extra["forces"]
    weight = DENSITY * 0.6 * 0.6 * 0.3 * G
    total = np.array(forces["high.contact.low"])
    np.testing.assert_allclose(
        total, [-weight * np.sin(theta), 0, weight * np.cos(theta)], rtol=1e-3, atol=1e-3 * weight
    )
    normal = np.array(forces["high.contact.low.normal"])
    friction = np.array(forces["high.contact.low.friction"])
    np.testing.assert_allclose(normal + friction, total, rtol=1e-12, atol=1e-12 * weight)
    assert friction[0] < -0.9 * weight * np.sin(theta)  # friction carries the slope's pull
    np.testing.assert_allclose(forces["low.contact.high"], -total, atol=1e-9 * weight)


def test_a_body_alone_or_against_obstacles_reports_no_body_forces():
    sim = ts.Simulation(ts.box((0, 0, 0.001), (1, 1, 0.3), (2, 2, 1)), MATERIAL, density=DENSITY)
    from tissuesim.contact.obstacles import plane

    sim.add_obstacle("floor", plane((0.5, 0.5, 0.0), (0, 0, 1), 4.0))
    sim.set_contact(dhat=0.01)
    sim.add_gravity([0.0, 0.0, -G])
    forces = sim.step().extra["forces"]
    assert "floor" in forces and not any(".contact." in name for name in forces)
