"""The README's promises: a two-command quick start, and its Python and TOML examples run."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np

from tissuesim.cli import example_path
from tissuesim.scene.loader import build_scene

README = Path(__file__).resolve().parents[1] / "README.md"


def blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README.read_text(), flags=re.S)


def test_quick_start_has_exactly_two_commands():
    text = README.read_text()
    section = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    fenced = re.findall(r"```\w*\n(.*?)```", section, flags=re.S)
    assert len(fenced) == 1
    commands = [line for line in fenced[0].splitlines() if line.strip()]
    assert len(commands) == 2
    assert "demo" in commands[0] and "pytest" in commands[1]


def test_python_example_runs(tmp_path):
    code = blocks("python")[0]
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    t, iterations, min_J = map(float, result.stdout.split())
    assert abs(t - 20 * 2 * np.pi / 200) < 1e-9 and iterations >= 1 and 0 < min_J < 2
    assert (tmp_path / "out/python_example/body.pvd").is_file()


def test_frames_python_example_runs(tmp_path):
    """The README's frame-based example, shortened to 3 steps (the code is otherwise as shown)."""
    code = blocks("python")[1]
    assert "steps=50" in code
    result = subprocess.run(
        [sys.executable, "-c", code.replace("steps=50", "steps=3")],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    out = tmp_path / "out/frames"
    for name in ("body_surface.pvd", "body_frames.pvd", "body.pvd", "final.png", "run.gif"):
        assert (out / name).is_file(), name
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"


def test_toml_example_is_the_shipped_beam_scene():
    (toml_text,) = blocks("toml")
    readme_scene = tomllib.loads(toml_text)
    shipped = tomllib.loads(example_path("beam_3d_gravity").read_text())
    assert readme_scene == shipped
    scene = build_scene(readme_scene, name="readme_beam")
    sim = scene.simulation
    sim.step()
    tip = np.isclose(sim.mesh.points[:, 0], 1.0)
    assert sim.displacement[tip, 2].mean() < 0  # it sags


def test_coupled_python_example_runs(tmp_path):
    """The README's organs + tissue example, as shown: the force drops to the weight after the
    cut."""
    code = blocks("python")[2]
    assert "add_tissue" in code
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    forces = [float(line.split()[-2]) for line in result.stdout.splitlines()]
    assert len(forces) == 10
    assert max(forces[:4]) > 60.0
    assert abs(forces[-1] - 58.86) < 0.5
    out = tmp_path / "out/coupled"
    for name in ("lower.pvd", "upper.pvd", "tissue_points.pvd", "cut.pvd", "summary.json"):
        assert (out / name).is_file(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and len(summary["forces"]) == 10
