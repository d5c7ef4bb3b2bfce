"""The retraction-and-cut scene with contact (organs_rest_after_cut), on coarser meshes and
steps so that it runs in a test: through the whole cut and the grasper's release no step
intersects, the freed gallbladder comes to rest on the liver (not in it, not above it), and the
liver's support then carries the weight of both organs and the tissue."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.cli import example_path
from tissuesim.scene.loader import load_scene

pytest.importorskip("ipctk")

G = 9.81


def coarse_scene(tmp_path):
    text = example_path("organs_rest_after_cut").read_text()
    for old, new in (
        ("divisions = 8", "divisions = 5"),
        ("spacing = 0.002", "spacing = 0.003"),
        ("frames = 30", "frames = 12"),
        ("time_step = 0.025", "time_step = 0.05"),
    ):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "organs_coarse.toml"
    path.write_text(text)
    return load_scene(path).simulation


def test_the_freed_gallbladder_rests_on_the_liver_which_carries_everything(tmp_path):
    sim = coarse_scene(tmp_path)
    records, heights = [], []
    while sim.time < 4.0 - 1e-9:
        records.append(sim.step())
        contact = sim.system.contact
        assert not contact.intersecting(sim.state.x, sim.time), f"intersecting at {sim.time} s"
        heights.append(sim.body_positions("gallbladder")[:, 2].mean())
    assert all(r.converged for r in records)
    assert any(e["kind"] == "cut" for r in records for e in r.extra.get("events", []))
    last = records[-1]
    assert "grasper" not in last.extra["forces"]  # released at 2.3 s
    # at rest: the gallbladder has stopped falling, and touches the liver
    _, _, v = sim.body_state("gallbladder")
    assert np.abs(v).max() < 2e-3  # m/s
    assert abs(heights[-1] - heights[-5]) < 1e-4
    assert 0 < last.extra["contact"]["min_distance"] < sim.system.contact.dhat
    assert last.extra["contact"]["active_pairs"] > 0
    # the liver's support carries both organs and the tissue
    mass = sum(float(b.model.mass.lumped.sum()) / 3 for b in sim.bodies.values() if b.kind == "fem")
    mass += float(sim.tissue.model.masses.sum())
    support = np.asarray(last.extra["forces"]["liver.support"])
    assert support[2] == pytest.approx(mass * G, rel=0.02)
    assert np.abs(support[:2]).max() < 0.02 * mass * G
