"""A sphere probe's indentation depth (contact/readout/indentation.py): 0 until it touches the
bodies as they are (sagged, moved), then its travel since the touch, past its radius too; reset
when it lets go; none for capsules and planes."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.obstacles import Obstacle, capsule, plane, sphere
from tissuesim.contact.readout.indentation import IndentationTracker

R = 0.005


def _probe(path):
    """A sphere of radius R whose centre starts at (0, 0, R + 1 mm) and moves down by path(t)."""
    return Obstacle("probe", sphere((0, 0, R + 1e-3), R, 2), translation=lambda t: (0, 0, -path(t)))


def test_the_depth_is_the_travel_since_touching_the_surface_as_it_is():
    flat = np.array([[x, y, 0.0] for x in (-0.01, 0.0, 0.01) for y in (-0.01, 0.0, 0.01)])
    sagged = flat - [0.0, 0.0, 0.002]  # the body sagged 2 mm before the probe came
    probe = _probe(lambda t: 1e-3 * t)  # 1 mm per unit of time
    tracker = IndentationTracker()
    others = [
        Obstacle("floor", plane((0, 0, -1), (0, 0, 1), 1.0)),
        Obstacle("jaw", capsule((0, -0.01, 0.02), (0, 0.01, 0.02), 0.002)),
    ]
    touching = {"probe": [0.0, 0.0, -0.1], "floor": [0.0, 0.0, 1.0], "jaw": [0.0, 0.0, -1.0]}
    free = {"probe": [0.0, 0.0, 0.0]}
    # t = 2: the probe is 1 mm below the rest surface but 1 mm above the sagged one
    assert tracker.depths([probe, *others], sagged, flat, 2.0, free) == {"probe": 0.0}
    # the probe touches at t = 3 (its barrier force on): from then on its travel since the
    # surface, 1 mm per unit of time, past its radius (5 mm) too
    depths = [tracker.depths([probe], sagged, flat, t, touching)["probe"] for t in (4, 5, 11)]
    np.testing.assert_allclose(depths, [1e-3, 2e-3, 8e-3], rtol=1e-12)
    assert "floor" not in tracker.depths(others, sagged, flat, 11, touching)
    # it lets go, and touches again further down: a new touch point
    assert tracker.depths([probe], sagged - [0, 0, 0.02], flat, 12, free)["probe"] == 0.0
    deeper = sagged - [0, 0, 0.0105]  # 1.5 mm below the probe's lowest point at t = 12
    assert tracker.depths([probe], deeper, flat, 12, free)["probe"] == 0.0
    assert tracker.depths([probe], deeper, flat, 14, touching)["probe"] == pytest.approx(5e-4)


def test_a_probe_touching_from_the_start_measures_from_the_rest_configuration():
    flat = np.array([[0.0, 0.0, 0.0], [0.01, 0.0, 0.0]])
    probe = _probe(lambda t: 1e-3 * t)
    depth = IndentationTracker().depths([probe], flat, flat, 3.0, {"probe": [0, 0, -1.0]})
    assert depth["probe"] == pytest.approx(2e-3, rel=1e-12)


def test_a_probe_above_a_sagging_block_reads_zero_until_it_touches_then_its_travel():
    """The issue's case: a soft block sags 2 mm under gravity; the probe, driven down 1 mm per
    step from 0.5 mm above the rest surface, reads 0 while it is below the rest surface but
    above the sagged one, then grows by its travel each step."""
    pytest.importorskip("ipctk")
    mesh = ts.box((-0.01, -0.01, -0.02), (0.01, 0.01, 0.0), (4, 4, 4))
    material = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="quasistatic", time_step=1.0)
    sim.fix("body", ts.select.vertices_on_plane(mesh, axis=2, value=-0.02), name="base")
    sim.add_gravity([0.0, 0.0, -9.81])
    sim.set_contact(dhat=5e-5)
    probe = sphere((0.0, 0.0, R + 5e-4), R, refinement=3)
    sim.add_obstacle("probe", probe, translation=lambda t: (0.0, 0.0, -1e-3 * t))
    records = [sim.step() for _ in range(5)]
    assert all(r.converged for r in records)
    top = sim.positions[np.argmin(np.linalg.norm(mesh.points - [0, 0, 0], axis=1))][2]
    depths = [r.extra["contact"]["indentation_depth"]["probe"] for r in records]
    forces = [-r.extra["forces"]["probe"][2] for r in records]
    assert depths[0] == 0.0 and forces[0] == 0.0  # below the rest surface, above the sagged one
    touched = [k for k, f in enumerate(forces) if f > 0]
    assert touched and touched == list(range(touched[0], 5))
    assert all(d == 0.0 for d in depths[: touched[0]])
    # while touching, the depth grows by the probe's travel (1 mm per step) along the touch
    # direction, to the nearest sagged vertex (tilted by its few-um lateral sag)
    np.testing.assert_allclose(np.diff(depths[touched[0] :]), 1e-3, rtol=1e-5)
    assert 0.0 < depths[touched[0]] <= 1e-3
    assert top < -1e-3  # the top sagged and is pressed: the old rest-based depth was wrong
