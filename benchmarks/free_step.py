"""The contact-free implicit step at its limit (issue 40): a step of the palpation organ
(``benchmarks/palpation.py``, Backward Euler at h = 1/30 s, gravity, PARDISO with its factor
kept) against one assembly (energy, gradient and Hessian) plus one back-solve of the same
matrix, measured in the same run; and the interactive mode's free motion (one gradient and one
back-solve on the kept factor, ``time/contact_step.py lagged_free_motion``).

The step's composition: evaluations per step by order (0 energy, 1 with the gradient, 2 with
the Hessian: Newton's matrices, the start's candidates, the line search, the record's energies),
back-solves and factorisations per step (the solver's counts), each timed alone on the same
matrix, and their sum against the step (the rest: Python, the state's update, reporting).

    python3 benchmarks/free_step.py                   # 1e4 tetrahedra, 20 steps
    python3 benchmarks/free_step.py --divisions 8 17
    python3 benchmarks/free_step.py --background      # the factor refreshed in a thread
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


def measure(divisions: int, steps: int, background: bool = False) -> dict:
    import numpy as np
    from palpation import organ

    from tissuesim.time.contact_step import lagged_free_motion

    sim = organ(divisions)
    if background:  # the kept factor refreshed in a thread (solve/reuse.py)
        from tissuesim.solve.reuse import ReusedFactorSolver

        sim.step()
        sim._solver = ReusedFactorSolver(sim._solver.direct, background=True)
    for _ in range(3):  # compile, factorise
        sim.step()
    s = sim.system
    solver = sim._linear_solver()
    walls, assemble, solve, lagged, iterations = [], [], [], [], []
    orders, linear = {0: 0, 1: 0, 2: 0}, {"back_solves": 0, "factorizations": 0}
    evaluate = s.evaluate

    def counted(x, order, *args, **kwargs):
        orders[order] += 1
        return evaluate(x, order, *args, **kwargs)

    for _ in range(steps):
        s.evaluate = counted
        start = time.perf_counter()
        record = sim.step()
        walls.append(time.perf_counter() - start)
        s.evaluate = evaluate
        iterations.append(record.newton_iterations)
        for key in linear:
            linear[key] += record.extra["linear"][key]
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
    x, energies = sim.state.x, s.last_step_energies
    cost = {}
    for order in (0, 1):
        times = []
        for _ in range(steps):
            start = time.perf_counter()
            s.evaluate(x, order, False, energies)
            times.append(time.perf_counter() - start)
        cost[order] = statistics.median(times)
    cost[2] = statistics.median(assemble)
    factor = []
    matrix = solver.factored_matrix
    for _ in range(3):
        start = time.perf_counter()
        solver.direct.factorize(matrix)
        factor.append(time.perf_counter() - start)
    per_step = {f"evaluations_{k}": v / steps for k, v in orders.items()}
    per_step.update({k: v / steps for k, v in linear.items()})
    modelled = (
        sum(cost[k] * per_step[f"evaluations_{k}"] for k in (0, 1, 2))
        + statistics.median(solve) * per_step["back_solves"]
        + statistics.median(factor) * per_step["factorizations"]
    )
    step, one = statistics.median(walls), statistics.median(assemble) + statistics.median(solve)
    return {
        "tetrahedra": int(sim.bodies["organ"].mesh.n_cells),
        "step_ms": 1e3 * step,
        "iterations": statistics.mean(iterations),
        "assembly_ms": 1e3 * statistics.median(assemble),
        "back_solve_ms": 1e3 * statistics.median(solve),
        "ratio": step / one,
        "lagged_free_motion_ms": 1e3 * statistics.median(lagged),
        **per_step,
        "energy_ms": 1e3 * cost[0],
        "gradient_ms": 1e3 * cost[1],
        "factorization_ms": 1e3 * statistics.median(factor),
        "modelled_ms": 1e3 * modelled,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--divisions", type=int, nargs="+", default=[12])
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument(
        "--background",
        action="store_true",
        help="refresh the kept factor in a thread while steps go on (2 cores)",
    )
    args = parser.parse_args()
    lines = [
        "| tetrahedra | step ms | Newton its / step | assembly ms | back-solve ms "
        "| step / (assembly + back-solve) | lagged free motion ms |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    rows = []
    for divisions in args.divisions:
        r = measure(divisions, args.steps, args.background)
        rows.append(r)
        lines.append(
            f"| {r['tetrahedra']:,} | {r['step_ms']:.1f} | {r['iterations']:.2f} | "
            f"{r['assembly_ms']:.2f} | {r['back_solve_ms']:.2f} | {r['ratio']:.1f} | "
            f"{r['lagged_free_motion_ms']:.1f} |"
        )
    lines += [
        "",
        "The step's composition (per step: evaluations by order, back-solves, factorisations; "
        "each kind timed alone on the last step's matrix; their sum against the step):",
        "",
        "| tetrahedra | energy (order 0) | gradient (1) | Hessian (2) | back-solves | "
        "factorisations | energy ms | gradient ms | factorisation ms | sum ms | step ms |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        lines.append(
            f"| {r['tetrahedra']:,} | {r['evaluations_0']:.2f} | {r['evaluations_1']:.2f} | "
            f"{r['evaluations_2']:.2f} | {r['back_solves']:.2f} | {r['factorizations']:.2f} | "
            f"{r['energy_ms']:.2f} | {r['gradient_ms']:.2f} | {r['factorization_ms']:.1f} | "
            f"{r['modelled_ms']:.1f} | {r['step_ms']:.1f} |"
        )
    text = (
        "# The contact-free step (benchmarks/free_step.py)\n\n"
        f"`python3 benchmarks/free_step.py {' '.join(sys.argv[1:])}`, one thread"
        + (" (and one that factorises)" if args.background else "")
        + ", medians of "
        f"{args.steps} steps.\n\n" + "\n".join(lines) + "\n"
    )
    name = "free_step_background.md" if args.background else "free_step.md"
    (HERE / "results" / name).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
