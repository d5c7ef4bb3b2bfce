"""Time per Newton iteration of ``Simulation.step`` on one large FEM body, for comparing two
versions of tissuesim side by side (the one-body case must cost what it cost before bodies
were unified). Uses only the public API both versions share.

    python3 benchmarks/step_overhead.py                        # the installed tissuesim
    PYTHONPATH=/path/to/old/src python3 benchmarks/step_overhead.py   # another checkout

Each run: a 2D square of 100,352 triangles and a 3D box of 105,456 tetrahedra (the sizes of
``run.py``), neo-Hookean, Backward Euler under gravity, clamped at x = 0; the first step (JIT,
analysis) is not timed, then ``--steps`` steps; the figure is the median over steps of
wall_time_s / newton_iterations. One thread (set before NumPy loads).
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402

import numpy as np  # noqa: E402

import tissuesim as ts  # noqa: E402


def measure(dim: int, steps: int, divisions: int | None = None) -> dict:
    if dim == 2:
        n = divisions or 224
        mesh = ts.rectangle(lower=(0, 0), upper=(1, 1), divisions=(n, n))
        g = (0.0, -9.81)
    else:
        n = divisions or 26
        mesh = ts.box(lower=(0, 0, 0), upper=(1, 1, 1), divisions=(n, n, n))
        g = (0.0, -9.81, 0.0)
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, time_step=0.01)
    sim.add_dirichlet(np.flatnonzero(mesh.points[:, 0] == 0.0))
    sim.add_gravity(g)
    sim.step()  # compile, analyse, build
    per_iteration, records = [], []
    for _ in range(steps):
        r = sim.step()
        records.append(r)
        if r.newton_iterations:
            per_iteration.append(r.wall_time_s / r.newton_iterations)
    return {
        "dim": dim,
        "elements": mesh.n_cells,
        "dofs": mesh.points.size,
        "tissuesim": ts.__file__,
        "solver": records[-1].linear_solver,
        "newton_iterations": [r.newton_iterations for r in records],
        "median_s_per_iteration": statistics.median(per_iteration),
        "median_s_per_step": statistics.median(r.wall_time_s for r in records),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dims", type=int, nargs="*", default=[2, 3])
    parser.add_argument("--steps", type=int, default=5)
    parser.add_argument(
        "--divisions",
        type=int,
        help="cells per side (default 224 in 2D, 26 in 3D); a small "
        "mesh shows the per-step bookkeeping instead of the solve",
    )
    args = parser.parse_args()
    for dim in args.dims:
        print(json.dumps(measure(dim, args.steps, args.divisions)), flush=True)


if __name__ == "__main__":
    main()
