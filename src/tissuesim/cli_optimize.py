"""``tissuesim run OPTIMISATION.feb --model MODEL.feb --out DIR``: a FEBio optimisation file
(``<febio_optimize>``, FEBio's ``-s``) run on its model (FEBio's ``-i``) by
``febio/optimize/``; writes optimize.json and fit.csv to DIR and prints the report."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

__all__ = ["is_optimisation_file", "optimize_command"]


def is_optimisation_file(path: Path) -> bool:
    """Whether a .feb file's root element is <febio_optimize> (read from its first 4 kB)."""
    try:
        with open(path, "rb") as f:
            head = f.read(4096)
    except OSError:
        return False  # the model reader names the file and the reason
    return b"<febio_optimize" in head


def optimize_command(
    path: Path,
    model: str | None,
    out: str | None,
    quiet: bool,
    gradients: str = "sensitivities",
    febio_solver: bool = False,
) -> int:
    """Run the optimisation, write optimize.json and fit.csv together (both or neither)."""
    import numpy as np

    from tissuesim.errors import InputError
    from tissuesim.febio.optimize import read_optimize, run_optimize
    from tissuesim.io.atomic import atomic_outputs
    from tissuesim.io.manifest import prepare_directory

    if model is None:
        raise InputError(
            f"{path}: an optimisation file runs on a model: give it with --model MODEL.feb "
            "(FEBio: febio4 -i MODEL.feb -s OPTIMISATION.feb)"
        )
    task = read_optimize(path)
    directory = prepare_directory(out or Path("out") / Path(path).stem)
    log = None if quiet else (lambda line: print(f"tissuesim: {line}", file=sys.stderr))
    result = run_optimize(task, model, log=log, gradients=gradients, febio_solver=febio_solver)
    report = {
        "optimisation": str(path),
        "model": str(model),
        "method": task.method,
        "gradients": result.gradients,
        "febio_solver": febio_solver,
        "parameters": result.parameters,
        "std": result.std,
        "objective": result.objective,  # FEBio's "Final objective value"
        "major_iterations": result.iterations,
        "runs": result.runs,
        "converged": result.converged,
        "wall_time_s": result.wall_s,
        "history": result.history,
    }
    targets = [directory / "optimize.json", directory / "fit.csv"]
    with atomic_outputs(targets) as (json_tmp, csv_tmp):
        json_tmp.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
        with open(csv_tmp, "w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(["x", "measured", "simulated", "quantity"])
            for row in zip(result.x, result.measured, result.simulated, result.labels,
                           strict=True):  # fmt: skip
                w.writerow([repr(float(row[0])), repr(float(row[1])), repr(float(row[2])), row[3]])
    if not quiet:
        line = (f"tissuesim: final objective value {result.objective:.6g} after "
                f"{result.iterations} major iterations, {result.runs} runs")  # fmt: skip
        print(line, file=sys.stderr)
    report.pop("history")
    print(json.dumps({**report, "written": [str(t) for t in targets]}, indent=2))
    return 0 if np.isfinite(result.objective) else 1
