"""Figures for the notes' example problem: both readings, several resolutions.

    python benchmarks/course_problem.py --divisions 16 64 [--reading stretch literal]
        [--solver auto] [--json out.json]

For each run: elements, steps, every step converged, smallest J over the run, Newton
iterations per step (mean / median / max), steps that needed halving, wall time per step.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
import tomllib

import numpy as np
from threadpoolctl import threadpool_limits

from tissuesim.cli import example_path
from tissuesim.errors import ConvergenceError
from tissuesim.scene.loader import build_scene


def run(reading: str, divisions: int, solver: str) -> dict:
    data = tomllib.loads(example_path(f"course_{reading}").read_text())
    data["mesh"]["divisions"] = [divisions, divisions]
    data.setdefault("newton", {})["linear_solver"] = solver
    sim = build_scene(data, name=f"{reading}_{divisions}").simulation
    steps = data["run"]["steps"]
    start = time.perf_counter()
    status = "completed"
    try:
        records = [sim.step() for _ in range(steps)]
    except ConvergenceError as exc:
        records, status = sim.history, f"failed: {exc}"
    wall = time.perf_counter() - start
    iters = np.array([r.newton_iterations for r in records])
    return {
        "reading": reading,
        "divisions": divisions,
        "elements": sim.mesh.n_cells,
        "steps": len(records),
        "end_time": sim.time,
        "status": status,
        "all_converged": status == "completed",
        "min_J": float(min(r.min_J for r in records)),
        "time_of_min_J": float(min(records, key=lambda r: r.min_J).time),
        "newton_mean": float(iters.mean()),
        "newton_median": float(np.median(iters)),
        "newton_max": int(iters.max()),
        "halved_steps": int(sum(r.substeps > 1 for r in records)),
        "seconds_per_step": wall / max(len(records), 1),
        "linear_solver": records[-1].linear_solver if records else None,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--divisions", type=int, nargs="+", default=[16, 64])
    parser.add_argument("--reading", nargs="+", default=["stretch", "literal"])
    parser.add_argument("--solver", default="auto")
    parser.add_argument("--json")
    args = parser.parse_args()
    rows = []
    with threadpool_limits(1):
        for reading in args.reading:
            for n in args.divisions:
                rows.append(run(reading, n, args.solver))
                r = rows[-1]
                print(
                    f"| {r['reading']} | {r['divisions']}x{r['divisions']} | {r['elements']} | "
                    f"{r['steps']} | {r['all_converged']} | {r['min_J']:.3f} "
                    f"(t = {r['time_of_min_J']:.2f}) | {r['newton_mean']:.1f} / "
                    f"{r['newton_median']:.0f} / {r['newton_max']} | {r['halved_steps']} | "
                    f"{r['seconds_per_step']:.3f} s | {r['linear_solver']} |",
                    flush=True,
                )
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"machine": platform.platform(), "runs": rows}, f, indent=2)


if __name__ == "__main__":
    main()
