"""The contact-free implicit step at its limit (issue 40): a step of the palpation organ
(``benchmarks/palpation.py``, Backward Euler at h = 1/30 s, gravity, PARDISO with its factor
kept) against one assembly (energy, gradient and Hessian) plus one back-solve of the same
matrix, measured in the same run; and the interactive mode's free motion (one gradient and one
back-solve on the kept factor, ``time/contact_step.py lagged_free_motion``).

    python3 benchmarks/free_step.py                   # 1e4 tetrahedra, 20 steps
    python3 benchmarks/free_step.py --divisions 8 17
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def measure(divisions: int, steps: int) -> dict:
    import numpy as np
    from palpation import organ

    from tissuesim.time.contact_step import lagged_free_motion

    sim = organ(divisions)
    for _ in range(3):  # compile, factorise
        sim.step()
    s = sim.system
    solver = sim._linear_solver()
    walls, assemble, solve, lagged, iterations = [], [], [], [], []
    for _ in range(steps):
        start = time.perf_counter()
        record = sim.step()
        walls.append(time.perf_counter() - start)
        iterations.append(record.newton_iterations)
        energies = s.last_step_energies
        x = sim.state.x
        start = time.perf_counter()
        acc = s.evaluate(x, 2, False, energies)
        assemble.append(time.perf_counter() - start)
        g = np.asarray(acc.gradient)
        start = time.perf_counter()
        solver.direct.solve(g)
        solve.append(time.perf_counter() - start)
        start = time.perf_counter()
        lagged_free_motion(s, sim.state, sim.time_step, solver, True, energies, sim.time)
        lagged.append(time.perf_counter() - start)
    step, one = statistics.median(walls), statistics.median(assemble) + statistics.median(solve)
    return {
        "tetrahedra": int(sim.bodies["organ"].mesh.n_cells),
        "step_ms": 1e3 * step,
        "iterations": statistics.mean(iterations),
        "assembly_ms": 1e3 * statistics.median(assemble),
        "back_solve_ms": 1e3 * statistics.median(solve),
        "ratio": step / one,
        "lagged_free_motion_ms": 1e3 * statistics.median(lagged),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--divisions", type=int, nargs="+", default=[12])
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args()
    lines = [
        "| tetrahedra | step ms | Newton its / step | assembly ms | back-solve ms "
        "| step / (assembly + back-solve) | lagged free motion ms |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for divisions in args.divisions:
        r = measure(divisions, args.steps)
        lines.append(
            f"| {r['tetrahedra']:,} | {r['step_ms']:.1f} | {r['iterations']:.2f} | "
            f"{r['assembly_ms']:.2f} | {r['back_solve_ms']:.2f} | {r['ratio']:.1f} | "
            f"{r['lagged_free_motion_ms']:.1f} |"
        )
    text = (
        "# The contact-free step (benchmarks/free_step.py)\n\n"
        f"`python3 benchmarks/free_step.py {' '.join(sys.argv[1:])}`, one thread, medians of "
        f"{args.steps} steps.\n\n" + "\n".join(lines) + "\n"
    )
    (HERE / "results" / "free_step.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
