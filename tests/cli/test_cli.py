"""The command line, in process (``tissuesim.cli.main``) and once through the entry point."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.cli import main
from tissuesim.mesh import write_mesh


def pvd_files(directory):
    root = ET.parse(directory / "body.pvd").getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    rows = root.find("Collection").findall("DataSet")
    return [(float(r.get("timestep")), directory / r.get("file")) for r in rows]


def test_run_course_stretch_writes_the_full_output(tmp_path, capsys):
    out = tmp_path / "stretch"
    assert main(["run", "course_stretch", "--steps", "4", "--out", str(out), "--quiet"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["steps"] == 4 and report["output"] == str(out)
    assert report["end_time"] == pytest.approx(4 * 0.031415926535897934)
    # the real elapsed time and its split (the solver's own time was all it reported)
    split = report["time_split_s"]
    assert set(split) == {"load_scene", "setup", "steps", "output", "pictures", "solver"}
    assert all(v >= 0 for v in split.values()) and split["pictures"] > 0  # forces.png, final.png
    assert split["solver"] <= split["steps"]
    parts = sum(v for k, v in split.items() if k != "solver")
    assert parts <= report["wall_time_s"] <= parts + 5.0  # only the report itself is left out

    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["error"] is None
    assert summary["totals"]["steps"] == 4
    assert summary["simulation"]["bodies"]["body"]["mesh"]["n_cells"] == 512
    assert len(summary["steps"]) == 4
    for k, step in enumerate(summary["steps"], start=1):
        assert step["step"] == k
        assert step["converged"] is True
        assert step["newton_iterations"] >= 1
        assert step["residual_norms"] and all(step["residual_norms"])
        assert set(step["energies"]) == {"elastic", "kinetic", "load_potential"}
        assert 0 < step["min_J"] < 2
    assert summary["steps"][-1]["energies"]["elastic"] > 0

    frames = pvd_files(out)
    # [run] every = 2: the rest frame, then steps 2 and 4.
    assert [p.name for _, p in frames] == [f"body_{i:05d}.vtu" for i in range(3)]
    times = [t for t, _ in frames]
    assert times == sorted(times) and times[0] == 0.0
    assert times[-1] == pytest.approx(report["end_time"])
    for _, path in frames:
        assert path.is_file()
    last = meshio.read(frames[-1][1])
    assert set(last.point_data) >= {"displacement", "velocity"}
    assert set(last.cell_data) >= {
        "J",
        "green_strain",
        "cauchy_stress",
        "von_mises",
        "energy_density",
    }
    assert last.cell_data["cauchy_stress"][0].shape == (512, 9)  # 3 x 3, with sigma_zz
    assert last.point_data["displacement"].shape == (289, 3)  # 2D vectors padded for ParaView
    assert last.cell_data["J"][0].shape == (512,)
    assert np.abs(last.point_data["displacement"]).max() > 0

    for picture in ("final.png", "run.gif"):
        assert (out / picture).is_file() and (out / picture).stat().st_size > 0
    assert (out / "final.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "run.gif").read_bytes()[:6] in (b"GIF87a", b"GIF89a")


def test_beam_3d_tip_moves_down(tmp_path, capsys):
    out = tmp_path / "beam"
    code = main(
        ["run", "beam_3d_gravity", "--steps", "2", "--out", str(out), "--quiet", "--no-render"]
    )
    assert code == 0
    assert not (out / "final.png").exists() and not (out / "run.gif").exists()
    summary = json.loads((out / "summary.json").read_text())
    # --no-render draws no picture at all: the forces are in forces.csv only (issue 41)
    assert (out / "forces.csv").is_file() and not (out / "forces.png").exists()
    assert not any(p.suffix in (".png", ".gif") for p in out.iterdir())
    assert summary["status"] == "completed" and summary["totals"]["steps"] == 2
    frames = pvd_files(out)
    last = meshio.read(frames[-1][1])
    u = last.point_data["displacement"]
    tip = np.abs(last.points[:, 0] - 1.0) < 1e-9  # points are the rest positions
    assert tip.sum() == 25
    assert np.all(u[tip, 2] < 0)
    root = np.abs(last.points[:, 0]) < 1e-9
    np.testing.assert_array_equal(u[root], 0.0)


def test_info_prints_mesh_json(tmp_path, capsys):
    path = tmp_path / "m.vtu"
    write_mesh(ts.box(lower=(0, 0, 0), upper=(1, 1, 1), divisions=(2, 1, 1)), path)
    assert main(["info", str(path)]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["n_cells"] == 12 and info["dim"] == 3
    assert info["total_volume"] == pytest.approx(1.0)


def test_info_into_a_pipe_closed_early_ends_quietly(tmp_path):
    """`tissuesim info mesh | head`: the reader stops reading; no "Broken pipe" error."""
    path = tmp_path / "m.vtu"
    write_mesh(ts.box(divisions=(2, 1, 1)), path)
    cmd = [sys.executable, "-m", "tissuesim", "info", str(path)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # before the child writes: its first write meets a closed pipe
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 0 and err == ""


def test_version_is_the_package_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"tissuesim {ts.__version__}"


def test_info_on_a_missing_mesh(tmp_path, capsys):
    assert main(["info", str(tmp_path / "none.vtu")]) == 2
    assert "none.vtu" in capsys.readouterr().err


def test_examples_lists_the_shipped_scenes(capsys):
    assert main(["examples", "--json"]) == 0
    described = json.loads(capsys.readouterr().out)
    names = {e["name"] for e in described}
    assert {"course_stretch", "course_literal", "beam_3d_gravity"} <= names
    for e in described:
        assert e["path"].endswith((f"{e['name']}.toml", f"{e['name']}.feb"))
        assert e["shows"].endswith(".") and len(e["shows"]) > 20
        assert re.fullmatch(r"\d+ s", e["runtime"] or "")  # each scene says
    by_name = {e["name"]: e for e in described}
    assert by_name["palpation"]["shows"].startswith("Palpation: a rigid sphere probe")
    assert by_name["palpation"]["made_of"] == "3D, 1 body, contact, 26 steps"
    assert by_name["course_stretch"]["made_of"] == "2D, 1 body, 200 steps"
    assert by_name["course_stretch"]["needs"] == []
    parts = by_name["organs_rest_after_cut"]["made_of"]
    assert parts.startswith("3D, 2 bodies, connective tissue, contact, cutting")
    assert "PyVista" in by_name["organs_rest_after_cut"]["needs"][0]
    artery = by_name["artery_strip"]  # a shipped FEBio model
    assert artery["path"].endswith("artery_strip.feb")
    assert artery["made_of"] == "3D, a FEBio model in 3 steps, 40 time steps"
    assert main(["examples"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("# run times: the plain install")
    for name in names:
        assert f"tissuesim run {name}    # " in text


def test_bad_scene_exits_2_naming_the_file(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text('[materail]\nmodel = "linear"\n')
    assert main(["run", str(scene), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert str(scene) in captured.err and "did you mean 'material'" in captured.err
    assert not (tmp_path / "o").exists()


def test_unknown_scene_lists_the_examples(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "nonexistent.toml"]) == 2
    message = capsys.readouterr().err
    assert message.startswith("tissuesim: error: ") and message.count("\n") == 1
    assert "nonexistent.toml" in message
    assert "course_stretch" in message and "beam_3d_gravity" in message


def test_negative_steps_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as info:
        main(["run", "course_stretch", "--steps", "-1"])
    assert info.value.code == 2
    assert "--steps" in capsys.readouterr().err


def test_failed_run_exits_1_and_says_why(tmp_path, capsys):
    scene = tmp_path / "squash.toml"
    scene.write_text(
        """
[mesh]
generator = "rectangle"
lower = [-1.0, -1.0]
upper = [1.0, 1.0]
divisions = [3, 3]

[material]
model = "neo_hookean"
youngs_modulus = 1000.0
poisson_ratio = 0.3

[simulation]
time_step = 0.5
max_step_halvings = 1

[newton]
max_iterations = 3

[[dirichlet]]
vertices = { on_plane = { axis = 0, value = -1.0 } }
displacement = ["-1.5 * x * t", "0"]

[[dirichlet]]
vertices = { on_plane = { axis = 0, value = 1.0 } }
displacement = ["-1.5 * x * t", "0"]
"""
    )
    out = tmp_path / "o"
    assert (
        main(["run", str(scene), "--steps", "4", "--out", str(out), "--quiet", "--no-render"]) == 1
    )
    err = capsys.readouterr().err
    assert err.startswith("tissuesim: error: ") and "Traceback" not in err
    assert "did not converge" in err and "time_step" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "did not converge" in summary["error"]


def test_entry_point_runs_as_a_module(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "tissuesim.cli", "examples"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    assert "course_stretch" in result.stdout


def test_quiet_3d_run_with_pictures_writes_nothing_to_stderr(tmp_path):
    """Off-screen VTK logs "bad X server connection" before falling back to EGL/OSMesa: with
    --quiet (and without) that warning must not reach stderr. VTK writes to the process's
    stderr directly, so the run is a child process."""
    pytest.importorskip("pyvista")
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    out = tmp_path / "o"
    command = [sys.executable, "-m", "tissuesim", "run", "beam_3d_gravity", "--steps", "1"]
    done = subprocess.run(
        [*command, "--out", str(out), "--quiet"], env=env, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    assert (out / "final.png").is_file()
    assert done.stderr == ""


def _help(capsys, *args) -> str:
    with pytest.raises(SystemExit) as exit_info:
        main([*args, "--help"])
    assert exit_info.value.code == 0
    return capsys.readouterr().out


def test_every_argument_of_every_subcommand_has_help_for_users(capsys):
    top = _help(capsys)
    commands = top.split("{", 1)[1].split("}", 1)[0].split(",")
    assert {"run", "demo", "play", "info", "examples"} <= set(commands)
    for text in [top] + [_help(capsys, c) for c in commands]:
        for pattern in (r"``", r"\bissue \d", r"\bsession \d", r"field notes", r"FIELD-NOTES"):
            assert not re.search(pattern, text, re.IGNORECASE), (pattern, text)
        lines = text.splitlines()
        for i, line in enumerate(lines):
            body = line[2:]
            # an argument listed alone on its line must have its help on the next, indented
            if line.startswith("  ") and not line.startswith("   ") and " " not in body.strip():
                follow = lines[i + 1] if i + 1 < len(lines) else ""
                assert follow.startswith("    ") and follow.strip(), (line, text)
