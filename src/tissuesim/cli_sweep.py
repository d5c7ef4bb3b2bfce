"""``tissuesim sweep``: the parameter study's command line (the study itself is
``tissuesim/sweep/``); ``cli.py`` adds the parser and dispatches here."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path

__all__ = ["add_sweep_parser", "sweep_command"]


def add_sweep_parser(
    sub: argparse._SubParsersAction,
    common: list,
    _frames: Callable[[str], int],
    _steps: Callable[[str], int],
) -> None:
    """The ``sweep`` subcommand's arguments (``_frames``: a count >= 1, ``_steps``: >= 0, the
    command line's own checks)."""
    p_sweep = sub.add_parser(
        "sweep",
        parents=common,
        help="run a scene many times over varied keys (a parameter study, training data)",
        description="Run a scene for every sample of the varied keys and write one table of "
        "the runs (runs.csv, runs.parquet) and, with --fields, a dataset of fields "
        "(docs/guide/sweeps.md). A killed study resumes: rerun the same command.",
    )
    p_sweep.add_argument(
        "scene", help="a scene file (.toml) or a shipped example's name (tissuesim examples)"
    )
    p_sweep.add_argument(
        "--vary",
        action="append",
        required=True,
        metavar="KEY=VALUES",
        help="a scene key by its path (material.youngs_modulus, bodies[0].material.density, "
        "obstacles[probe].translation[2]) and its values: a list 1e3,2e3; LOW:HIGH:N (N values, "
        "both ends; LOW:HIGH:N:log); an interval LOW:HIGH (LOW:HIGH:log) for --sampler "
        "sobol|lhs|random; glob:meshes/*.vtu (files in the scene's folder); repeatable, the "
        "lists form a grid",
    )
    p_sweep.add_argument("--out", required=True, help="the study's directory")
    p_sweep.add_argument(
        "--samples", type=_frames, help="points drawn in the intervals (sobol, lhs, random)"
    )
    p_sweep.add_argument(
        "--sampler",
        choices=("grid", "sobol", "lhs", "random"),
        default=None,
        help="grid (default without intervals), sobol (default with them), lhs, random",
    )
    p_sweep.add_argument("--seed", type=_steps, default=0, help="the samplers' seed (default 0)")
    p_sweep.add_argument("--steps", type=_steps, help="steps per run (default the scene's [run])")
    p_sweep.add_argument("--workers", type=_frames, help="worker processes (default one per core)")
    p_sweep.add_argument(
        "--executor",
        default="local",
        help="local (a process pool, default), dask-local (a Dask LocalCluster), "
        "dask://HOST:PORT (a running Dask scheduler) or ray (a local Ray cluster of --workers "
        "CPUs, or the cluster RAY_ADDRESS names; needs Ray)",
    )
    from tissuesim.sweep.dataset import FIELDS as SWEEP_FIELDS

    p_sweep.add_argument(
        "--fields",
        action="append",
        choices=SWEEP_FIELDS,
        help="save this field of every run's end (fields/<run>.h5 or .zarr; repeatable): the "
        "vertices' displacement or a cell field",
    )
    p_sweep.add_argument(
        "--dataset-format",
        choices=("hdf5", "zarr"),
        default="hdf5",
        help="with --fields: one HDF5 file per run (h5py, default) or one Zarr group per run "
        "(zarr 3); tissuesim.sweep.load_dataset reads either",
    )
    p_sweep.add_argument(
        "--every",
        type=_frames,
        help="with --fields: save them at the start, every N steps and at the end (default "
        "only the end)",
    )
    p_sweep.add_argument(
        "--no-render", action="store_true", help="accepted for symmetry: a study draws nothing"
    )
    p_sweep.add_argument("--quiet", action="store_true", help="no progress lines")


def sweep_command(args) -> int:
    """``tissuesim sweep``: the study (tissuesim/sweep/), then a JSON report; exit 0 when it
    ran to its end, failed runs included (they are rows of the table, status "failed")."""
    import time

    from tissuesim.sweep import sweep
    from tissuesim.sweep.executors import close, executor_from_spec

    started = time.perf_counter()
    executor, resources = (None, [])
    if args.executor != "local":
        executor, resources = executor_from_spec(args.executor, args.workers)
    try:
        results = sweep(
            args.scene,
            args.vary,
            out=args.out,
            samples=args.samples,
            sampler=args.sampler,  # None: sobol where there is an interval, else the grid
            seed=args.seed,
            steps=args.steps,
            executor=executor,
            workers=args.workers,
            fields=tuple(args.fields or ()),
            every=args.every,
            dataset_format=args.dataset_format,
            progress=not args.quiet,
        )
    finally:
        close(resources)
    failed = [r for r in results if r["status"] != "completed"]
    out = Path(args.out)
    report = {
        "output": str(out),
        "runs": len(results),
        "completed": len(results) - len(failed),
        "failed": len(failed),
        "first_failure": failed[0]["error"] if failed else None,
        "table": [str(p) for p in (out / "runs.csv", out / "runs.parquet") if p.exists()],
        "fields": str(out / "fields") if args.fields else None,
        "wall_time_s": time.perf_counter() - started,
    }
    print(json.dumps(report, indent=2))
    return 0
