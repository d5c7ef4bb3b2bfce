"""A study on a real Dask LocalCluster of worker processes (2 workers, 1 thread each) through
``Client.get_executor()`` equals the same study on the default process pool, bit for bit."""

from __future__ import annotations

import csv
import json

import pytest

import tissuesim

distributed = pytest.importorskip("distributed")  # in the test extra: CI runs this

TIMES = ("wall_time_s", "build_time_s", "setup_time_s", "solve_time_s", "fields_write_s")


def _rows(path):
    with open(path, newline="") as f:
        return [{k: v for k, v in row.items() if k not in TIMES} for row in csv.DictReader(f)]


def test_a_dask_local_cluster_study_equals_the_process_pool_one(bar_scene, tmp_path):
    vary = {"material.youngs_modulus": "500:2000", "material.poisson_ratio": [0.25, 0.45]}
    kwargs = {"samples": 2, "sampler": "lhs", "seed": 11, "fields": ["displacement"]}
    pool = tissuesim.sweep(bar_scene, vary, out=tmp_path / "pool", workers=2, **kwargs)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        dask = tissuesim.sweep(
            bar_scene, vary, out=tmp_path / "dask", executor=client.get_executor(), **kwargs
        )
        pids = client.run(lambda: __import__("os").getpid())
    assert len(set(pids.values())) == 2  # two worker processes
    assert [r["status"] for r in dask] == ["completed"] * 4
    assert [r["forces"] for r in dask] == [r["forces"] for r in pool]
    assert [r["params"] for r in dask] == [r["params"] for r in pool]
    assert _rows(tmp_path / "dask" / "runs.csv") == _rows(tmp_path / "pool" / "runs.csv")
    a = tissuesim.sweep.load_dataset(tmp_path / "pool")
    b = tissuesim.sweep.load_dataset(tmp_path / "dask")
    assert (a["body/displacement"] == b["body/displacement"]).all()


def test_the_command_line_starts_a_dask_local_cluster(bar_scene, tmp_path, capsys):
    from tissuesim.cli import main

    out = tmp_path / "s"
    args = ["sweep", str(bar_scene), "--vary", "material.youngs_modulus=800,1500"]
    code = main([*args, "--out", str(out), "--executor", "dask-local", "--workers", "2", "--quiet"])
    assert code == 0
    assert json.loads(capsys.readouterr().out)["completed"] == 2
    tissuesim.sweep(bar_scene, {"material.youngs_modulus": "800,1500"}, out=tmp_path / "p")
    assert _rows(out / "runs.csv") == _rows(tmp_path / "p" / "runs.csv")


def test_the_command_line_connects_to_a_running_scheduler(bar_scene, tmp_path, capsys):
    from tissuesim.cli import main

    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        address = cluster.scheduler_address.removeprefix("tcp://")
        args = ["sweep", str(bar_scene), "--vary", "material.youngs_modulus=800,1500", "--quiet"]
        assert main([*args, "--out", str(tmp_path / "s"), "--executor", f"dask://{address}"]) == 0
        assert json.loads(capsys.readouterr().out)["completed"] == 2
        # the scheduler and its worker are the caller's: still running after the study
        with distributed.Client(cluster) as client:
            assert len(client.scheduler_info()["workers"]) == 1
    import dask

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        code = main([*args, "--out", str(tmp_path / "t"), "--executor", f"dask://{address}"])
    assert code == 2
    assert "cannot reach a Dask scheduler" in capsys.readouterr().err
