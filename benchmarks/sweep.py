"""What a parameter study costs (``tissuesim.sweep``, issue 43).

    python3 benchmarks/sweep.py [--scene two_blocks_tied] [--runs 40] [--workers 1 2] [--dask]
                                [--ray] [--repeat 3] [--dataset-format hdf5 zarr]
                                [--write benchmarks/results/sweep.md]

A study of ``--runs`` runs of a shipped contact-free scene (default ``two_blocks_tied``: two
glued blocks, 720 tetrahedra, 10 quasistatic steps; its fat layer's Young's modulus
varied over 2e3..8e3 Pa, evenly spaced), for each worker count on the default process pool
(one thread per worker; ``--dask``: also on tissuesim's Dask LocalCluster of as many worker
processes, ``executor_from_spec("dask-local")``, and on a LocalCluster with Dask's defaults;
``--ray``: on a local Ray cluster of as many CPUs, ``executor_from_spec("ray")``, its workers
started by Ray at the first tasks),
each ``--repeat`` times in interleaved rounds, the median round shown:

- runs per minute, with and without the pool's start-up (workers started, imports, warm-up);
- per run (median): the run's wall time in its worker, its steps' own solve time, the scene
  built (``build_scene``) and the model set up, and all but the solve against the solve time;
- the study's own overhead per run: workers x study wall time - the runs' summed wall times
  (dispatch, result files, the table, workers idle at the end), per run;
- ``--malloc-trim``: up to 40 runs in one process (a thread pool of one, after the warm-up)
  with glibc's ``MALLOC_TRIM_THRESHOLD_`` unset and at the 65536 Dask's nanny sets: the
  study's time, its minor page faults, the median run's solve;
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


def measure(kind: str, scene: str, runs: int, workers: int, key) -> dict:
    """One study on ``kind``'s executor, its start-up (the pool's workers, or the cluster,
    its client and the workers' warm-up) timed with it."""
    if kind == "process pool":
        return study(scene, runs, workers, None, key=key)
    if kind == "Ray (local)":  # as --executor ray: executor_from_spec("ray")
        from tissuesim.sweep.executors import close, executor_from_spec

        t0 = time.perf_counter()
        executor, owned = executor_from_spec("ray", workers)
        started = time.perf_counter() - t0
        try:
            row = study(scene, runs, workers, executor, key=key)
        finally:
            close(owned)
        row["start_s"] = started
        row["runs_per_min_with_start"] = 60 * runs / (started + row["study_s"])
        return row
    from distributed import Client, LocalCluster

    from tissuesim.sweep.executors import dask_local_cluster, warm_dask_workers

    t0 = time.perf_counter()
    if kind == "Dask LocalCluster":  # tissuesim's: executor_from_spec("dask-local")
        cluster = dask_local_cluster(workers)
        client = Client(cluster)
        warm_dask_workers(client)
    else:  # Dask's defaults; the workers prepare at their first run
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    with cluster, client:
        started = time.perf_counter() - t0
        row = study(scene, runs, workers, client.get_executor(), key=key)
    row["start_s"] = started
    row["runs_per_min_with_start"] = 60 * runs / (started + row["study_s"])
    return row


TRIM_CHILD = r"""
import resource, statistics, sys, tempfile, time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
import tissuesim
from tissuesim.sweep.runs import prepare_worker
prepare_worker()
with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(1) as pool:
    r0, t0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    runs = tissuesim.sweep(sys.argv[1], {sys.argv[2]: sys.argv[3]}, out=Path(tmp) / "s",
                           executor=pool, progress=False)
    t1, r1 = time.perf_counter(), resource.getrusage(resource.RUSAGE_SELF)
print(t1 - t0, r1.ru_minflt - r0.ru_minflt, statistics.median(r["solve_time_s"] for r in runs))
"""


def malloc_trim(scene: str, runs: int, key, repeat: int) -> list[str]:
    """The runs in one process (after its warm-up) with glibc's MALLOC_TRIM_THRESHOLD_ unset
    and at Dask's 65536, ``repeat`` interleaved rounds: wall time, minor page faults, the
    median run's solve time."""
    import subprocess
    import sys

    low, high = (2e3, 8e3) if key is None else (5e4, 2e5)
    args = [scene, key or "bodies[fat].material.youngs_modulus", f"{low}:{high}:{runs}"]
    found: dict[str, list] = {"unset": [], "65536": []}
    for _ in range(repeat):
        for name in found:
            env = {k: v for k, v in os.environ.items() if k != "MALLOC_TRIM_THRESHOLD_"}
            if name != "unset":
                env["MALLOC_TRIM_THRESHOLD_"] = name
            out = subprocess.run([sys.executable, "-c", TRIM_CHILD, *args], env=env,
                                 capture_output=True, text=True, check=True)  # fmt: skip
            found[name].append([float(v) for v in out.stdout.split()[-3:]])
    lines = [
        "",
        f"glibc's trim threshold ({runs} runs in one process after its warm-up, "
        f"{repeat} interleaved rounds; medians):",
        "",
        "| MALLOC_TRIM_THRESHOLD_ | study s | minor page faults | run solve s |",
        "| --- | ---: | ---: | ---: |",
    ]
    for name, rows in found.items():
        med = [statistics.median(r[i] for r in rows) for i in range(3)]
        lines.append(f"| {name} | {med[0]:.2f} | {med[1]:.0f} | {med[2]:.3f} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default="two_blocks_tied")
    parser.add_argument("--runs", type=int, default=40)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument(
        "--dask",
        action="store_true",
        help="also on tissuesim's Dask LocalCluster (dask-local) and on one with Dask's defaults",
    )
    parser.add_argument(
        "--ray", action="store_true", help="also on a local Ray cluster (--executor ray)"
    )
    parser.add_argument("--repeat", type=int, default=3, help="rounds; the median is shown")
    parser.add_argument(
        "--malloc-trim",
        action="store_true",
        help="also the runs in one process with glibc's MALLOC_TRIM_THRESHOLD_ unset and at "
        "Dask's 65536 (page faults, time)",
    )
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
    kinds = ["process pool"]
    if args.dask:
        kinds += ["Dask LocalCluster", "Dask LocalCluster, Dask's defaults"]
    if args.ray:
        kinds.append("Ray (local)")
    measured: dict[tuple[str, int], list[dict]] = {}
    for _ in range(args.repeat):  # interleaved rounds: a slow spell of the machine hits all
        for kind in kinds:
            for w in args.workers:
                row = measure(kind, args.scene, args.runs, w, args.key)
                measured.setdefault((kind, w), []).append(row)
                print(kind, row)
    # the median round of each (by its study time)
    rows = []
    for (kind, _), found in measured.items():
        found.sort(key=lambda r: r["study_s"])
        rows.append((kind, found[len(found) // 2]))
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
        f"{' --ray' if args.ray else ''} --repeat "
        f"{args.repeat}"
        f"{' --dataset-format ' + ' '.join(args.dataset_format) if not args.no_fields else ''}`."
        " Each run: "
        f"{rows[0][1]['steps']} steps, "
        + (
            "the fat layer's E from 2e3 to 8e3 Pa."
            if args.key is None
            else f"`{args.key}` from 5e4 to 2e5 Pa."
        )
        + f" Each row: the median of {args.repeat} interleaved rounds (by study time).",
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
    by = {(name, r["workers"]): r for name, r in rows}
    for kind in kinds[1:]:
        for w in args.workers:
            pool, other = by[("process pool", w)], by[(kind, w)]
            lines.append(
                f"\n{kind} against the process pool, {w} worker{'s' * (w > 1)}: runs/min "
                f"{other['runs_per_min'] / pool['runs_per_min']:.2f} (with start-up "
                f"{other['runs_per_min_with_start'] / pool['runs_per_min_with_start']:.2f}), "
                f"run solve time {other['run_solve_s'] / pool['run_solve_s']:.2f}."
            )
    if args.malloc_trim:
        lines += malloc_trim(args.scene, min(args.runs, 40), args.key, args.repeat)
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
