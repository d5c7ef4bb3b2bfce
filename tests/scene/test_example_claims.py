"""Issue 41: an example's header says what its run shows. The palpation header said the probe
"presses 6 mm into" the organ, its nominal travel below the organ at rest, while the organ,
sagging under its weight, took most of it: the indentation peaks near 1 mm."""

from __future__ import annotations

import re

import pytest

from tissuesim.scene.examples import describe_example, example_path
from tissuesim.scene.loader import build_scene

pytest.importorskip("ipctk")


def test_the_palpation_header_states_the_depth_a_run_shows():
    import tomllib

    shows = describe_example("palpation")["shows"]
    claimed = float(re.search(r"presses about (\d+(?:\.\d+)?) mm into", shows).group(1)) * 1e-3
    data = tomllib.loads(example_path("palpation").read_text())
    data["mesh"]["divisions"] = 6  # coarser (1.3k tetrahedra): the sag and depth barely change
    sim = build_scene(data, source="palpation (coarse)").simulation
    depths, touched = [], None
    for _ in range(11):  # the descent: 0.35 s at 30 steps per second
        record = sim.step()
        depth = record.extra["contact"]["indentation_depth"]["probe"]
        depths.append(depth)
        if depth > 0 and touched is None:
            touched = record.time
    assert 0.5 * claimed < max(depths) < 1.5 * claimed  # 0.95 mm on the shipped mesh
    assert 0.2 < touched < 0.34  # "meets it at about 0.3 s": the organ sagged meanwhile
