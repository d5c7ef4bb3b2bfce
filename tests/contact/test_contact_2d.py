"""Contact in 2D: the bodies' boundary edges (point-edge and edge-edge pairs through ipctk):
the energy's gradient and Hessian against finite differences, a block dropped on a block that
never intersects and rests with its weight on the support, CCD stopping a fast body, and the
one clear error for obstacles (3D surfaces) in a 2D scene."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts

ipctk = pytest.importorskip("ipctk")

from tissuesim.contact.obstacles import plane  # noqa: E402

MATERIAL = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)


def two_squares(gap: float, dhat: float = 0.01, gravity=(0.0, -9.81)) -> ts.Simulation:
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01, gravity=gravity)
    low = sim.add_body("low", ts.rectangle((0, 0), (1, 0.3), (6, 2)), MATERIAL, density=100.0)
    high = ts.rectangle((0.2, 0.3 + gap), (0.8, 0.6 + gap), (4, 2))
    sim.add_body("high", high, MATERIAL, density=100.0)
    sim.fix("low", ts.select.vertices_on_plane(low.mesh, axis=1, value=0.0), name="support")
    sim.set_contact(dhat=dhat)
    return sim


def test_2d_contact_energy_gradient_and_hessian_match_finite_differences():
    sim = two_squares(0.004)
    s, rng = sim.system, np.random.default_rng(2)
    assert s.contact.dim == 2
    x = sim.state.x + 1e-4 * rng.standard_normal(sim.state.x.size)
    value, grad, _ = s.contact.evaluate(x, 1)
    assert value > 0
    h = 1e-7
    for _ in range(5):
        d = rng.standard_normal(x.size)
        fd = (s.contact.evaluate(x + h * d, 0)[0] - s.contact.evaluate(x - h * d, 0)[0]) / (2 * h)
        assert fd == pytest.approx(grad @ d, rel=1e-5)
    exact = s.contact.evaluate(x, 2, project=False)[2]
    for _ in range(3):
        d = rng.standard_normal(x.size)
        fd = (s.contact.evaluate(x + h * d, 1)[1] - s.contact.evaluate(x - h * d, 1)[1]) / (2 * h)
        assert np.linalg.norm(fd - exact @ d) <= 1e-4 * np.linalg.norm(exact @ d)
    projected = s.contact.evaluate(x, 2)[2].toarray()  # what Newton uses: PSD per collision
    eig = np.linalg.eigvalsh(projected)
    assert eig.min() >= -1e-9 * eig.max()


def test_a_2d_block_dropped_on_a_block_rests_on_it_with_its_weight():
    sim = two_squares(0.05)
    records = []
    for _ in range(150):
        records.append(sim.step())
        assert not sim.system.contact.intersecting(sim.state.x, sim.time)
    assert all(r.converged for r in records)
    high = sim.body_positions("high")
    assert high[:, 1].min() > 0.3  # on the lower block, not in it
    weight = (1.0 * 0.3 + 0.6 * 0.3) * 100.0 * 9.81  # N per metre of thickness
    support = np.asarray(records[-1].extra["forces"]["support"])
    assert support[1] == pytest.approx(weight, rel=0.01)


def test_ccd_stops_a_fast_2d_body_before_it_crosses():
    """10 m/s, 0.01 s steps: 0.1 m per step against a 5 mm gap and a 2 mm barrier."""
    sim = two_squares(0.005, dhat=0.002, gravity=None)
    high = sim.bodies["high"]
    sim.set_velocity(np.tile([0.0, -10.0], (high.mesh.n_points, 1)), body="high")
    for _ in range(5):
        record = sim.step()
        assert record.converged
        assert not sim.system.contact.intersecting(sim.state.x, sim.time)
    # it did not tunnel: the impact dents the lower block, but the upper one stays above it
    assert sim.body_positions("high")[:, 1].min() > sim.body_positions("low")[:, 1].mean()


def test_obstacles_in_2d_are_one_clear_error():
    sim = two_squares(0.05)
    sim.add_obstacle("floor", plane((0.5, 0.5, 0.0), (0, 0, 1), 4.0))
    with pytest.raises(ts.InputError, match="contact in 2D: obstacles are not built"):
        sim.step()
