"""The fields dataset in Zarr (``dataset_format="zarr"``): one group per run written by its
worker, opened with zarr it holds what docs/guide/sweeps.md says, and ``load_dataset`` reads it
into the arrays the HDF5 dataset of the same study gives, bit for bit."""

from __future__ import annotations

import json
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import tissuesim
from tissuesim.cli import main
from tissuesim.errors import InputError, OutputError

zarr = pytest.importorskip("zarr")

VARY = {
    "material.youngs_modulus": [800.0, 1500.0],
    "dirichlet[pull].displacement[0]": ["0.1 * t", "0.2 * t"],
}
FIELDS = ("displacement", "J", "cauchy_stress")


def _study(scene, out, dataset_format, **kwargs):
    with ThreadPoolExecutor(1) as pool:
        return tissuesim.sweep(
            scene, VARY, out=out, executor=pool, dataset_format=dataset_format, **kwargs
        )


def _assert_same_dataset(a: dict, b: dict) -> None:
    assert sorted(a) == sorted(b)
    for key in a:
        assert a[key].dtype == b[key].dtype, key
        assert a[key].shape == b[key].shape, key
        assert np.array_equal(a[key], b[key]), key


def test_a_zarr_grid_study_holds_what_the_docs_say(bar_scene, tmp_path):
    out = tmp_path / "z"
    # two worker processes writing their runs' groups at once
    results = tissuesim.sweep(
        bar_scene, VARY, out=out, workers=2, fields=FIELDS, dataset_format="zarr"
    )
    assert [r["status"] for r in results] == ["completed"] * 4
    folder = out / "fields"
    assert sorted(p.name for p in folder.iterdir()) == [
        "r00000.zarr",
        "r00001.zarr",
        "r00002.zarr",
        "r00003.zarr",
        "rest.zarr",
    ]  # no temporary group left behind
    mesh = tissuesim.read_mesh(bar_scene.parent / "mesh" / "bar.vtu")
    rest = zarr.open_group(folder / "rest.zarr", mode="r")
    assert np.array_equal(rest["body/points"][...], mesh.points)
    assert np.array_equal(rest["body/cells"][...], mesh.cells)
    assert rest["body/cells"].dtype == np.int64
    run = zarr.open_group(folder / "r00003.zarr", mode="r")
    attrs = run.attrs.asdict()
    assert attrs["run_id"] == "r00003" and attrs["index"] == 3
    assert attrs["rest_sha256"] == rest.attrs["rest_sha256"]
    assert attrs["param:material.youngs_modulus"] == 1500.0
    assert attrs["param:dirichlet[pull].displacement[0]"] == "0.2 * t"
    assert sorted(run["body"].array_keys()) == ["J", "cauchy_stress", "displacement"]
    u = run["body/displacement"][...]
    assert u.shape == (20, 3) and u.dtype == np.float64
    assert run["body/cauchy_stress"].shape == (mesh.n_cells, 3, 3)
    assert run["body/displacement"].chunks == (20, 3)  # one chunk: the run's own
    assert u[:, 0].max() == pytest.approx(0.2, abs=1e-12)  # the pulled end: 0.2 * t at t = 1
    size = sum(p.stat().st_size for p in (folder / "r00003.zarr").rglob("*") if p.is_file())
    assert results[3]["fields_bytes"] == size
    study = json.loads((out / "study.json").read_text())
    assert study["dataset_format"] == "zarr"

    h5 = tmp_path / "h"
    _study(bar_scene, h5, "hdf5", fields=FIELDS)
    data = tissuesim.sweep.load_dataset(out)
    _assert_same_dataset(data, tissuesim.sweep.load_dataset(h5))
    assert data["body/displacement"].shape == (4, 20, 3)
    assert np.array_equal(data["body/displacement"][3], u)
    assert "dataset_format" not in json.loads((h5 / "study.json").read_text())


def test_zarr_fields_at_every_saved_time_equal_hdf5_s(bar_scene, tmp_path):
    z, h = tmp_path / "z", tmp_path / "h"
    _study(bar_scene, z, "zarr", fields=("displacement", "J"), every=1)
    _study(bar_scene, h, "hdf5", fields=("displacement", "J"), every=1)
    data = tissuesim.sweep.load_dataset(z)
    _assert_same_dataset(data, tissuesim.sweep.load_dataset(h))
    assert data["times"].tolist() == [[0.0, 0.5, 1.0]] * 4
    run = zarr.open_group(z / "fields" / "r00000.zarr", mode="r")
    assert run["body/displacement"].chunks == (1, 20, 3)  # one chunk per saved time
    assert run["times"][...].tolist() == [0.0, 0.5, 1.0]


def test_a_zarr_run_written_again_replaces_its_group(bar_scene, tmp_path):
    """A study killed between a run's fields and its result: the resumed run writes its group
    again over the old one."""
    out = tmp_path / "z"
    _study(bar_scene, out, "zarr", fields=("displacement",))
    before = tissuesim.sweep.load_dataset(out)
    (out / "runs" / "r00002.json").unlink()
    (out / "fields" / "r00002.zarr" / "body" / "displacement" / "zarr.json").unlink()
    results = _study(bar_scene, out, "zarr", fields=("displacement",))
    assert results[2]["status"] == "completed"
    _assert_same_dataset(tissuesim.sweep.load_dataset(out), before)
    assert not [p for p in (out / "fields").iterdir() if p.name.startswith(".")]


def test_a_mesh_per_sample_in_zarr(bar_scene, tmp_path):
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
        tissuesim.sweep(
            scene,
            ["mesh.file=glob:meshes/*.vtu"],
            out=out,
            executor=pool,
            fields=["displacement"],
            dataset_format="zarr",
        )
    run = zarr.open_group(out / "fields" / "r00001.zarr", mode="r")
    assert run["body/points"].shape == (36, 3)  # its own rest mesh
    assert "points" not in set(zarr.open_group(out / "fields" / "r00000.zarr")["body"])
    with pytest.raises(InputError, match="rest mesh differs.*read each run's file with zarr"):
        tissuesim.sweep.load_dataset(out)


def test_bad_dataset_formats_are_one_line(bar_scene, tmp_path, monkeypatch):
    vary = {"material.youngs_modulus": [1e3]}
    with pytest.raises(InputError, match="--dataset-format 'netcdf': choose hdf5"):
        tissuesim.sweep(bar_scene, vary, out=tmp_path / "a", dataset_format="netcdf")
    with pytest.raises(InputError, match="--dataset-format zarr is the format of the fields"):
        tissuesim.sweep(bar_scene, vary, out=tmp_path / "b", dataset_format="zarr")
    h5 = tmp_path / "c"
    _study(bar_scene, h5, "hdf5", fields=("displacement",))
    with pytest.raises(OutputError, match="holds another study .its dataset_format differ"):
        _study(bar_scene, h5, "zarr", fields=("displacement",))
    monkeypatch.setitem(sys.modules, "zarr", None)  # zarr not installed
    with pytest.raises(InputError, match=r"needs zarr \(3.x\): pip install 'tissuesim\[sweep\]'"):
        _study(bar_scene, tmp_path / "d", "zarr", fields=("displacement",))
    assert not (tmp_path / "a").exists() and not (tmp_path / "d").exists()


def test_the_command_line_s_dataset_format(bar_scene, tmp_path, capsys):
    out = tmp_path / "s"
    args = ["sweep", str(bar_scene), "--vary", "material.youngs_modulus=500,2000"]
    args += ["--out", str(out), "--workers", "1", "--fields", "displacement", "--quiet"]
    assert main([*args, "--dataset-format", "zarr"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["completed"] == 2 and report["fields"] == str(out / "fields")
    data = tissuesim.sweep.load_dataset(out)
    assert data["body/displacement"].shape == (2, 20, 3)
    assert data["material.youngs_modulus"].tolist() == [500.0, 2000.0]
