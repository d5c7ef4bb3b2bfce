"""IPC's adaptive barrier stiffness (contact/barrier/stiffness.py): kappa balances the other
energies' gradient when contact appears, within [E, 100 E], and doubles while the gap keeps closing
below round-off scale; a block on a floor with it rests carrying its weight."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts

ipctk = pytest.importorskip("ipctk")

from tissuesim.contact.barrier.stiffness import EPSILON, AdaptiveStiffness  # noqa: E402
from tissuesim.contact.obstacles import plane  # noqa: E402


def test_the_initial_stiffness_balances_the_gradients_within_its_bounds():
    rule = AdaptiveStiffness(kappa_min=10.0, diagonal=1.0)
    g_B = np.array([0.0, 0.0, 2.0])
    assert rule.initial(np.array([0.0, 0.0, -60.0]), g_B) == pytest.approx(30.0)  # 60 / 2
    assert rule.initialized
    assert rule.initial(np.array([0.0, 0.0, -1.0]), g_B) == 10.0  # never below kappa_min
    assert rule.initial(np.array([0.0, 0.0, -1e6]), g_B) == 1000.0  # nor above 100 kappa_min
    assert rule.initial(np.array([0.0, 0.0, 5.0]), g_B) == 10.0  # pulled apart: the minimum


def test_the_stiffness_doubles_only_while_a_tiny_gap_keeps_closing():
    rule = AdaptiveStiffness(kappa_min=10.0, diagonal=2.0)
    tiny = EPSILON * 2.0
    assert rule.update(10.0, 0.5 * tiny) == 10.0  # no previous distance yet
    assert rule.update(10.0, 0.25 * tiny) == 20.0  # below eps x diagonal and closing
    assert rule.update(20.0, 0.5 * tiny) == 20.0  # opening again
    assert rule.update(20.0, 1e-3) == 20.0 and rule.update(20.0, 1e-4) == 20.0  # large gaps
    rule.previous_distance = 0.9 * tiny
    assert rule.update(999.0, 0.1 * tiny) == 1000.0  # capped at 100 kappa_min
    assert rule.doublings == 2


def test_a_block_on_a_floor_with_adaptive_stiffness_rests_with_its_weight():
    mesh = ts.box((0, 0, 0), (1, 1, 0.5), (3, 3, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=100.0, integrator="backward_euler", time_step=0.05)
    sim.add_gravity([0.0, 0.0, -9.81])
    sim.add_obstacle("floor", plane((0.5, 0.5, -0.004), (0, 0, 1), 4.0))
    sim.set_contact(dhat=0.01)  # adaptive is the default
    contact = sim.system.contact
    assert contact.adaptive is not None and contact.kappa == pytest.approx(1e4)
    records = []
    for _ in range(40):
        records.append(sim.step())
        assert not contact.intersecting(sim.state.x, sim.time)
    assert contact.adaptive.initialized  # contact appeared, and kappa was set from it
    kappas = [r.extra["contact"]["stiffness_Pa"] for r in records]
    assert all(1e4 <= k <= 1e6 for k in kappas)
    force = np.asarray(records[-1].extra["forces"]["floor"])
    assert force[2] == pytest.approx(100.0 * 0.5 * 9.81, rel=0.02)
    assert sim.describe()["contact"]["adaptive_stiffness"] is True


def test_a_number_fixes_the_stiffness_and_adaptive_can_be_named():
    sim = ts.Simulation(
        ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1)),
        ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3),
    )
    sim.set_contact(stiffness=3e4)
    assert sim.system.contact.adaptive is None and sim.system.contact.kappa == 3e4
    sim.set_contact(stiffness="adaptive")
    assert sim.system.contact.adaptive is not None


def test_a_stiffness_word_other_than_adaptive_is_one_clear_error():
    sim = ts.Simulation(
        ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1)),
        ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3),
    )
    with pytest.raises(ts.InputError, match='number \\(Pa\\) or "adaptive"'):
        sim.set_contact(stiffness="stiff")
