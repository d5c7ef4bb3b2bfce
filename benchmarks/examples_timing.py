"""Run the shipped examples one at a time as a user would and record what each run shows.

Each example runs in a child process, ``tissuesim run NAME --out DIR/NAME`` (pictures drawn,
as ``tissuesim run NAME`` does; ``--no-render`` to skip them), timed from outside (the whole
command: import, scene, steps, output, pictures). From each run's summary.json it records the
steps, halved steps, Newton iterations, the split of the wall time, and per force (forces.csv
names) the largest magnitude and the last value, and per step extra (indentation depth, the
smallest gap, cut areas, pieces) the range. The results go to
``benchmarks/results/examples_timing.json`` under a label (``--label fast`` with
``pip install ".[test,fast]"``, ``--label plain`` with ``pip install .``), merged with the
labels already there; docs/examples.md's table and the scenes' ``# Runs in about`` lines are
checked against them by ``tests/scene/test_example_runtimes.py``.

    python3 benchmarks/examples_timing.py --label fast                 # all, this environment
    python3 benchmarks/examples_timing.py --label plain --python /tmp/plain/bin/python \\
        --only hertz_indentation organs_retraction_cut

One thread (OMP/MKL/OpenBLAS/Numba set to 1 unless already set). Run one example at a time on a
machine doing nothing else: the runs are the measurement.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results" / "examples_timing.json"
THREAD_VARS = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "NUMBA_NUM_THREADS",
    "TISSUESIM_CONTACT_THREADS",
)


def _norm(v) -> float:
    return math.sqrt(sum(float(x) ** 2 for x in v)) if isinstance(v, list) else abs(float(v))


def _ranges(steps: list[dict]) -> dict[str, list[float]]:
    """[min, max, last, the time it first reached its max] of every numeric per-step value in
    ``extra`` (not the linear solver's counts), ``min_distance``, ``active_pairs``, ``min_J``."""
    seen: dict[str, list[float]] = {}

    def walk(prefix: str, value, t: float) -> None:
        if isinstance(value, bool) or value is None:
            return
        if isinstance(value, (int, float)):
            if math.isfinite(value):
                r = seen.setdefault(prefix, [value, value, value, t])
                if value > r[1]:
                    r[1], r[3] = value, t
                r[0], r[2] = min(r[0], value), value
            return
        if isinstance(value, dict):
            for k, v in value.items():
                walk(f"{prefix}.{k}" if prefix else str(k), v, t)

    for step in steps:
        extra = dict(step.get("extra") or {})
        extra.pop("linear", None)
        extra.pop("forces", None)
        t = step.get("time", 0.0)
        walk("", extra, t)
        for key in ("min_distance", "active_pairs", "min_J"):
            if key in step:
                walk(key, step[key], t)
    return {k: [float(f"{x:.6g}") for x in v] for k, v in sorted(seen.items())}


def summarize(out: Path) -> dict:
    """What a finished run's summary.json shows, in a few figures."""
    summary = json.loads((out / "summary.json").read_text())
    steps = summary.get("steps") or []
    forces: dict[str, dict] = {}
    for step in steps:
        for name, value in ((step.get("extra") or {}).get("forces") or {}).items():
            norm = _norm(value)
            entry = forces.setdefault(name, {"max_norm": 0.0, "at_time": None})
            if norm > entry["max_norm"]:
                entry["max_norm"], entry["at_time"] = norm, step.get("time")
            if norm > 0:  # a condition of a step of its own reports zero outside it
                entry["min_nonzero_norm"] = min(entry.get("min_nonzero_norm", norm), norm)
                entry["last_nonzero"] = value
            entry["last"] = value
    for entry in forces.values():
        for key, value in entry.items():
            if key == "at_time" or value is None:
                continue
            if isinstance(value, list):
                entry[key] = [float(f"{x:.6g}") for x in value]
            else:
                entry[key] = float(f"{value:.6g}")
    iterations = [s.get("newton_iterations", 0) for s in steps]
    totals = summary.get("totals") or {}
    return {
        "status": summary.get("status"),
        "steps": len(steps),
        "halved_steps": sum(1 for s in steps if s.get("substeps", 1) > 1),
        "newton_iterations": {
            "mean": round(sum(iterations) / max(len(iterations), 1), 1),
            "max": max(iterations, default=0),
        },
        "end_time": steps[-1].get("time") if steps else None,
        "time_split_s": {k: round(v, 2) for k, v in (totals.get("time_split_s") or {}).items()},
        "forces": forces,
        "per_step": _ranges(steps),
    }


def run_one(python: str, name: str, out: Path, render: bool) -> dict:
    cmd = [python, "-m", "tissuesim", "run", name, "--out", str(out), "--quiet"]
    if not render:
        cmd.append("--no-render")
    load_before = os.getloadavg()[0]
    cpu_before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - start
    cpu_after = resource.getrusage(resource.RUSAGE_CHILDREN)
    # the child's CPU time (user + system): one thread, so on a quiet machine the wall time is
    # about this; on a shared one the wall time grows with the others' load and this does not
    cpu = sum(getattr(cpu_after, f) - getattr(cpu_before, f) for f in ("ru_utime", "ru_stime"))
    # the machine's 1-minute load average before and after: another job running beside the
    # example shows here (the example itself adds about 1)
    load = [round(load_before, 1), round(os.getloadavg()[0], 1)]
    if proc.returncode != 0:
        return {
            "wall_s": round(wall, 1),
            "cpu_s": round(cpu, 1),
            "load": load,
            "error": proc.stderr.strip()[-2000:],
        }
    return {
        "wall_s": round(wall, 1),
        "cpu_s": round(cpu, 1),
        "load": load,
        "render": render,
        **summarize(out),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--label", required=True, help="fast or plain (the install)")
    parser.add_argument("--python", default=sys.executable, help="the install's interpreter")
    parser.add_argument("--only", nargs="*", help="these examples (default: all)")
    parser.add_argument("--out", type=Path, help="output folder (default: a temporary one)")
    parser.add_argument("--no-render", action="store_true", help="draw no pictures")
    parser.add_argument("--results", type=Path, default=RESULTS)
    parser.add_argument(
        "--resummarize",
        action="store_true",
        help="run nothing: read the figures again from the runs' folders under --out",
    )
    parser.add_argument("--machine", default=f"{os.cpu_count()}-core {platform.machine()}")
    args = parser.parse_args(argv)
    for var in THREAD_VARS:
        os.environ.setdefault(var, "1")
    names = args.only or json.loads(
        subprocess.run(
            [
                args.python,
                "-c",
                "from tissuesim.scene.examples import list_examples as l; "
                "import json; print(json.dumps(l()))",
            ],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    )
    base = args.out or Path(tempfile.mkdtemp(prefix="examples_timing_"))
    results = json.loads(args.results.read_text()) if args.results.exists() else {}
    label = results.setdefault(args.label, {"examples": {}})
    label["machine"] = f"{args.machine}, one thread ({', '.join(THREAD_VARS)} = 1)"
    label["python"] = args.python
    if args.resummarize:
        for name in names:
            if name in label["examples"] and (base / name / "summary.json").exists():
                kept = {k: label["examples"][name][k] for k in ("wall_s", "cpu_s", "load", "date")}
                render = label["examples"][name].get("render", True)
                label["examples"][name] = {**kept, "render": render, **summarize(base / name)}
        args.results.write_text(json.dumps(results, indent=1, sort_keys=True) + "\n")
        return 0
    for name in names:
        print(f"{name} ...", end=" ", flush=True)
        record = run_one(args.python, name, base / name, not args.no_render)
        record["date"] = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
        label["examples"][name] = record
        print(
            f"{record['wall_s']} s (CPU {record['cpu_s']} s)", record.get("error", ""), flush=True
        )
        args.results.parent.mkdir(parents=True, exist_ok=True)
        args.results.write_text(json.dumps(results, indent=1, sort_keys=True) + "\n")
    print(f"written: {args.results}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
