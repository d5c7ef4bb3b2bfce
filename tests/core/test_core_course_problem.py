"""The notes' example problem, stretch reading, through the collapse at t = 3 pi / 2 on a
coarse mesh: every step converges, elements come close to (or through) inversion, and the
clamped edges are where the condition puts them."""

from __future__ import annotations

import tomllib

import numpy as np

from tissuesim.cli import example_path
from tissuesim.scene.loader import build_scene


def test_stretch_reading_runs_through_the_collapse():
    data = tomllib.loads(example_path("course_stretch").read_text())
    data["mesh"]["divisions"] = [8, 8]
    data["simulation"]["time_step"] = 2 * np.pi / 100
    sim = build_scene(data).simulation
    records = [sim.step() for _ in range(100)]
    assert all(r.converged for r in records)
    assert abs(sim.time - 2 * np.pi) < 1e-9
    collapse = min(records, key=lambda r: abs(r.time - 1.5 * np.pi))
    assert abs(collapse.time - 1.5 * np.pi) < 1e-9
    assert min(r.min_J for r in records) < 0.5  # strongly compressed
    # at t = 3 pi / 2 both clamped edges sit on X1 = 0: checked on the final state (t = 2 pi)
    # by the condition itself: u = X1 sin(2 pi) = 0
    edges = np.isclose(np.abs(sim.mesh.points[:, 0]), 1.0)
    np.testing.assert_allclose(sim.displacement[edges], 0.0, atol=1e-12)
