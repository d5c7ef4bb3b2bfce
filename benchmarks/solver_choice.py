"""Which linear solver "auto" should take without PARDISO or CHOLMOD (pip alone, or pip + pyamg).

For 3D cubes of increasing size and 2D squares, each solver (SciPy SuperLU, AMG-CG, Jacobi-CG)
factorises / solves the same Newton matrix (``run.py``'s problem and ``worker_solve``), each in
its own single-threaded subprocess; the figure is the median time per iteration with the
analysis (ordering, AMG hierarchy) reused, plus the first solve with it. The thresholds in
``solve/linear.py`` (``SPLU_MAX_DOFS_3D``) come from this table.

    python3 benchmarks/solver_choice.py                 # sizes 6 9 12 15 18 (3D), 3 repeats
    python3 benchmarks/solver_choice.py --sizes3d 8 12 --repeat 1
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from run import spawn  # noqa: E402  (the benchmark suite's isolated single-threaded workers)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes3d", type=int, nargs="*", default=[6, 9, 12, 15, 18])
    parser.add_argument("--sizes2d", type=int, nargs="*", default=[])
    parser.add_argument("--solvers", nargs="*", default=["splu", "amg", "cg"])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    rows = []
    for dim, sizes in ((3, args.sizes3d), (2, args.sizes2d)):
        for n in sizes:
            for solver in args.solvers:
                r = spawn("solve", dim=dim, n=n, solver_name=solver, repeat=args.repeat)
                rows.append((dim, n, solver, r))
                if "error" in r:
                    print(f"{dim}D n={n} {solver}: {r['error']}", flush=True)
                    continue
                its = r["cg_iterations_per_solve"]
                print(
                    f"{dim}D n={n:3d} {solver:5s} first {r['first_s']:8.3f} s  per iteration "
                    f"{r['per_iteration_s']:8.3f} s  residual {r['residual']:.1e}"
                    + (f"  CG its {its:.0f}" if its else "")
                    + f"  peak {r['peak_mb']:.0f} MB",
                    flush=True,
                )


if __name__ == "__main__":
    main()
