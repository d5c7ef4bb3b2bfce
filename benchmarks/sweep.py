"""What a parameter study costs (``tissuesim.sweep``, issue 43).

    python3 benchmarks/sweep.py [--scene two_blocks_tied] [--runs 40] [--workers 1 2] [--dask]
                                [--dataset-format hdf5 zarr] [--write benchmarks/results/sweep.md]

A study of ``--runs`` runs of a shipped contact-free scene (default ``two_blocks_tied``: two
glued blocks, 720 tetrahedra, 10 quasistatic steps; its fat layer's Young's modulus
varied over 2e3..8e3 Pa, evenly spaced), for each worker count on the default process pool
(one thread per worker; ``--dask``: also on a Dask LocalCluster of as many worker processes):

- runs per minute, with and without the pool's start-up (workers started, imports, warm-up);
- per run (median): the run's wall time in its worker, its steps' own solve time, the scene
  built (``build_scene``) and the model set up, and all but the solve against the solve time;
- the study's own overhead per run: workers x study wall time - the runs' summed wall times
  (dispatch, result files, the table, workers idle at the end), per run;
- the fields dataset (``--fields displacement``) in each ``--dataset-format`` (default hdf5):
  file (Zarr: group) size and write time per run (median), and reading every run back with
  ``load_dataset``.

The 1-minute load average is printed before and after each measurement: on a shared machine
the figures are only as good as the load was low.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path


def load() -> str:
    return "/".join(f"{x:.2f}" for x in os.getloadavg())


def study(
    scene: str, runs: int, workers: int, executor, fields=(), key=None, dataset_format="hdf5"
) -> dict:
    import tissuesim
    from tissuesim.sweep.executors import process_pool

    low, high = (2e3, 8e3) if key is None else (5e4, 2e5)
    vary = {key or "bodies[fat].material.youngs_modulus": f"{low}:{high}:{runs}"}
    before = load()
    t0 = time.perf_counter()
    owned = None
    if executor is None:
        executor = owned = process_pool(workers)
    t1 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        results = tissuesim.sweep(
            scene,
            vary,
            out=Path(tmp) / "s",
            executor=executor,
            fields=fields,
            progress=False,
            **({"dataset_format": dataset_format} if fields else {}),
        )
        t2 = time.perf_counter()
        read_s = None
        if fields:
            tissuesim.sweep.load_dataset(Path(tmp) / "s")
            read_s = time.perf_counter() - t2
    if owned is not None:
        owned.shutdown()
    failed = [r for r in results if r["status"] != "completed"]
    assert not failed, failed[0]["error"]
    wall = [r["wall_time_s"] for r in results]
    solve = [r["solve_time_s"] for r in results]
    rest = [w - s for w, s in zip(wall, solve, strict=True)]
    out = {
        "workers": workers,
        "start_s": t1 - t0,
        "study_s": t2 - t1,
        "runs_per_min": 60 * runs / (t2 - t1),
        "runs_per_min_with_start": 60 * runs / (t2 - t0),
        "run_wall_s": statistics.median(wall),
        "run_solve_s": statistics.median(solve),
        "run_build_s": statistics.median(r["build_time_s"] for r in results),
        "run_setup_s": statistics.median(r["setup_time_s"] for r in results),
        "run_rest_share": statistics.median(r / s for r, s in zip(rest, solve, strict=True)),
        "study_overhead_s": (workers * (t2 - t1) - sum(wall)) / runs,
        "steps": results[0]["steps"],
        "load_before": before,
        "load_after": load(),
    }
    if fields:
        out["dataset_format"] = dataset_format
        out["fields_bytes"] = statistics.median(r["fields_bytes"] for r in results)
        out["fields_write_s"] = statistics.median(r["fields_write_s"] for r in results)
        out["read_all_s"] = read_s
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default="two_blocks_tied")
    parser.add_argument("--runs", type=int, default=40)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--dask", action="store_true", help="also on a Dask LocalCluster")
    parser.add_argument("--write", help="write the markdown table to this file")
    parser.add_argument(
        "--key",
        help="the key to vary over 5e4..2e5 Pa (default bodies[fat].material.youngs_modulus "
        "over 2e3..8e3, for two_blocks_tied); e.g. material.youngs_modulus for "
        "friction_incline (contact)",
    )
    parser.add_argument("--no-fields", action="store_true", help="skip the dataset's figures")
    parser.add_argument(
        "--dataset-format",
        nargs="+",
        choices=("hdf5", "zarr"),
        default=["hdf5"],
        help="the fields dataset's formats to measure (default hdf5)",
    )
    args = parser.parse_args()
    print(f"load before: {load()} (1, 5, 15 min), {os.cpu_count()} cores")
    rows = []
    for w in args.workers:
        rows.append(("process pool", study(args.scene, args.runs, w, None, key=args.key)))
        print(rows[-1])
    if args.dask:
        from distributed import Client, LocalCluster

        for w in args.workers:
            t0 = time.perf_counter()
            with (
                LocalCluster(
                    n_workers=w, threads_per_worker=1, processes=True, dashboard_address=None
                ) as cluster,
                Client(cluster) as client,
            ):
                started = time.perf_counter() - t0
                row = study(args.scene, args.runs, w, client.get_executor(), key=args.key)
                row["start_s"] = started
                rows.append(("Dask LocalCluster", row))
                print(rows[-1])
    datasets = []
    if not args.no_fields:
        for fmt in args.dataset_format:
            datasets.append(
                study(
                    args.scene,
                    args.runs,
                    max(args.workers),
                    None,
                    ("displacement",),
                    key=args.key,
                    dataset_format=fmt,
                )
            )
            print(datasets[-1])
    lines = [
        f"# Parameter study: {args.runs} runs of `{args.scene}` (`benchmarks/sweep.py`)",
        "",
        f"Measured {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
        f"{os.cpu_count()} cores; `python3 benchmarks/sweep.py --scene {args.scene} "
        f"{'' if args.key is None else '--key ' + args.key + ' '}--runs {args.runs} --workers "
        f"{' '.join(map(str, args.workers))}{' --dask' if args.dask else ''}"
        f"{' --dataset-format ' + ' '.join(args.dataset_format) if not args.no_fields else ''}`."
        " Each run: "
        f"{rows[0][1]['steps']} steps, "
        + (
            "the fat layer's E from 2e3 to 8e3 Pa."
            if args.key is None
            else f"`{args.key}` from 5e4 to 2e5 Pa."
        ),
        "",
        "| executor | workers | start-up s | study s | runs/min | runs/min with start-up "
        "| run wall s | run solve s | build + setup s | rest / solve | study overhead s/run "
        "| load before -> after |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |",
    ]
    for name, r in rows:
        lines.append(
            f"| {name} | {r['workers']} | {r['start_s']:.2f} | {r['study_s']:.2f} "
            f"| {r['runs_per_min']:.0f} | {r['runs_per_min_with_start']:.0f} "
            f"| {r['run_wall_s']:.3f} | {r['run_solve_s']:.3f} "
            f"| {r['run_build_s']:.3f} + {r['run_setup_s']:.3f} "
            f"| {100 * r['run_rest_share']:.0f} % "
            f"| {r['study_overhead_s']:.3f} | {r['load_before']} -> {r['load_after']} |"
        )
    for fields in datasets:
        lines += [
            "",
            f"Fields dataset (`--fields displacement --dataset-format "
            f"{fields['dataset_format']}`, {fields['workers']} workers): "
            f"{fields['fields_bytes'] / 1024:.1f} KiB per run, written in "
            f"{1e3 * fields['fields_write_s']:.1f} ms per run (median); every run read back by "
            f"`load_dataset` in {fields['read_all_s']:.2f} s; load {fields['load_before']} -> "
            f"{fields['load_after']}.",
        ]
    lines.append("")
    text = "\n".join(lines)
    print(text)
    if args.write:
        Path(args.write).write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
