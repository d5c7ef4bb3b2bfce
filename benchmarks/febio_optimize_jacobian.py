"""The Jacobian of a FEBio optimisation's residuals from the run's sensitivities against
central differences of whole runs, at the task's start (issue 44).

    python3 benchmarks/febio_optimize_jacobian.py --suite TestSuite [--task op01 --model oi01]

Prints the objective at the start and, per parameter, the largest difference over the
largest derivative (relative step 1e-5 of the parameter).
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

from tissuesim.febio.optimize.model import ModelBuilder
from tissuesim.febio.optimize.run import _Objective
from tissuesim.febio.optimize.task import read_optimize


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, required=True, help="TestSuite root or Verify")
    parser.add_argument("--task", default="op01")
    parser.add_argument("--model", default="oi01")
    args = parser.parse_args()
    verify = args.suite / "Verify" if (args.suite / "Verify").is_dir() else args.suite
    warnings.simplefilter("ignore")
    task = read_optimize(verify / f"{args.task}.feb")
    builder = ModelBuilder(verify / f"{args.model}.feb", task)
    try:
        objective = _Objective(task, builder, "sensitivities")
        a = np.array([p.initial for p in task.parameters])
        r, J = objective._residuals(a, True)
        print(f"{args.task} on {args.model}: objective {r @ r:.6g} at {a}")
        for i, p in enumerate(task.parameters):
            d = 1e-5 * abs(a[i])
            up, down = a.copy(), a.copy()
            up[i] += d
            down[i] -= d
            fd = (objective._residuals(up, False)[0] - objective._residuals(down, False)[0]) / (
                2 * d
            )
            worst = np.abs(J[:, i] - fd).max() / np.abs(fd).max()
            print(f"{p.name}: largest difference / largest derivative {worst:.1e}")
    finally:
        builder.close()


if __name__ == "__main__":
    main()
