"""A study of a Python function: ``bar`` builds the bar of conftest.py with the Python API
(a module's function, so that a worker process imports it by name)."""

from __future__ import annotations

import numpy as np


def bar(youngs_modulus: float, pull: float):
    """The bar clamped at x = 0, its end x = 1 pulled ``pull * t`` (m) along x."""
    import tissuesim as ts

    sim = ts.Simulation(integrator="quasistatic", time_step=0.5)
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.25, 0.25), (4, 1, 1))
    material = ts.make_material("neo_hookean", youngs_modulus=youngs_modulus, poisson_ratio=0.3)
    sim.add_body("bar", mesh, material)
    x = mesh.points[:, 0]
    sim.fix(np.flatnonzero(x < 1e-9), name="clamp")
    end = np.flatnonzero(x > 1 - 1e-9)
    sim.add_dirichlet(end, lambda X, t: np.outer(np.ones(len(X)), [pull * t, 0, 0]), name="pull")
    return sim
