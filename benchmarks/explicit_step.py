"""Time per explicit (symplectic Euler) step on one large FEM body, for comparing two versions
of tissuesim side by side (issue 21: the unified step had made explicit steps slower than at
1e66a1d). Uses only the public API both versions share.

    python3 benchmarks/explicit_step.py                            # the installed tissuesim
    PYTHONPATH=/path/to/old/src python3 benchmarks/explicit_step.py  # another checkout

A 2D square of 100,352 triangles and a 3D box of 105,456 tetrahedra, neo-Hookean
(E = 1e4 Pa, nu = 0.3, 1000 kg/m^3), clamped at x = 0 (a named support: its reaction is
reported every step), gravity, lumped mass, h = 1e-4 s (stable); the first steps
(JIT) are not timed, then ``--steps`` steps; the figures are the median wall time per step
and vertex updates per second (vertices / median step time). One thread.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

import tissuesim as ts  # noqa: E402


def measure(dim: int, steps: int) -> dict:
    if dim == 2:
        mesh = ts.rectangle(lower=(0, 0), upper=(1, 1), divisions=(224, 224))
        g = (0.0, -9.81)
    else:
        mesh = ts.box(lower=(0, 0, 0), upper=(1, 1, 1), divisions=(26, 26, 26))
        g = (0.0, -9.81, 0.0)
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    h = 1e-4  # s, well below the stability limit of both meshes (about 3e-3 s)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="symplectic_euler", time_step=h)
    sim.add_dirichlet(np.flatnonzero(mesh.points[:, 0] == 0.0))
    sim.add_gravity(g)
    for _ in range(3):
        sim.step()  # compile, build
    walls = []
    for _ in range(steps):
        start = time.perf_counter()
        sim.step()
        walls.append(time.perf_counter() - start)
    median = statistics.median(walls)
    return {
        "dim": dim,
        "elements": mesh.n_cells,
        "vertices": mesh.n_points,
        "tissuesim": ts.__file__,
        "median_ms_per_step": 1e3 * median,
        "vertex_updates_per_s": mesh.n_points / median,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dims", type=int, nargs="*", default=[2, 3])
    parser.add_argument("--steps", type=int, default=30)
    args = parser.parse_args()
    for dim in args.dims:
        print(json.dumps(measure(dim, args.steps)), flush=True)


if __name__ == "__main__":
    main()
