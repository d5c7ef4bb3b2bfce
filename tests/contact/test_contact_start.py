"""Issue 41: contact's set-up is checked before the first step. A dhat the bodies' edges
cannot hold (0.5 m on a 0.1 m box: 0 steps in 300 s) is one error line naming dhat, the body's
size and a value to use; a probe that starts inside the organ (reported after six halvings as
"did not converge ... try a smaller time_step") is named at t = 0, from the API and a scene
(a FEBio model's contact is FEBio's penalty, which takes overlapping surfaces)."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.cli import main
from tissuesim.errors import InputError

pytest.importorskip("ipctk")

MODELS = __import__("pathlib").Path(__file__).resolve().parents[1] / "febio" / "models"

SCENE = """
[mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.1, 0.05, 0.05]
divisions = [4, 2, 2]
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
dhat = 1e-4
[[obstacles]]
name = "probe"
sphere = { center = [0.05, 0.025, 0.0602], radius = 0.01, refinement = 2 }
translation = ["0", "0", "-0.001 * t"]
[run]
steps = 2
render = false
"""


def _liver(dhat=None) -> ts.Simulation:
    sim = ts.Simulation(integrator="quasistatic", time_step=0.1)
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim.add_body("liver", ts.box((0, 0, 0), (0.1, 0.05, 0.05), (4, 2, 2)), material)
    sim.fix(np.flatnonzero(sim.body("liver").mesh.points[:, 2] < 1e-9))
    if dhat is not None:
        sim.set_contact(dhat=dhat)
    return sim


def _run(tmp_path, capsys, text: str) -> tuple[int, str]:
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    code = main(["run", str(scene), "--out", str(tmp_path / "out"), "--quiet"])
    return code, capsys.readouterr().err


def test_a_dhat_larger_than_the_edges_is_refused_before_the_first_step():
    sim = _liver(dhat=0.5)
    with pytest.raises(InputError) as info:
        sim.step()
    said = str(info.value)
    assert said.startswith("contact dhat = 0.5 m is not below the edges of body 'liver'")
    assert "0.1 x 0.05 x 0.05 m" in said and "use dhat = 0.0001 m or less" in said
    assert not sim.history  # nothing was stepped


def test_a_dhat_below_the_edges_runs():
    sim = _liver(dhat=1e-3)
    sim.step()
    assert len(sim.history) == 1


def test_a_scene_dhat_too_large_is_one_line(tmp_path, capsys):
    code, err = _run(tmp_path, capsys, SCENE.replace("dhat = 1e-4", "dhat = 0.5"))
    assert code == 2
    (line,) = err.strip().splitlines()
    assert "contact dhat = 0.5 m is not below the edges of body 'body'" in line
    assert "Traceback" not in err


def test_a_probe_inside_the_organ_is_named_at_the_start():
    sim = _liver()
    # the probe's centre 5 mm above the top face, radius 10 mm: it starts 5 mm inside
    probe = ts.sphere((0.05, 0.025, 0.055), 0.01)
    sim.add_obstacle("probe", probe, translation=lambda t: [0.0, 0.0, -0.001 * t])
    with pytest.raises(InputError, match=r"^obstacle 'probe' intersects body 'liver' at t = 0 s"):
        sim.step()
    assert not sim.history


def test_a_scene_probe_inside_is_one_line_and_outside_runs(tmp_path, capsys):
    code, err = _run(tmp_path, capsys, SCENE.replace("0.0602", "0.055"))
    assert code == 2
    (line,) = err.strip().splitlines()
    assert "obstacle 'probe' intersects body 'body' at t = 0 s" in line
    assert "did not converge" not in err and "time_step" not in err
    code, err = _run(tmp_path, capsys, SCENE)  # 0.2 mm above the face: it runs
    assert code == 0, err


def test_two_bodies_that_start_crossed_are_named(tmp_path):
    sim = _liver()
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim.add_body("fat", ts.box((0.02, 0.01, 0.04), (0.08, 0.04, 0.07), (2, 1, 1)), material)
    sim.fix(np.flatnonzero(sim.body("fat").mesh.points[:, 2] > 0.07 - 1e-9), body="fat")
    sim.set_contact(dhat=1e-4)
    with pytest.raises(InputError, match=r"^body 'fat' intersects body 'liver' at t = 0 s"):
        sim.step()


def test_a_febio_model_that_starts_overlapping_runs_as_febio_does(tmp_path, capsys):
    """FEBio's sliding contact is a penalty: surfaces that start overlapping are pushed
    apart, not refused (the barrier's crossing check is for barrier contact only)."""
    text = (MODELS / "contact_stack.feb").read_text()
    # a corner of 'upper''s contact face (the pair's surfaces are single faces) 0.02 below
    # 'lower''s: the two faces cross
    old = '<node id="9">0,0,1.02</node>'
    assert old in text
    text = text.replace(old, '<node id="9">0,0,0.98</node>')
    feb = tmp_path / "crossed.feb"
    feb.write_text(text)
    code = main(["run", str(feb), "--out", str(tmp_path / "out"), "--quiet"])
    assert code == 0, capsys.readouterr().err
