"""The shipped examples' comments name only files their runs write (a comment once sent users
to a block.pvd that the scene, whose body is "body", never wrote)."""

from __future__ import annotations

import re

import pytest

from tissuesim.io.series.bodies import series_names
from tissuesim.scene.examples import example_path, list_examples
from tissuesim.scene.loader import load_scene

#: what every run with output writes besides the bodies' and obstacles' series
RUN_FILES = {"summary.json", "forces.csv", "forces.png", "final.png", "run.gif", "manifest.json"}
RUN_FILES |= {"checkpoint.npz", "cut.pvd"}


@pytest.mark.parametrize("name", list_examples())
def test_files_named_in_an_example_comment_are_written_by_it(name):
    text = example_path(name).read_text()
    comments = "\n".join(line for line in text.splitlines() if line.lstrip().startswith("#"))
    named = set(re.findall(r"\b[\w-]+\.(?:pvd|csv|png|gif|json|npz)\b", comments))
    if not named:
        return
    sim = load_scene(example_path(name)).simulation
    written = set(RUN_FILES)
    for body in sim.bodies.values():
        written |= {f"{s}.pvd" for s in series_names(body.name, body.kind)}
    written |= {f"{o.name}.pvd" for o in sim.obstacles}
    assert named <= written, f"{name}: comments name {sorted(named - written)}"
