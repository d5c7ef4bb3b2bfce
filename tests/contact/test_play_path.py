"""``tissuesim play`` that can be tested (issue 40): off screen the instrument follows a recorded
device path or the scene's own motion, presses the body and its force changes; the report
gives the real-time factor to three significant digits; a bad path file or a missing display
gets one clear line."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("ipctk")
pytest.importorskip("pyvista")

SCENE = """
[mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.02, 0.02, 0.01]
divisions = [3, 3, 2]
[material]
model = "neo_hookean"
youngs_modulus = 1e4
poisson_ratio = 0.3
[simulation]
integrator = "backward_euler"
time_step = 0.02
density = 1000.0
[[dirichlet]]
name = "base"
vertices = { on_plane = { axis = 2, value = 0.0 } }
[contact]
dhat = 1e-4
[[obstacles]]
name = "probe"
sphere = { center = [0.01, 0.01, 0.0152], radius = 0.005, refinement = 2 }
"""


def _play(tmp_path, capsys, scene: str, *extra: str) -> dict:
    from tissuesim.cli import main

    path = tmp_path / "probe.toml"
    path.write_text(scene)
    code = main(["play", str(path), "--off-screen", str(tmp_path / "frames"), *extra])
    assert code == 0
    return json.loads(capsys.readouterr().out)


def test_play_off_screen_follows_a_device_path_and_the_force_changes(tmp_path, capsys):
    device = tmp_path / "device.csv"
    device.write_text("time_s,x_m,y_m,z_m\n0,0,0,0\n0.1,0,0,-8e-4\n")
    first = _play(tmp_path, capsys, SCENE, "--frames", "2", "--path", str(device))
    later = _play(tmp_path, capsys, SCENE, "--frames", "5", "--path", str(device))
    assert first["contact_mode"] == "interactive"  # play's default
    assert later["force_N"][2] < first["force_N"][2] < 0.0  # pressed further, harder
    assert later["certified_frames"] + later["fallback_frames"] >= 1
    assert later["real_time_factor"] == float(f"{later['real_time_factor']:.3g}") > 0


def test_play_off_screen_follows_the_scenes_own_motion(tmp_path, capsys):
    moving = SCENE + 'translation = ["0", "0", "-0.008 * t"]\n'
    report = _play(tmp_path, capsys, moving, "--frames", "5")
    still = _play(tmp_path, capsys, SCENE, "--frames", "5")
    assert report["force_N"][2] < 0.0
    assert np.linalg.norm(still["force_N"]) == 0.0


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("time,x,y,z\n0,0,0\n", "3 columns"),
        ("0,0,0,0\n0,0,0,1e-3\n", "does not increase"),
        ("0,0,0,0\n0.1,a,0,0\n", "line 2.*not numbers"),
        ("time,x,y,z\n", "no samples"),
    ],
)
def test_a_bad_device_path_gets_one_line_naming_the_file_and_line(tmp_path, text, message):
    from tissuesim.errors import InputError
    from tissuesim.io.device_path import read_device_path

    device = tmp_path / "device.csv"
    device.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        read_device_path(device)
    assert "device.csv" in str(info.value) and "\n" not in str(info.value)


def test_play_in_a_window_without_a_display_says_how_to_run_off_screen(
    tmp_path, capsys, monkeypatch
):
    from tissuesim.cli import main

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    scene = tmp_path / "probe.toml"
    scene.write_text(SCENE)
    assert main(["play", str(scene)]) == 2
    err = capsys.readouterr().err
    assert "--off-screen" in err and "DISPLAY" in err and len(err.strip().splitlines()) == 1


def test_play_refuses_zero_frames(tmp_path, capsys):
    from tissuesim.cli import main

    scene = tmp_path / "probe.toml"
    scene.write_text(SCENE)
    with pytest.raises(SystemExit):
        main(["play", str(scene), "--off-screen", str(tmp_path / "f"), "--frames", "0"])
    assert ">= 1" in capsys.readouterr().err


def test_play_off_screen_runs_frames_and_saves_them(tmp_path, capsys):
    report = _play(tmp_path, capsys, SCENE, "--frames", "2")
    assert report["frames"] == 2 and report["obstacle"] == "probe"
    frames = tmp_path / "frames"
    assert sorted(p.name for p in frames.iterdir()) == ["frame_0000.png", "frame_0001.png"]
