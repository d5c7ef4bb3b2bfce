"""Newton's start when the prescribed motion alone inverts elements (solve/tangent_start.py):
a support pushed farther in one step than the thin layer of elements next to it is thick."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import ConvergenceError
from tissuesim.mesh import select

PUSH = 0.03  # the top face's travel; the top layer is 0.01 thick


def down(depth: float):
    """A prescribed motion: down by depth x t."""
    return lambda X, t: np.column_stack([0 * X[:, 0], 0 * X[:, 0], np.full(len(X), -depth * t)])


def thin_topped_column(steps: int, halvings: int = 0) -> ts.Simulation:
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (1, 1, 3))
    z = mesh.points[:, 2].copy()
    # layers at z = 0, 0.5, 0.99, 1: the top one 0.01 thick
    mesh.points[:, 2] = np.interp(z, [0.0, 1 / 3, 2 / 3, 1.0], [0.0, 0.5, 0.99, 1.0])
    sim = ts.Simulation(
        mesh,
        ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
        integrator="quasistatic",
        time_step=1.0 / steps,
        max_step_halvings=halvings,
    )
    sim.fix(select.vertices_on_plane(mesh, 2, 0.0))
    top = select.vertices_on_plane(mesh, 2, 1.0)
    sim.add_dirichlet(top, down(PUSH))
    return sim


def test_a_push_past_a_thin_layer_starts_from_the_linear_response():
    sim = thin_topped_column(steps=1)
    # the naive start (top face moved, the rest where it was) puts the top face below the
    # layer under it: an inverted element, infinite energy
    assert 1.0 - PUSH < 0.99
    sim.step()  # no halving allowed: the first try must start and converge
    one = sim.positions.copy()
    assert np.all(sim.cell_fields()["J"] > 0)
    # the same equilibrium as ten small steps (quasistatic hyperelasticity: one answer)
    gradual = thin_topped_column(steps=10)
    for _ in range(10):
        gradual.step()
    assert np.max(np.abs(one - gradual.positions)) < 1e-9
    assert np.min(one[:, 2][one[:, 2] > 0.5]) > 0.9  # the layer kept its order


def test_a_motion_that_inverts_whatever_the_start_still_fails_clearly():
    """Prescribed motion that crushes the column through itself: no start helps."""
    sim = thin_topped_column(steps=1)
    sim.add_dirichlet(select.vertices_on_plane(sim.mesh, 2, 0.99), down(-0.02))
    with pytest.raises(ConvergenceError, match="infinite energy"):
        sim.step()
