"""Quasistatics of a body that only contact holds (time/integrators/pseudo_time.py): an organ
resting on a table, then pressed by a probe. Each step comes to rest in pseudo-time, and the
result is a static equilibrium: the table carries the weight, table and probe together carry it
once the probe presses, no state intersects, and the bodies are at rest (zero velocity)."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError

pytest.importorskip("ipctk")
from tissuesim.contact.obstacles import plane, sphere  # noqa: E402


def organ_on_table(friction: float = 0.3, probe: bool = False) -> ts.Simulation:
    mesh = ts.ellipsoid((0.0, 0.0, 0.0305), (0.04, 0.03, 0.03), 4)
    material = ts.make_material("neo_hookean", youngs_modulus=5e3, poisson_ratio=0.45)
    sim = ts.Simulation(
        mesh,
        material,
        density=1000.0,
        integrator="quasistatic",
        time_step=0.1,
        gravity=(0.0, 0.0, -9.81),
    )
    sim.set_contact(dhat=2e-4, friction=friction)
    sim.add_obstacle("table", plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.2))
    if probe:  # 1 mm above the crest, 3 and 2 mm off it, down at 20 mm/s
        sim.add_obstacle(
            "probe",
            sphere((0.003, 0.002, 0.0715), 0.01),
            translation=lambda t: (0.0, 0.0, -0.02 * t),
        )
    return sim


def weight(sim) -> float:
    return float(sim.model.mass.lumped.sum() / 3 * 9.81)


def static_residual(sim) -> float:
    s = sim.system
    energies = sim.step_energies(sim.time, None, sim.time_step)
    with s.contact.last_step_lag():
        g = s.evaluate(sim.state.x, 1, False, energies).gradient
    free = np.ones(g.size, dtype=bool)
    free[s.elimination.dofs] = False
    return float(np.linalg.norm(g[free]))


def test_an_unsupported_organ_comes_to_rest_on_the_table_carrying_its_weight():
    sim = organ_on_table()
    for _ in range(2):
        record = sim.step()
        assert record.converged
        table = np.array(sim.forces()["table"])
        np.testing.assert_allclose(
            table, [0.0, 0.0, weight(sim)], rtol=1e-5, atol=1e-5 * weight(sim)
        )
        np.testing.assert_array_equal(sim.velocity, 0.0)
        assert not sim.system.contact.intersecting(sim.state.x)
        assert static_residual(sim) <= 1e-5 * weight(sim)
    assert sim.system.contact.proximity(sim.state.x)[0] < 2e-4  # resting within dhat
    assert sim.positions[:, 2].min() > 0.0


def test_a_probe_pressing_an_organ_held_by_contact_balances_table_and_probe():
    sim = organ_on_table(probe=True)
    pressed = []
    for _ in range(8):
        sim.step()
        f = sim.forces()
        total = np.add(f["table"], f["probe"])
        np.testing.assert_allclose(total, [0.0, 0.0, weight(sim)], atol=2e-5 * weight(sim))
        assert not sim.system.contact.intersecting(sim.state.x)
        pressed.append(-f["probe"][2])
    assert pressed[0] == pytest.approx(0.0, abs=1e-9)  # not touching yet
    assert pressed[-1] > 0.5 * weight(sim)  # presses hard by the end
    touching = [p for p in pressed if p > 1e-6]
    assert len(touching) >= 3 and np.all(np.diff(touching) > 0)  # deeper, harder


def test_frictionless_contact_alone_is_refused_with_the_reason():
    sim = organ_on_table(friction=0.0)
    with pytest.raises(InputError, match="needs friction.*free to slide"):
        sim.step()


def test_without_contact_the_refusal_says_contact_could_hold_it():
    mesh = ts.ellipsoid((0.0, 0.0, 0.0305), (0.04, 0.03, 0.03), 3)
    material = ts.make_material("neo_hookean", youngs_modulus=5e3, poisson_ratio=0.45)
    sim = ts.Simulation(mesh, material, integrator="quasistatic", gravity=(0.0, 0.0, -9.81))
    with pytest.raises(InputError, match="rigid motions.*set_contact"):
        sim.step()
