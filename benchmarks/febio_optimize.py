"""FEBio's optimisation models of its verification suite (``Verify/op*.feb``, each run on its
model ``oi*.feb`` as the suite runs it: ``febio4 -i oiNN.feb -s opNN.feb``) run by tissuesim
(``tissuesim run opNN.feb --model oiNN.feb``), against FEBio's recorded final objective
(``code/linuxGoldStandards.py``).

    python benchmarks/febio_optimize.py --suite TestSuite [--gold FILE] [--out STEM]
        [--gradients sensitivities|differences] [--febio-solver] [--only 'op04|op06']
        [--timeout 900]

Writes STEM.csv and STEM.md (default benchmarks/results/febio_optimize): per model the
status (ran, refused with its one line, failed), the parameters found, the final objective
beside FEBio's, the major iterations, the runs (tissuesim: one differentiated run per
evaluation; FEBio's recorded "Total iterations", its model solves: one per evaluation and one
more per parameter) and the wall time. Each
model runs in its own process (a timeout kills it). A fit counts as FEBio's when its objective
is within 1e-3 of FEBio's, or when both fits leave a relative misfit sqrt(objective / sum of
the data's squares) below 1e-5: a noise-free data set's objective at its minimum is then the
two solvers' round-off and stopping points, not the fit.
"""

from __future__ import annotations

import argparse
import csv
import json
import multiprocessing as mp
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from febio_suite import read_gold  # noqa: E402

FIELDS = ("model", "status", "message", "parameters", "objective", "febio_objective",
          "rel_difference", "misfit", "febio_misfit", "matched", "lower", "iterations",
          "runs", "febio_runs", "wall_s")  # fmt: skip


def run_one(opt: Path, model: Path, gradients: str, febio_solver: bool, queue) -> None:
    import warnings

    import numpy as np

    from tissuesim.errors import InputError, RunError
    from tissuesim.febio.optimize import read_optimize, run_optimize

    out = {"status": "", "message": ""}
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            task = read_optimize(opt)
            fit = run_optimize(task, model, gradients=gradients, febio_solver=febio_solver)
        data = fit.measured
        out.update(status="ran", parameters=json.dumps(fit.parameters), objective=fit.objective,
                   iterations=fit.iterations, runs=fit.runs,
                   data_squares=float(np.sum(np.asarray(data) ** 2)))  # fmt: skip
    except InputError as exc:
        out.update(status="refused", message=" ".join(str(exc).split()))
    except RunError as exc:
        out.update(status="failed", message=" ".join(str(exc).split()))
    except Exception as exc:  # noqa: BLE001 - a crash is a result
        out.update(status="crashed", message=f"{type(exc).__name__}: {exc}"[:300])
    out["wall_s"] = time.perf_counter() - start
    queue.put(out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, required=True,
                        help="the TestSuite checkout, or a folder of its .feb files")  # fmt: skip
    parser.add_argument("--gold", type=Path, help="gold-standard file (default: the suite's)")
    parser.add_argument("--out", default=str(HERE / "results" / "febio_optimize"))
    parser.add_argument("--gradients", default="sensitivities",
                        choices=("sensitivities", "differences"))  # fmt: skip
    parser.add_argument("--only", help="a regular expression of model names")
    parser.add_argument("--febio-solver", action="store_true",
                        help="the model's steps by FEBio's quasi-Newton (run's flag)")  # fmt: skip
    parser.add_argument("--timeout", type=float, default=900.0)
    parser.add_argument("--at", default="", help="what the report's header says was measured")
    args = parser.parse_args()
    import re

    folder = args.suite / "Verify" if (args.suite / "Verify").is_dir() else args.suite
    gold = read_gold(args.gold or args.suite / "code" / "linuxGoldStandards.py")
    rows = []
    for opt in sorted(folder.glob("op*.feb")):
        name = opt.stem
        if args.only and not re.fullmatch(args.only, name):
            continue
        model = folder / f"oi{name[2:]}.feb"
        queue = mp.get_context("spawn").Queue()
        proc = mp.get_context("spawn").Process(target=run_one,
                                               args=(opt, model, args.gradients,
                                                     args.febio_solver, queue))  # fmt: skip
        proc.start()
        proc.join(args.timeout)
        if proc.is_alive():
            proc.kill()
            out = {"status": "timeout", "message": f"still running after {args.timeout:g} s",
                   "wall_s": args.timeout}  # fmt: skip
        else:
            lost = {"status": "crashed", "message": "no output"}
            out = queue.get() if not queue.empty() else lost
        entry = gold.get(name)
        out["model"] = name
        if entry is not None:
            out["febio_objective"] = float(entry[1])
            out["febio_runs"] = int(entry[2])  # FEBio's "Total iterations": its model solves
        if out["status"] == "ran" and entry is not None:
            ours, theirs = out["objective"], out["febio_objective"]
            out["rel_difference"] = ours / theirs - 1.0 if theirs else None
            squares = out.pop("data_squares")
            out["misfit"] = (ours / squares) ** 0.5 if squares else None
            out["febio_misfit"] = (theirs / squares) ** 0.5 if squares else None
            close = theirs and abs(ours / theirs - 1.0) <= 1e-3
            floor = squares and max(out["misfit"], out["febio_misfit"]) <= 1e-5
            out["matched"] = bool(close or floor)
            out["lower"] = bool(ours < theirs)
        rows.append(out)
        print(f"{name}: {out['status']} {out.get('objective', '')} (FEBio "
              f"{out.get('febio_objective', '')}) {out['wall_s']:.1f} s {out['message'][:90]}",
              flush=True)  # fmt: skip
    stem = Path(args.out)
    stem.parent.mkdir(parents=True, exist_ok=True)
    with open(f"{stem}.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    write_md(rows, Path(f"{stem}.md"), args)
    return 0


def _verdict(r: dict) -> str:
    if r["status"] != "ran":
        return ""
    if r.get("matched"):
        return "yes"
    return "no (lower)" if r.get("lower") else "no"


def _g(v, fmt=".4g") -> str:
    return "" if v in (None, "") else format(v, fmt)


def _short(name: str) -> str:
    """A parameter's short label: its last name, a curve point's curve and index too
    (``tau1[1].y`` for ``fem.material('tissue').relaxation.tau1.points[1].y``)."""
    parts = name.split(".")
    if len(parts) >= 3 and parts[-2].startswith("points["):
        return f"{parts[-3]}{parts[-2][len('points') :]}.{parts[-1]}"
    return parts[-1]


def write_md(rows: list[dict], path: Path, args) -> None:
    ran = [r for r in rows if r["status"] == "ran"]
    matched = [r for r in ran if r.get("matched")]
    lines = [
        "# FEBio's optimisation models",
        "",
        f"`python benchmarks/febio_optimize.py --suite TestSuite --gradients {args.gradients}"
        + (" --febio-solver`" if args.febio_solver else "`")
        + (f" ({args.at})" if args.at else ""),
        "",
        f"{len(rows)} models: {len(ran)} ran, {len(matched)} of them FEBio's fit (objective "
        "within 1e-3 of FEBio's, or both misfits sqrt(objective / sum of data squared) below "
        "1e-5), "
        + ", ".join(f"{sum(r['status'] == s for r in rows)} {s}"
                    for s in ("refused", "failed", "timeout", "crashed")),
        "",
        "Runs: tissuesim's model runs (FEBio's recorded \"Total iterations\", its model "
        "solves; the test script keeps only the last digit of a count of 10 or more). The model "
        "itself is solved by "
        + ("FEBio's quasi-Newton (`--febio-solver`)." if args.febio_solver
           else "tissuesim's Newton (no `--febio-solver`).")
        + " Wall times on a 2-core machine.",
        "",
        "| model | status | parameters found | objective | FEBio's | misfit | FEBio's misfit | "
        "FEBio's fit | major iterations | runs (FEBio's) | wall (s) | message |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]  # fmt: skip
    for r in rows:
        params = ""
        if r.get("parameters"):
            params = ", ".join(f"{_short(k)} = {v:.6g}"
                               for k, v in json.loads(r["parameters"]).items())  # fmt: skip
        lines.append(
            f"| {r['model']} | {r['status']} | {params} | {_g(r.get('objective'))} | "
            f"{_g(r.get('febio_objective'))} | {_g(r.get('misfit'), '.1e')} | "
            f"{_g(r.get('febio_misfit'), '.1e')} | "
            f"{_verdict(r)} | "
            f"{r.get('iterations', '')} | "
            f"{r.get('runs', '')} ({r.get('febio_runs', '')}) | {r['wall_s']:.1f} | "
            f"{r['message'][:160]} |"
        )
    path.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
