"""Issue 41: ``[[graspers]]`` on a one-body scene was refused ("graspers belong to coupled
scenes with connective tissue"); a grasper is the most basic interaction, and the API allowed
it on any scene. The scene's body may be left out (it is the only one)."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.errors import SceneError
from tissuesim.scene.loader import load_scene

BLOCK = """
[simulation]
integrator = "quasistatic"
time_step = 0.5

[mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.1, 0.05, 0.05]
divisions = [2, 1, 1]

[material]
model = "neo_hookean"
youngs_modulus = 1e4
poisson_ratio = 0.3

[[dirichlet]]
vertices = { on_plane = { axis = 0, value = 0.0 } }
"""

GRASP = """
[[graspers]]
vertices = { on_plane = { axis = 0, value = 0.1 } }
displacement = ["0.002 * t", "0", "0"]
name = "jaw"
"""


def _scene(tmp_path, text):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return load_scene(path)


def test_a_grasper_on_a_one_body_scene_pulls_it(tmp_path):
    sim = _scene(tmp_path, BLOCK + GRASP).simulation
    (jaw,) = sim.graspers
    assert jaw.name == "jaw"
    sim.step()
    sim.step()
    mesh = sim.body("body").mesh
    tip = np.isclose(mesh.points[:, 0], 0.1)
    u = sim.displacement
    np.testing.assert_allclose(u[tip, 0], 0.002 * sim.time, rtol=1e-9)
    f = sim.forces()
    assert f["jaw"][0] > 0 and f["body.dirichlet_0"][0] < 0  # it pulls, the clamp holds back
    np.testing.assert_allclose(np.add(f["jaw"], f["body.dirichlet_0"]), 0.0, atol=1e-8)


def test_a_one_body_grasper_may_name_its_body(tmp_path):
    sim = _scene(tmp_path, BLOCK + GRASP + 'body = "body"\n').simulation
    assert [g.name for g in sim.graspers] == ["jaw"]


def test_a_bad_one_body_grasper_names_its_table(tmp_path):
    with pytest.raises(SceneError) as info:
        _scene(tmp_path, BLOCK + GRASP.replace('name = "jaw"', "stiffnes = 1.0"))
    said = str(info.value)
    assert "scene.toml [[graspers]] #1" in said and "did you mean 'stiffness'" in said
    with pytest.raises(SceneError, match=r"\[\[graspers\]\] #1: unknown body 'liver'"):
        _scene(tmp_path, BLOCK + GRASP + 'body = "liver"\n')
