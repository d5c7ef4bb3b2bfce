"""A study end to end on the tiny bar (conftest.py): results equal single runs bit for bit, a
failing sample is recorded while the others finish, a killed study resumes to the same table,
the fields dataset holds what docs/guide/sweeps.md says."""

from __future__ import annotations

import copy
import csv
import json
import tomllib
from concurrent.futures import Future, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool

import h5py
import numpy as np
import pytest

import tissuesim
from tissuesim.errors import OutputError
from tissuesim.scene.loader import build_scene

VARY = {
    "material.youngs_modulus": [800.0, 1500.0],
    "dirichlet[pull].displacement[0]": ["0.1 * t", "0.2 * t"],
}
TIMES = ("wall_time_s", "build_time_s", "setup_time_s", "solve_time_s", "fields_write_s")


def _single_run(scene, values):
    """The scene run alone, in this process, with the values put in by hand."""
    data = tomllib.loads(scene.read_text())
    data = copy.deepcopy(data)
    data["material"]["youngs_modulus"] = values["material.youngs_modulus"]
    data["dirichlet"][1]["displacement"][0] = values["dirichlet[pull].displacement[0]"]
    sim = build_scene(data, base_dir=scene.parent, source=str(scene)).simulation
    history = sim.run(2, progress=False, render=False)
    return sim, history


def _single_run_e(scene, youngs_modulus):
    return _single_run(
        scene,
        {"material.youngs_modulus": youngs_modulus, "dirichlet[pull].displacement[0]": "0.1 * t"},
    )


def _rows(path):
    with open(path, newline="") as f:
        return [{k: v for k, v in row.items() if k not in TIMES} for row in csv.DictReader(f)]


def test_a_grid_study_equals_single_runs_bit_for_bit(bar_scene, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the mesh is found beside the scene, not here
    out = tmp_path / "study"
    results = tissuesim.sweep(bar_scene, VARY, out=out, workers=2, fields=["displacement"])
    assert [r["params"] for r in results] == [
        {"material.youngs_modulus": e, "dirichlet[pull].displacement[0]": u}
        for e in (800.0, 1500.0)
        for u in ("0.1 * t", "0.2 * t")
    ]
    data = tissuesim.sweep.load_dataset(out)
    assert list(data["run_id"]) == ["r00000", "r00001", "r00002", "r00003"]
    for i, result in enumerate(results):
        assert result["status"] == "completed", result["error"]
        sim, history = _single_run(bar_scene, result["params"])
        assert result["forces"] == sim.forces()  # exact: floats compared bit for bit
        assert result["steps"] == 2
        assert result["newton_iterations"] == sum(r.newton_iterations for r in history)
        assert np.array_equal(data["body/displacement"][i], sim.body_displacement("body"))
    # the stiffer bar pulls harder, the longer pull more: the runs did get their values
    pull = [r["forces"]["pull"][0] for r in results]
    assert pull[0] < pull[1] and pull[0] < pull[2] < pull[3]
    table = _rows(out / "runs.csv")
    assert [row["material.youngs_modulus"] for row in table] == [
        "800.0",
        "800.0",
        "1500.0",
        "1500.0",
    ]
    assert [float(row["pull_x_N"]) for row in table] == pull  # repr floats: exact


def test_a_failing_sample_is_recorded_and_the_others_finish(bar_scene, tmp_path, capsys):
    vary = {"material.poisson_ratio": [0.3, 0.7, 0.4]}
    with ThreadPoolExecutor(2) as pool:
        results = tissuesim.sweep(bar_scene, vary, out=tmp_path / "s", executor=pool)
    progress = capsys.readouterr().err.splitlines()  # not a terminal: one line per tenth
    # one line per run: a run reading its mesh in a worker thread once swapped the process's
    # sys.stderr (mesh/io.py), and lines went missing (2 of 3 in CI, then 0)
    assert len(progress) == 3 and progress[-1].startswith("tissuesim: run 3/3 done, 1 failed, ")
    assert progress[-1].endswith("about 0 s left")
    assert [r["status"] for r in results] == ["completed", "failed", "completed"]
    assert "poisson_ratio" in results[1]["error"] and "\n" not in results[1]["error"]
    assert results[1]["forces"] == {}
    assert results[2]["forces"]["pull"][0] > results[0]["forces"]["pull"][0] > 0
    table = _rows(tmp_path / "s" / "runs.csv")
    assert [row["status"] for row in table] == ["completed", "failed", "completed"]
    assert table[1]["error"] == results[1]["error"] and table[1]["pull_x_N"] == ""


class _DiesAfter(ThreadPoolExecutor):
    """An executor whose workers die after ``n`` runs: the rest fail as a process pool's do."""

    def __init__(self, n):
        super().__init__(1)
        self.n = n

    def submit(self, fn, task):
        if task.index < self.n:
            return super().submit(fn, task)
        future = Future()
        future.set_exception(BrokenProcessPool("a worker died"))
        return future


def test_a_killed_study_resumes_and_ends_with_the_same_table(bar_scene, tmp_path):
    vary = {"material.youngs_modulus": "500:2000:4"}
    with ThreadPoolExecutor(1) as pool:
        whole = tissuesim.sweep(bar_scene, vary, out=tmp_path / "whole", executor=pool)
    out = tmp_path / "killed"
    with _DiesAfter(2) as pool:
        first = tissuesim.sweep(bar_scene, vary, out=out, executor=pool)
    assert [r["status"] for r in first] == ["completed", "completed", "failed", "failed"]
    assert "executor lost the run" in first[2]["error"]
    assert sorted(p.name for p in (out / "runs").iterdir()) == ["r00000.json", "r00001.json"]
    kept = {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()}
    with ThreadPoolExecutor(1) as pool:
        resumed = tissuesim.sweep(bar_scene, vary, out=out, executor=pool)
    assert {p: (out / "runs" / p).stat().st_mtime_ns for p in kept} == kept  # not run again
    assert [r["status"] for r in resumed] == ["completed"] * 4
    assert _rows(out / "runs.csv") == _rows(tmp_path / "whole" / "runs.csv")
    assert [r["forces"] for r in resumed] == [r["forces"] for r in whole]
    # another study in the same directory is refused, naming what differs
    with pytest.raises(OutputError, match="holds another study .*runs"):
        tissuesim.sweep(bar_scene, {"material.youngs_modulus": "500:2000:3"}, out=out)


def test_sobol_study_runs_the_samples_asked_for(bar_scene, tmp_path):
    vary = ["material.youngs_modulus=500:2000", "material.poisson_ratio=0.2,0.4"]
    with ThreadPoolExecutor(2) as pool:
        results = tissuesim.sweep(
            bar_scene,
            vary,
            out=tmp_path / "s",
            samples=2,
            seed=5,
            executor=pool,  # sobol
        )
    params = tissuesim.sweep.parameters(vary, tomllib.loads(bar_scene.read_text()))
    assert [r["params"] for r in results] == tissuesim.sweep.make_samples(params, 2, "sobol", 5)
    assert [r["params"]["material.poisson_ratio"] for r in results] == [0.2, 0.2, 0.4, 0.4]
    study = json.loads((tmp_path / "s" / "study.json").read_text())
    assert study["runs"] == [r["params"] for r in results] and study["seed"] == 5
    assert study["sampler"] == "sobol"  # the default where a key is an interval


def test_the_dataset_holds_what_the_docs_say(bar_scene, tmp_path):
    out = tmp_path / "s"
    with ThreadPoolExecutor(1) as pool:
        results = tissuesim.sweep(
            bar_scene,
            {"material.youngs_modulus": [700.0, 900.0]},
            out=out,
            executor=pool,
            fields=("displacement", "J", "cauchy_stress"),
        )
    mesh = tissuesim.read_mesh(bar_scene.parent / "mesh" / "bar.vtu")
    with h5py.File(out / "fields" / "rest.h5", "r") as f:
        assert np.array_equal(f["body/points"][()], mesh.points)
        assert np.array_equal(f["body/cells"][()], mesh.cells)
    with h5py.File(out / "fields" / "r00001.h5", "r") as f:
        assert f.attrs["run_id"] == "r00001" and f.attrs["index"] == 1
        assert f.attrs["param:material.youngs_modulus"] == 900.0
        u = f["body/displacement"][()]
        assert u.shape == (20, 3) and u.dtype == np.float64
        assert "points" not in f["body"]  # the shared rest mesh is in rest.h5 only
        assert sorted(f["body"]) == ["J", "cauchy_stress", "displacement"]
        J, stress = f["body/J"][()], f["body/cauchy_stress"][()]
    assert J.shape == (mesh.n_cells,) and stress.shape == (mesh.n_cells, 3, 3)
    sim, _ = _single_run_e(bar_scene, 900.0)
    assert np.array_equal(J, sim.cell_fields("body")["J"])
    assert np.array_equal(stress, sim.cell_fields("body")["cauchy_stress"])
    assert (stress[:, 0, 0] > 0).all()  # the pulled bar is in tension along x
    assert u[:, 0].max() == pytest.approx(0.1, abs=1e-12)  # the pulled end: 0.1 * t at t = 1
    data = tissuesim.sweep.load_dataset(out)
    assert data["body/displacement"].shape == (2, 20, 3)
    assert data["body/cauchy_stress"].shape == (2, mesh.n_cells, 3, 3)
    assert np.array_equal(data["body/J"][1], J)
    assert np.array_equal(data["body/displacement"][1], u)
    assert list(data["material.youngs_modulus"]) == [700.0, 900.0]
    assert np.array_equal(data["body/points"], mesh.points)
    assert results[1]["fields_bytes"] == (out / "fields" / "r00001.h5").stat().st_size
    table = tissuesim.sweep.load_table(out)
    assert [row["fields_bytes"] for row in table] == [r["fields_bytes"] for r in results]
    assert json.loads((out / "study.json").read_text())["scene"] == str(bar_scene)


def test_fields_at_every_saved_time(bar_scene, tmp_path):
    out = tmp_path / "s"
    with ThreadPoolExecutor(1) as pool:
        tissuesim.sweep(
            bar_scene,
            {"material.youngs_modulus": [700.0, 900.0]},
            out=out,
            executor=pool,
            fields=("displacement", "J"),
            every=1,
        )
    data = tissuesim.sweep.load_dataset(out)
    assert data["times"].tolist() == [[0.0, 0.5, 1.0]] * 2
    assert data["body/displacement"].shape == (2, 3, 20, 3)
    assert data["body/J"].shape == (2, 3, 24)
    assert (data["body/displacement"][:, 0] == 0).all() and (data["body/J"][:, 0] == 1).all()
    sim, _ = _single_run_e(bar_scene, 900.0)
    assert np.array_equal(data["body/displacement"][1, -1], sim.body_displacement("body"))
    assert data["body/displacement"][1, 1, :, 0].max() == pytest.approx(0.05, abs=1e-12)
    with pytest.raises(tissuesim.InputError, match="give --fields too"):
        tissuesim.sweep(bar_scene, {"material.youngs_modulus": [1.0]}, out=out / "x", every=2)


def test_a_mesh_per_sample_from_a_folder(bar_scene, tmp_path):
    from tissuesim.mesh.io import write_mesh

    folder = tmp_path / "scene"
    (folder / "meshes").mkdir(parents=True)
    for n in (4, 8):
        mesh = tissuesim.box((0, 0, 0), (1.0, 0.25, 0.25), (n, 1, 1))
        write_mesh(mesh, folder / "meshes" / f"bar{n}.vtu")
    scene = folder / "bar.toml"
    scene.write_text(bar_scene.read_text())
    out = tmp_path / "s"
    with ThreadPoolExecutor(1) as pool:
        results = tissuesim.sweep(
            scene, ["mesh.file=glob:meshes/*.vtu"], out=out, executor=pool, fields=["displacement"]
        )
    assert [r["params"]["mesh.file"] for r in results] == ["meshes/bar4.vtu", "meshes/bar8.vtu"]
    assert [r["status"] for r in results] == ["completed", "completed"]
    assert results[0]["forces"] != results[1]["forces"]  # another mesh, another answer
    with h5py.File(out / "fields" / "r00001.h5", "r") as f:
        assert f["body/points"].shape == (36, 3)  # its own rest mesh: not rest.h5's
    with pytest.raises(tissuesim.InputError, match="rest mesh differs"):
        tissuesim.sweep.load_dataset(out)
    with pytest.raises(tissuesim.InputError, match="no file matches"):
        tissuesim.sweep(scene, ["mesh.file=glob:meshes/*.stl"], out=tmp_path / "t")
