"""``tissuesim run`` on frame scenes: the shipped example end to end, the banner, and errors."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import meshio
import numpy as np

from tissuesim.cli import main


def series(directory, name):
    """(time, path) rows of ``name``.pvd; the file must exist (no skipping)."""
    root = ET.parse(directory / f"{name}.pvd").getroot()
    rows = root.find("Collection").findall("DataSet")
    return [(float(r.get("timestep")), directory / r.get("file")) for r in rows]


def test_run_frames_example_writes_its_output(tmp_path, capsys):
    out = tmp_path / "sag"
    assert main(["run", "frames_block_sag", "--steps", "2", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "frames_block_sag: body: 6 rigid frames, 320 points" in captured.err
    assert "backward_euler" in captured.err
    report = json.loads(captured.out)
    assert report["steps"] == 2 and report["output"] == str(out)
    assert report["end_time"] > 0 and 0 < report["min_J"] <= 1.0 + 1e-9

    for name in ("body_frames", "body_surface", "body"):
        rows = series(out, name)
        assert rows[0][0] == 0.0 and len(rows) >= 2
        assert all(path.is_file() for _, path in rows)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["error"] is None
    assert summary["totals"]["steps"] == 2
    for picture in ("final.png", "run.gif"):
        assert (out / picture).is_file() and (out / picture).stat().st_size > 0

    # the free end of the block moves down (-y); the clamped frame stays, and the surface at
    # z = 0 moves only a little (its points also feel the next frame: a frame clamp is soft)
    last = meshio.read(series(out, "body_surface")[-1][1])
    u = last.point_data["displacement"]
    rest = last.points  # the series are on rest positions
    tip, root = np.abs(rest[:, 2] - 2.0) < 1e-9, np.abs(rest[:, 2]) < 1e-9
    assert tip.any() and root.any() and np.all(u[tip, 1] < 0)
    assert np.abs(u[root]).max() < 0.05 * np.abs(u[tip, 1]).min()
    frames = meshio.read(series(out, "body_frames")[-1][1])
    u = frames.point_data["displacement"]
    clamped = np.abs(frames.points[:, 2]) < 1e-9
    assert clamped.sum() == 1
    np.testing.assert_array_equal(u[clamped], 0.0)


def test_examples_lists_the_frames_example(capsys):
    assert main(["examples", "--json"]) == 0
    names = {e["name"] for e in json.loads(capsys.readouterr().out)}
    assert "frames_block_sag" in names


def test_frame_scene_from_a_file_without_render(tmp_path, capsys):
    scene = tmp_path / "ball.toml"
    scene.write_text(
        """
[frames]
count = 4

[region]
ellipsoid = { center = [0.0, 0.0, 0.0], semi_axes = [0.3, 0.2, 0.2] }
spacing = 0.1

[material]
model = "neo_hookean"
youngs_modulus = 1e4
poisson_ratio = 0.3

[simulation]
density = 1000.0
time_step = 0.01

[gravity]
acceleration = [0.0, 0.0, -9.81]

[[springs]]
points = { surface_on_plane = { axis = 2, value = 0.2, tolerance = 0.05 } }
stiffness = 200.0

[run]
steps = 3
"""
    )
    out = tmp_path / "o"
    assert main(["run", str(scene), "--out", str(out), "--quiet", "--no-render"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["steps"] == 3
    assert (out / "summary.json").is_file() and (out / "body_surface.pvd").is_file()
    assert not (out / "final.png").exists()


def test_bad_frame_scene_exits_2_naming_file_and_table(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text(
        """
[frames]
count = 3

[material]
model = "stvk"
youngs_modulus = 1e4
poisson_ratio = 0.3
"""
    )
    assert main(["run", str(scene), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert str(scene) in captured.err and "[region]" in captured.err
    assert not (tmp_path / "o").exists()
