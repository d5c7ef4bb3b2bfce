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


def _worker_state() -> dict:
    import os

    import dask

    from tissuesim.sweep import runs

    return {
        "trim": os.environ.get("MALLOC_TRIM_THRESHOLD_"),
        "numba_threads": os.environ.get("NUMBA_NUM_THREADS"),
        "tick": dask.config.get("distributed.admin.tick.interval"),
        "profile": dask.config.get("distributed.worker.profile.enabled"),
        "contact_threads": os.environ.get("TISSUESIM_CONTACT_THREADS"),
        "prepared": runs._prepared,
    }


def _trim() -> str | None:
    import os

    return os.environ.get("MALLOC_TRIM_THRESHOLD_")


def test_tissuesims_local_cluster_starts_its_workers_warm_and_without_dasks_malloc_trim():
    import os

    from tissuesim.sweep.executors import dask_local_cluster, process_pool, warm_dask_workers

    kept = os.environ.get("MALLOC_TRIM_THRESHOLD_")
    # a nanny sets its pre-spawn variables in its own process: Dask's defaults leave 65536
    os.environ["MALLOC_TRIM_THRESHOLD_"] = "65536"
    try:
        pool = process_pool(1)
        assert pool.submit(_trim).result() is None  # the default pool's workers: unset too
        pool.shutdown()
        with dask_local_cluster(1) as cluster, distributed.Client(cluster) as client:
            (before,) = client.run(_worker_state).values()
            warm_dask_workers(client)
            (after,) = client.run(_worker_state).values()
        assert os.environ["MALLOC_TRIM_THRESHOLD_"] == "65536"  # this process's: restored
    finally:
        if kept is None:
            os.environ.pop("MALLOC_TRIM_THRESHOLD_", None)
        else:
            os.environ["MALLOC_TRIM_THRESHOLD_"] = kept
    # Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 by default (benchmarks/sweep.py)
    assert before["trim"] is None and before["numba_threads"] == "1"
    assert before["tick"] == "1s" and before["profile"] is False and not before["prepared"]
    assert before["contact_threads"] == "1"  # ipctk's TBB: one thread per worker
    assert after["prepared"]
    # Dask's own default is untouched in this process
    import dask

    assert "MALLOC_TRIM_THRESHOLD_" in dask.config.get("distributed.nanny.pre-spawn-environ")
