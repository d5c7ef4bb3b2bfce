"""Resuming a run (io/checkpoints/checkpoint.py): a run stopped (killed, or finished and continued
with more steps) and resumed gives exactly (np.array_equal) the positions, velocities, forces and
output files of a run that never stopped, with the direct solvers' kept factor restored from its
matrix; scene mismatches and damaged checkpoints are one error line each.

Contact runs are compared with ipctk on one thread: its parallel sums differ in the last bits
between any two runs on several threads, resumed or not."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
import tomllib
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

from tissuesim.cli import example_path
from tissuesim.errors import InputError
from tissuesim.scene.loader import build_scene

from .conftest import SCENE

SCENE_2D = (
    SCENE.replace("divisions = [4, 4]", "divisions = [6, 6]").replace("steps = 3", "steps = 10")
    + "\n[gravity]\nacceleration = [0.0, -9.81]\n"
)
SOLVERS = ("auto", "splu")  # auto: PARDISO where pypardiso is installed (CI: SuperLU)


@pytest.fixture
def one_thread():
    import ipctk

    before = ipctk.get_num_threads()
    ipctk.set_num_threads(1)
    yield
    ipctk.set_num_threads(before)


def _sim(text: str, linear_solver: str = "auto"):
    data = tomllib.loads(text)
    data.setdefault("newton", {})["linear_solver"] = linear_solver
    return build_scene(data).simulation


def _forces(sim) -> list:
    return [r.extra["forces"] for r in sim.history]


def _assert_same(a, b) -> None:
    assert np.array_equal(a.state.x, b.state.x)
    assert np.array_equal(a.state.v, b.state.v)
    assert a.time == b.time
    assert _forces(a) == _forces(b)
    assert [r.residual_norms for r in a.history] == [r.residual_norms for r in b.history]


def _frames(out, name: str = "body") -> list:
    root = ET.parse(out / f"{name}.pvd").getroot()
    return [(d.get("timestep"), d.get("file")) for d in root.iter("DataSet")]


def _assert_same_output(a, b, names=("body",)) -> None:
    for name in names:
        assert _frames(a, name) == _frames(b, name)
        for _, file in _frames(a, name):
            ma, mb = meshio.read(a / file), meshio.read(b / file)
            assert np.array_equal(ma.points, mb.points)
            for key, value in ma.point_data.items():
                assert np.array_equal(value, mb.point_data[key]), (file, key)
    assert (a / "forces.csv").read_text() == (b / "forces.csv").read_text()
    sa, sb = (json.loads((d / "summary.json").read_text()) for d in (a, b))
    assert sa["status"] == sb["status"] == "completed"
    assert sa["forces"] == sb["forces"]
    assert [s["residual_norms"] for s in sa["steps"]] == [s["residual_norms"] for s in sb["steps"]]


@pytest.mark.parametrize("linear_solver", SOLVERS)
def test_save_load_continues_bit_identical_2d(tmp_path, linear_solver):
    whole = _sim(SCENE_2D, linear_solver)
    whole.run(10, None, progress=False)
    first = _sim(SCENE_2D, linear_solver)
    first.run(4, None, progress=False)
    first.save(tmp_path / "state.npz")
    resumed = _sim(SCENE_2D, linear_solver).load(tmp_path / "state.npz")
    assert np.array_equal(resumed.state.x, first.state.x) and len(resumed.history) == 4
    resumed.run(6, None, progress=False)
    assert not np.array_equal(resumed.state.x, first.state.x)  # it moved on
    _assert_same(whole, resumed)
    assert "factorisation reused" in whole.solver_reason or linear_solver == "cg"


def test_a_fresh_factor_would_not_be_bit_identical(tmp_path, monkeypatch):
    """The kept factor matters: restored from a fresh factorisation, the iterates differ."""
    import tissuesim.io.checkpoints.checkpoint as checkpoint

    whole = _sim(SCENE_2D, "splu")
    whole.run(10, None, progress=False)
    first = _sim(SCENE_2D, "splu")
    first.run(4, None, progress=False)
    first.save(tmp_path / "state.npz")
    monkeypatch.setattr(checkpoint, "_restore_solver", lambda *args, **kw: None)
    resumed = _sim(SCENE_2D, "splu").load(tmp_path / "state.npz")
    resumed.run(6, None, progress=False)
    assert not np.array_equal(whole.state.x, resumed.state.x)
    assert np.allclose(whole.state.x, resumed.state.x, rtol=0, atol=1e-9)


@pytest.mark.parametrize("linear_solver", ("auto", "amg"))
def test_save_load_continues_bit_identical_3d(tmp_path, linear_solver):
    text = example_path("beam_3d_gravity").read_text().replace("[20, 4, 4]", "[8, 2, 2]")
    assert "[8, 2, 2]" in text
    whole = _sim(text, linear_solver)
    whole.run(8, None, progress=False)
    first = _sim(text, linear_solver)
    first.run(3, None, progress=False)
    first.save(tmp_path / "beam.npz")
    resumed = _sim(text, linear_solver).load(tmp_path / "beam.npz")
    resumed.run(5, None, progress=False)
    _assert_same(whole, resumed)


@pytest.mark.parametrize("linear_solver", SOLVERS)
def test_cli_resume_of_a_contact_run_with_a_moving_probe_and_friction(
    tmp_path, cli, scene, one_thread, linear_solver
):
    text = example_path("palpation").read_text().replace("divisions = 12", "divisions = 6")
    run = '[run]\nsteps = 26\nfield = "von_mises"'
    assert run in text
    text = text.replace(run, "[run]\nsteps = 8\nrender = false")
    text += f'\n[newton]\nlinear_solver = "{linear_solver}"\n'
    path = scene(text)
    whole, part = tmp_path / "whole", tmp_path / "part"
    assert cli("run", path, "--out", whole, "--quiet").code == 0
    assert cli("run", path, "--out", part, "--quiet", "--steps", "5").code == 0
    result = cli("run", path, "--out", part, "--quiet", "--resume")
    assert result.code == 0, result.err
    assert json.loads(result.out)["steps"] == 8
    _assert_same_output(whole, part, names=("body", "probe"))
    summary = json.loads((part / "summary.json").read_text())
    assert summary["resumed_at_step"] == 5
    assert summary["steps"][-1]["active_pairs"] > 0  # the probe is in contact
    assert any(f["probe"][0] != 0.0 for f in summary["forces"])  # friction along x


def test_cli_resume_of_a_tissue_cut_mid_run(tmp_path, cli, scene):
    """A run whose connective tissue a blade is cutting when it stops goes on as the run that
    never stopped: the bodies' and the tissue points' series (cut-away points keep the values
    of the last frame written), the blade's swept surface, forces and residuals."""
    from tests.cli.test_cli_coupled import SMALL

    text = SMALL.replace('"-0.2 + 5.6 * (t - 0.25)"', '"-0.2 + 2.8 * (t - 0.25)"')
    text = text.replace("end = 0.5", "end = 0.75").replace("steps = 3", "steps = 4")
    path = scene(text + "render = false\n")
    whole, part = tmp_path / "whole", tmp_path / "part"
    assert cli("run", path, "--out", whole, "--quiet").code == 0
    assert cli("run", path, "--out", part, "--quiet", "--steps", "2").code == 0
    summary = json.loads((part / "summary.json").read_text())
    events = [e for step in summary["steps"] for e in step["extra"]["events"]]
    cut = [e for e in events if e["kind"] == "cut"]
    assert sum(e.get("severed_pairs", 0) for e in cut) > 0  # the blade was cutting when it stopped
    assert len(_frames(part, "cut")) == 1
    result = cli("run", path, "--out", part, "--quiet", "--resume")
    assert result.code == 0, result.err
    _assert_same_output(whole, part, names=("lower", "upper", "tissue_points", "cut"))


def test_kill_mid_run_then_resume(tmp_path, cli, scene):
    path = scene(SCENE_2D.replace("steps = 10", "steps = 60").replace("[6, 6]", "[12, 12]"))
    whole, killed = tmp_path / "whole", tmp_path / "killed"
    assert cli("run", path, "--out", whole, "--quiet").code == 0
    proc = subprocess.Popen(
        [sys.executable, "-m", "tissuesim", "run", str(path), "--out", str(killed), "--quiet"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    history = killed / "checkpoint_history.jsonl"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if history.is_file() and history.read_text().count("\n") >= 20:
            break
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run ended before the kill"
    summary = json.loads((killed / "summary.json").read_text())
    assert summary["status"] == "running"
    assert 20 <= len(_frames(killed)) < 61
    leftover = killed / ".body_0007.tmp-0123abcd.vtu"  # what a kill in mid-write leaves
    leftover.write_text("")
    result = cli("run", path, "--out", killed, "--quiet", "--resume")
    assert result.code == 0, result.err
    assert not leftover.exists()
    _assert_same_output(whole, killed)
    assert len(list(killed.glob("body_*.vtu"))) == 61


def test_a_finished_run_continues_with_more_steps_and_is_complete_with_as_many(
    tmp_path, cli, scene
):
    path = scene(SCENE_2D)
    whole, part = tmp_path / "whole", tmp_path / "part"
    assert cli("run", path, "--out", whole, "--quiet", "--steps", "10").code == 0
    assert cli("run", path, "--out", part, "--quiet", "--steps", "7").code == 0
    assert cli("run", path, "--out", part, "--quiet", "--resume", "--steps", "10").code == 0
    _assert_same_output(whole, part)
    before = {p.name: p.stat().st_mtime_ns for p in part.iterdir()}
    result = cli("run", path, "--out", part, "--quiet", "--resume", "--steps", "10")
    assert result.code == 0
    assert "already complete (10 steps)" in result.err
    assert {p.name: p.stat().st_mtime_ns for p in part.iterdir()} == before  # nothing written
    fewer = cli("run", path, "--out", part, "--quiet", "--resume", "--steps", "4")
    assert fewer.code == 2
    assert "holds a run of 10 steps, more than the 4 asked for" in fewer.error_line


def test_resume_with_another_scene_is_one_error_line_and_touches_nothing(tmp_path, cli, scene):
    out = tmp_path / "out"
    assert cli("run", scene(SCENE_2D), "--out", out, "--quiet", "--steps", "3").code == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    other = scene(SCENE_2D.replace("youngs_modulus = 1000.0", "youngs_modulus = 2000.0"))
    result = cli("run", other, "--out", out, "--quiet", "--resume", "--steps", "6")
    assert result.code == 2
    line = result.error_line
    assert "checkpoint.npz was written for a different scene" in line
    assert "body 'body': checkpoint" in line and "shear_modulus" in line  # the material
    assert "run without --resume" in line
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # a change the simulation does not show (the prescribed motion) is caught by the file hash
    moved = scene(SCENE_2D.replace('"0.1 * t"', '"0.2 * t"'))
    line = cli("run", moved, "--out", out, "--quiet", "--resume", "--steps", "6").error_line
    assert "scene file (all but [run]): checkpoint" in line


def test_missing_or_damaged_checkpoint_is_one_error_line(tmp_path, cli, scene):
    path = scene(SCENE_2D)
    out = tmp_path / "out"
    line = cli("run", path, "--out", out, "--quiet", "--resume").error_line
    assert "no checkpoint" in line and "checkpoint.npz" in line and "without --resume" in line
    assert cli("run", path, "--out", out, "--quiet", "--steps", "3").code == 0
    history = (out / "checkpoint_history.jsonl").read_text()
    (out / "checkpoint_history.jsonl").write_text(history.splitlines(keepends=True)[0])
    line = cli("run", path, "--out", out, "--quiet", "--resume", "--steps", "5").error_line
    assert "does not hold the 3 steps" in line
    (out / "checkpoint.npz").write_bytes(b"PK\x03\x04 torn")
    result = cli("run", path, "--out", out, "--quiet", "--resume", "--steps", "5")
    assert result.code == 2
    assert "is not a readable tissuesim checkpoint" in result.error_line


def test_load_checks_the_set_up(tmp_path):
    sim = _sim(SCENE_2D)
    sim.run(2, None, progress=False)
    sim.save(tmp_path / "s.npz")
    with pytest.raises(InputError, match="has not stepped yet"):
        sim.load(tmp_path / "s.npz")
    other = _sim(SCENE_2D.replace("time_step = 0.01", "time_step = 0.02"))
    settings = "simulation settings: checkpoint backward_euler, time_step 0.01"
    with pytest.raises(InputError, match=settings):
        other.load(tmp_path / "s.npz")
