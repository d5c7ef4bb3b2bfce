"""``run()`` after steps taken by hand writes one consistent window: the series starts at the
state the run starts from and summary.json / forces.csv hold the run's steps only."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np

import tissuesim as ts


def beam() -> ts.Simulation:
    material = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(
        ts.rectangle((0, 0), (1, 0.2), (8, 2)),
        material,
        density=100,
        integrator="backward_euler",
        time_step=0.01,
        gravity=(0, -9.81),
    )
    sim.fix(ts.select.vertices_on_plane(sim.mesh, axis=0, value=0.0), name="wall")
    return sim


def test_run_after_manual_steps_writes_only_its_own_steps(tmp_path):
    sim = beam()
    for _ in range(4):
        sim.step()
    start = sim.time
    records = sim.run(3, tmp_path / "o", progress=False, render=False)
    assert [r.step for r in records] == [5, 6, 7]
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["totals"]["steps"] == 3 and len(summary["steps"]) == 3
    times = [f["time"] for f in summary["forces"]]
    np.testing.assert_allclose(times, start + 0.01 * np.arange(1, 4), atol=1e-12)
    rows = (tmp_path / "o" / "forces.csv").read_text().splitlines()[1:]
    np.testing.assert_allclose([float(r.split(",")[0]) for r in rows], times, atol=1e-12)
    root = ET.parse(tmp_path / "o" / "body.pvd").getroot()
    frame_times = [float(d.get("timestep")) for d in root.iter("DataSet")]
    np.testing.assert_allclose(frame_times, start + 0.01 * np.arange(4), atol=1e-12)
    assert summary["totals"]["end_time"] == sim.time


def test_a_run_from_the_start_is_unchanged(tmp_path):
    sim = beam()
    records = sim.run(3, tmp_path / "o", progress=False, render=False)
    assert [r.step for r in records] == [1, 2, 3]
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["totals"]["steps"] == 3
