"""Shared helpers for the core tests: small meshes and finite-difference checks."""

from __future__ import annotations

import pytest

from tissuesim.mesh import box, rectangle


@pytest.fixture(params=[2, 3], ids=["2d", "3d"])
def small_mesh(request):
    if request.param == 2:
        return rectangle(lower=(0, 0), upper=(1, 0.7), divisions=(3, 2))
    return box(lower=(0, 0, 0), upper=(1, 0.6, 0.5), divisions=(2, 2, 1))


@pytest.fixture
def sim():
    """A quasistatic simulation of one small box, "organ" (API tests of tests/core)."""
    import tissuesim as ts

    sim = ts.Simulation(integrator="quasistatic", time_step=0.1)
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim.add_body("organ", ts.box((0, 0, 0), (0.1, 0.05, 0.05), (2, 1, 1)), material)
    return sim
