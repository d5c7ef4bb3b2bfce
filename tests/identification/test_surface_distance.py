"""A point cloud of the deformed surface as the measurement (identification/observations.py
SurfaceDistance): its derivative against central differences of whole runs, and a cantilever's
stiffness recovered from a scan of its sagged surface."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.mesh import select
from tissuesim.mesh.queries.boundary import boundary_facets

STEPS = 2


def sagging(p):
    mesh = ts.box((0, 0, 0), (1.0, 0.2, 0.2), (5, 1, 1))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3),
                        integrator="quasistatic", time_step=0.5)  # fmt: skip
    sim.fix(select.vertices_on_plane(mesh, 0, 0.0), name="wall")
    sim.add_body_force(lambda X, t: np.tile([0.0, 0.0, -2e3 * t], (len(X), 1)))
    return sim


def scan(E: float) -> np.ndarray:
    """Points on the sagged cantilever's surface: its boundary facets' centroids past x = 0.5,
    pushed 1 mm off the surface along the facet normal (a scan never lies on the mesh)."""
    sim = sagging({"E": E})
    for _ in range(STEPS):
        sim.step()
    mesh = sim.bodies["body"].mesh
    x = sim.body_positions()
    f = boundary_facets(mesh.cells)
    c = x[f].mean(axis=1)
    n = np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]])
    n /= np.linalg.norm(n, axis=1)[:, None]
    keep = mesh.points[f].mean(axis=1)[:, 0] > 0.5
    return (c + 1e-3 * n)[keep]


def test_the_distance_derivative_matches_central_differences():
    points = scan(4e4)
    obs = [ts.SurfaceDistance(points)]
    r = ts.sensitivities(sagging, {"E": 5e4}, obs, STEPS)

    def distances(E):
        sim = sagging({"E": E})
        for _ in range(STEPS):
            sim.step()
        deformed = dataclasses.replace(sim.bodies["body"].mesh, points=sim.body_positions())
        from tissuesim.mesh.queries.locate import distance_to_boundary

        return distance_to_boundary(deformed, points)

    np.testing.assert_allclose(r.values[-1], distances(5e4), rtol=1e-10, atol=1e-12)
    d = 5e4 * 1e-5
    fd = (distances(5e4 + d) - distances(5e4 - d)) / (2 * d)
    assert np.abs(fd).max() > 0
    assert np.abs(r.jacobian[-1][:, 0] - fd).max() <= 1e-5 * np.abs(fd).max()


def test_a_scan_of_the_sagged_surface_gives_the_stiffness():
    points = scan(4e4)
    data = np.full((STEPS, len(points)), np.nan)
    data[-1] = 1e-3  # every scanned point sits 1 mm off the true surface
    fit = ts.identify(sagging, {"E": 1e5}, [ts.SurfaceDistance(points)], data, STEPS,
                      bounds={"E": (1e3, 1e7)}, scale=[0.01])  # fmt: skip
    assert fit.parameters["E"] == pytest.approx(4e4, rel=1e-3)
