"""``tissuesim run`` on coupled scenes ([[organs]]): the shipped example for two steps, a small
scene with pictures, the banner, and errors."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import meshio
import numpy as np

from tissuesim.cli import main

SMALL = """
[simulation]
integrator = "quasistatic"
time_step = 0.25

[gravity]
acceleration = [0.0, 0.0, -9.81]

[[organs]]
name = "lower"
mesh = { generator = "box", lower = [0, 0, -0.5], upper = [1, 1, 0], divisions = [3, 3, 2] }
material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.3 }
density = 10.0
fix = { tagged = "zmin" }

[[organs]]
name = "upper"
mesh = { generator = "box", lower = [0, 0, 0.2], upper = [1, 1, 0.7], divisions = [3, 3, 2] }
material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.3 }
density = 10.0

[[graspers]]
organ = "upper"
vertices = { tagged = "zmax" }
displacement = ["0", "0", "0.2 * t"]

[tissue]
material = { model = "stvk", youngs_modulus = 300.0, poisson_ratio = 0.3 }
thickness = 0.2
spacing = 0.1
frames = 8
density = 10.0
region = { where = "(x > 0) * (x < 1) * (y > 0) * (y < 1)" }

[[cuts]]
blade = [["-0.2 + 5.6 * (t - 0.25)", "-0.2", "0.15"], ["-0.2 + 5.6 * (t - 0.25)", "1.2", "0.15"]]
start = 0.25
end = 0.5

[run]
steps = 3
"""


def series(directory, name):
    """(time, path) rows of ``name``.pvd; the file must exist (no skipping)."""
    root = ET.parse(directory / f"{name}.pvd").getroot()
    rows = root.find("Collection").findall("DataSet")
    return [(float(r.get("timestep")), directory / r.get("file")) for r in rows]


def test_run_coupled_example_for_two_steps(tmp_path, capsys):
    out = tmp_path / "organs"
    args = ["run", "organs_retraction_cut", "--steps", "2", "--out", str(out), "--no-render"]
    assert main(args) == 0
    captured = capsys.readouterr()
    banner = captured.err
    assert "organs_retraction_cut: liver: 729 vertices, 3072 tetrahedra; gallbladder: 729" in banner
    assert "/ 30 frames; 1 cut, backward_euler, time_step 0.025 s, 2 steps" in banner
    report = json.loads(captured.out)
    assert report["steps"] == 2 and report["end_time"] == 0.05
    assert 0 < report["min_J"] <= 1.0 + 1e-9

    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["totals"]["steps"] == 2
    forces = summary["forces"]
    assert [f["time"] for f in forces] == [0.025, 0.05]
    assert forces[-1]["grasper"][2] > 0 and forces[-1]["liver.support"][2] > 0
    # [run] every = 2: the rest frame and step 2
    for name in ("liver", "gallbladder", "tissue_points"):
        rows = series(out, name)
        assert [t for t, _ in rows] == [0.0, 0.05] and all(p.is_file() for _, p in rows)
    assert not (out / "cut.pvd").exists()  # the blade starts at t = 1.2 s
    gb = meshio.read(series(out, "gallbladder")[-1][1])
    lifted = gb.point_data["displacement"][:, 2]
    np.testing.assert_allclose(lifted.max(), 0.015 * 0.05, rtol=1e-9)  # the grasped top
    points = meshio.read(series(out, "tissue_points")[-1][1])
    assert points.point_data["alive"].all()


def test_small_coupled_scene_with_a_cut_and_pictures(tmp_path, capsys):
    scene = tmp_path / "boxes.toml"
    scene.write_text(SMALL)
    out = tmp_path / "o"
    assert main(["run", str(scene), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "boxes: lower: 48 vertices, 108 tetrahedra; upper: 48 vertices" in captured.err
    assert "/ 8 frames; 1 cut, quasistatic" in captured.err
    report = json.loads(captured.out)
    assert report["steps"] == 3
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    events = [e for s in summary["steps"] for e in s["extra"]["events"]]
    assert [e["kind"] for e in events] == ["cut"] and events[0]["severed_pairs"] > 0
    # the cut (t = 0.25-0.5 s) parts the layer: the grasper lets go of the lower box, and
    # grasper and support share the weight (boxes 5 kg each, the tissue on either side)
    grasper = [f["grasper"][2] for f in summary["forces"]]
    support = [f["lower.support"][2] for f in summary["forces"]]
    assert grasper[1] > 2 * grasper[2] and support[1] < 0 < support[2]
    assert grasper[2] > 5.0 * 9.81 and support[2] > 5.0 * 9.81
    assert [t for t, _ in series(out, "cut")] == [0.5, 0.75]
    for picture in ("final.png", "run.gif"):
        assert (out / picture).is_file() and (out / picture).stat().st_size > 0


def test_examples_lists_the_coupled_example(capsys):
    assert main(["examples", "--json"]) == 0
    names = {e["name"] for e in json.loads(capsys.readouterr().out)}
    assert "organs_retraction_cut" in names


def test_bad_coupled_scene_exits_2_naming_file_and_table(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text(SMALL.replace('organ = "upper"', 'organ = "uper"'))
    assert main(["run", str(scene), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert str(scene) in captured.err and "graspers[1]" in captured.err
    assert "unknown organ 'uper'; did you mean 'upper'?" in captured.err
    assert not (tmp_path / "o").exists()


def test_the_banner_names_each_bodys_cells():
    """The run banner says what a body's cells are (it had called every 3D mesh's cells
    tetrahedra, FEBio's hexahedra20 too)."""
    import tissuesim as ts
    from tissuesim.cli import _body

    sim = ts.Simulation(integrator="quasistatic")
    law = ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3)
    sim.add_body("hex", ts.box(divisions=(2, 1, 1), element="hex20"), law)
    sim.add_body("tet", ts.box(divisions=(1, 1, 1)), law)
    assert _body(sim) == ("hex: 32 vertices, 2 20-node hexahedra; tet: 8 vertices, 6 tetrahedra"), (
        _body(sim)
    )
