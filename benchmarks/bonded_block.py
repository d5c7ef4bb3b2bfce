"""Bonded compression of a block: the reaction force against mesh size for P1, P1 mean
dilatation, P2 and P2 mean dilatation at nearly incompressible Poisson ratios.

The unit cube (m) of neo-Hookean tissue (mu = 1000 Pa) is clamped at z = 0; the face z = 1 is
clamped in x and y and moved down by 0.2 m (20 % compression) in ``--steps`` quasistatic steps.
The quantity is the vertical force on the top face (N; the block pushes back upwards, so the
force the support applies is negative), summed from the step's reactions.

    python3 benchmarks/bonded_block.py --nu 0.45 0.49 --p1 4 8 12 16 --p2 2 4 6 8
writes benchmarks/results/bonded_block_last_run.md (the curated table: bonded_block.md).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from tissuesim import Simulation  # noqa: E402
from tissuesim.materials.registry import make_material  # noqa: E402
from tissuesim.mesh import box  # noqa: E402
from tissuesim.solve.newton import NewtonOptions  # noqa: E402

MU = 1000.0


def compress(n: int, order: int, formulation: str, nu: float, steps: int) -> dict:
    mesh = box(divisions=(n, n, n), order=order)
    material = make_material("neo_hookean", youngs_modulus=2 * MU * (1 + nu), poisson_ratio=nu)
    sim = Simulation(
        integrator="quasistatic", time_step=1.0 / steps, newton=NewtonOptions(max_iterations=60)
    )
    body = sim.add_body("block", mesh, material, density=1.0, formulation=formulation)
    body.fix(mesh.point_sets["zmin"], name="bottom")
    body.add_dirichlet(
        mesh.point_sets["zmax"], lambda X, t: np.array([0.0, 0.0, -0.2 * min(t, 1.0)]), name="top"
    )
    start, iterations = time.perf_counter(), 0
    for _ in range(steps):
        record = sim.step()
        iterations += record.newton_iterations
    return {
        "cells": mesh.n_cells,
        "dofs": body.model.n_dofs,
        "force": float(sim.forces()["top"][2]),
        "iterations": iterations,
        "wall_s": time.perf_counter() - start,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nu", type=float, nargs="+", default=[0.45, 0.49])
    ap.add_argument("--p1", type=int, nargs="+", default=[4, 8, 12, 16], help="P1 divisions")
    ap.add_argument("--p2", type=int, nargs="+", default=[2, 4, 6, 8], help="P2 divisions")
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/bonded_block_last_run.md"))
    args = ap.parse_args(argv)
    lines = [
        "# Bonded block compressed 20 %: force on the top face (N)",
        "",
        f"`python3 benchmarks/bonded_block.py --nu {' '.join(map(str, args.nu))} --p1 "
        f"{' '.join(map(str, args.p1))} --p2 {' '.join(map(str, args.p2))} --steps {args.steps}`",
        "",
    ]
    variants = [
        ("P1", 1, "displacement", args.p1),
        ("P1 mean dilatation", 1, "mean_dilatation", args.p1),
        ("P2", 2, "displacement", args.p2),
        ("P2 mean dilatation", 2, "mean_dilatation", args.p2),
    ]
    for nu in args.nu:
        lines += [f"## nu = {nu}", "", "| variant | n | cells | DOFs | F_z (N) | Newton | s |"]
        lines.append("|---|---|---|---|---|---|---|")
        for label, order, form, sizes in variants:
            for n in sizes:
                r = compress(n, order, form, nu, args.steps)
                row = (
                    f"| {label} | {n} | {r['cells']} | {r['dofs']} | {r['force']:.3f} | "
                    f"{r['iterations']} | {r['wall_s']:.1f} |"
                )
                print(f"nu {nu}: {row}", flush=True)
                lines.append(row)
        lines.append("")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
