"""A tiny one-body scene for the study tests: a bar of 4 x 1 x 1 boxes (20 vertices) clamped at
x = 0 and pulled at x = 1 in two quasistatic steps (about 0.1 s a run), its mesh a file next to
the scene (relative: the runs must read it from the scene's folder, not the working one)."""

from __future__ import annotations

from pathlib import Path

import pytest

SCENE = """
[mesh]
file = "mesh/bar.vtu"

[material]
model = "neo_hookean"
youngs_modulus = 1000.0
poisson_ratio = 0.3

[simulation]
integrator = "quasistatic"
time_step = 0.5

[[dirichlet]]
name = "clamp"
vertices = { on_plane = { axis = 0, value = 0.0 } }

[[dirichlet]]
name = "pull"
vertices = { on_plane = { axis = 0, value = 1.0 } }
displacement = ["0.1 * t", "0", "0"]

[run]
steps = 2
"""


@pytest.fixture(scope="session")
def bar_scene(tmp_path_factory) -> Path:
    import tissuesim as ts
    from tissuesim.mesh.io import write_mesh

    folder = tmp_path_factory.mktemp("bar")
    (folder / "mesh").mkdir()
    write_mesh(ts.box((0, 0, 0), (1.0, 0.25, 0.25), (4, 1, 1)), folder / "mesh" / "bar.vtu")
    path = folder / "bar.toml"
    path.write_text(SCENE, encoding="utf-8")
    return path
