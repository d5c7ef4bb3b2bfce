"""[contact] and [[obstacles]] in scene files: a probe pressed into a clamped block from the
command line, its force balancing the support's, its surface written as a series; bad tables
named in one error line."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

from tissuesim.cli import main

pytest.importorskip("ipctk")

SCENE = """
[mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [1.0, 1.0, 0.5]
divisions = [4, 4, 2]
[material]
model = "neo_hookean"
youngs_modulus = 1e4
poisson_ratio = 0.3
[simulation]
integrator = "quasistatic"
time_step = 0.1
[[dirichlet]]
vertices = { tagged = "zmin" }
[contact]
dhat = 0.005
[[obstacles]]
name = "probe"
sphere = { center = [0.5, 0.5, 0.703], radius = 0.2, refinement = 2 }
translation = ["0", "0", "-0.02 * t"]
[run]
steps = 4
render = false
"""


def test_a_probe_scene_runs_and_its_force_balances_the_support(tmp_path, capsys):
    scene = tmp_path / "probe.toml"
    scene.write_text(SCENE)
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    last = summary["forces"][-1]
    probe, support = np.array(last["probe"]), np.array(last["body.dirichlet_0"])
    assert probe[2] < 0
    np.testing.assert_allclose(probe + support, 0.0, atol=1e-5 * abs(probe[2]))  # Newton tol
    contact = summary["steps"][-1]["extra"]["contact"]
    assert 0 < contact["min_distance"] < 0.005 and contact["active_pairs"] > 0
    assert summary["simulation"]["contact"]["obstacles"] == ["probe"]
    frame = meshio.read(out / "probe_00004.vtu")
    np.testing.assert_allclose(frame.point_data["displacement"][:, 2], -0.02 * 0.4, rtol=1e-9)
    assert "probe" in json.loads((out / "manifest.json").read_text())["series"]


@pytest.mark.parametrize(
    ("old", "new", "words"),
    [
        ("dhat = 0.005", "dhat = -1", "[contact]: contact dhat must be > 0"),
        (
            "dhat = 0.005",
            "dhat = 0.005\nfrictoin = 0.3",
            "[contact]: unknown key 'frictoin'; did you mean 'friction'",
        ),
        ('name = "probe"\n', "", "obstacles[1]: name must be a non-empty string"),
        ("sphere = {", "torus = {", "obstacles[1]: unknown key 'torus'"),
        ("radius = 0.2", "radius = 0.0", "obstacles[1] sphere: sphere: radius must be > 0"),
        ('"-0.02 * t"', '"-0.02 * z"', "translation[2]: the obstacle's translation depends on t"),
    ],
)
def test_bad_contact_tables_are_one_error_line(tmp_path, capsys, old, new, words):
    scene = tmp_path / "probe.toml"
    assert old in SCENE
    scene.write_text(SCENE.replace(old, new))
    assert main(["run", str(scene), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("tissuesim: error:") == 1 and words in err, err


@pytest.mark.parametrize(
    "shape, kind",
    [
        (
            "capsule = { start = [0.2, 0.5, 0.603], end = [0.8, 0.5, 0.603], radius = 0.1 }",
            "capsule",
        ),
        ("cylinder = { start = [0.5, 0.5, 0.52], end = [0.5, 0.5, 0.8], radius = 0.1 }", ""),
    ],
)
def test_capsule_and_cylinder_obstacles_in_a_scene(tmp_path, shape, kind):
    from tissuesim.scene.loader import load_scene

    scene = tmp_path / "jaw.toml"
    scene.write_text(
        SCENE.replace(
            "sphere = { center = [0.5, 0.5, 0.703], radius = 0.2, refinement = 2 }", shape
        )
    )
    sim = load_scene(scene).simulation
    (obstacle,) = sim.obstacles
    assert getattr(obstacle.surface, "kind", "") == kind
    record = sim.step()
    assert record.converged and not sim.system.contact.intersecting(sim.state.x, sim.time)
