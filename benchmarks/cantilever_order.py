"""The 0.4 x 0.4 x 2 m cantilever under a 1 N tip load: deflection and cost against mesh size
for P1 and P2 tetrahedra (and their mean-dilatation variants with --formulations).

Small-strain linear elasticity (E = 1e5 Pa, ``--nu``), clamped at x = 0, a dead traction of
-6.25 Pa (z) on the end face x = 2. The deflection is the end face's mean u_z (its
area-weighted mean, work-conjugate to the uniform traction: f . u / |F|). The error is
against ``--reference`` (FElupe, Hex27, converged: benchmarks/results/felupe_reference.md) when
given, else against the finest P2 value. Time per Newton iteration is the step's wall time over
its iterations (assembly, factorisation, line search).

    python3 benchmarks/cantilever_order.py --nu 0 --p1 2 4 8 12 --p2 1 2 4 6
writes benchmarks/results/cantilever_order_last_run.md (the curated table: cantilever_order.md).
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
from tissuesim.energies.loads import Traction  # noqa: E402
from tissuesim.materials.registry import make_material  # noqa: E402
from tissuesim.mesh import box  # noqa: E402
from tissuesim.solve.newton import NewtonOptions  # noqa: E402

TRACTION = -1.0 / 0.16  # Pa: 1 N over the 0.4 x 0.4 end face


def deflect(n: int, order: int, nu: float, formulation: str = "displacement") -> dict:
    mesh = box((0, 0, 0), (2.0, 0.4, 0.4), (5 * n, n, n), order=order)
    material = make_material("linear", youngs_modulus=1e5, poisson_ratio=nu)
    sim = Simulation(
        integrator="quasistatic", time_step=1.0, newton=NewtonOptions(gradient_tolerance=1e-10)
    )
    body = sim.add_body("beam", mesh, material, density=1.0, formulation=formulation)
    body.fix(mesh.point_sets["xmin"], name="clamp")
    end = mesh.facet_sets["xmax"]
    body.add_traction(end, [0.0, 0.0, TRACTION])
    start = time.perf_counter()
    record = sim.step()
    wall = time.perf_counter() - start
    unit = Traction(end, lambda X, t: np.broadcast_to([0.0, 0.0, 1.0], X.shape))
    weights = unit.nodal_forces(body.model, 0.0)[:, 2]  # int N^a dA over the end face
    mean_uz = float(weights @ sim.displacement[:, 2] / weights.sum())
    return {
        "cells": mesh.n_cells,
        "dofs": body.model.n_dofs,
        "nnz": body.model.pattern.nnz,
        "mean_uz": mean_uz,
        "iterations": record.newton_iterations,
        "per_iteration_s": wall / max(record.newton_iterations, 1),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nu", type=float, nargs="+", default=[0.0])
    ap.add_argument("--p1", type=int, nargs="+", default=[2, 4, 8, 12])
    ap.add_argument("--p2", type=int, nargs="+", default=[1, 2, 4, 6])
    ap.add_argument("--formulations", nargs="+", default=["displacement"])
    ap.add_argument("--reference", type=float, nargs="*", default=None, help="per nu, m (< 0)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/cantilever_order_last_run.md"))
    args = ap.parse_args(argv)
    lines = [
        "# Cantilever 0.4 x 0.4 x 2 m, 1 N tip load: mean end-face deflection",
        "",
        f"`python3 benchmarks/cantilever_order.py {' '.join(argv or sys.argv[1:])}`",
        "",
    ]
    for k, nu in enumerate(args.nu):
        rows = []
        for form in args.formulations:
            for order, sizes in ((1, args.p1), (2, args.p2)):
                for n in sizes:
                    r = deflect(n, order, nu, form)
                    rows.append((order, form, n, r))
                    print(f"nu {nu} P{order} {form} n={n}: {r}", flush=True)
        if args.reference:
            ref = args.reference[k]
            source = "FElupe Hex27, converged"
        else:
            ref = min((r for o, f, n, r in rows if o == 2), key=lambda r: -r["dofs"])["mean_uz"]
            source = "the finest P2 run"
        lines += [
            f"## nu = {nu} (reference {ref:.6e} m, {source})",
            "",
            "| element | formulation | divisions | cells | DOFs | Hessian nnz | mean u_z (m) | "
            "error | s / Newton iteration |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for order, form, n, r in rows:
            lines.append(
                f"| P{order} | {form} | {5 * n} x {n} x {n} | {r['cells']} | {r['dofs']} | "
                f"{r['nnz']} | {r['mean_uz']:.6e} | {100 * (r['mean_uz'] / ref - 1):+.2f} % | "
                f"{r['per_iteration_s']:.3f} |"
            )
        lines.append("")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
