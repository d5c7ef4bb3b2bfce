"""What P2 and the mean-dilatation formulation cost: assembly time per element, the Hessian's
entries, memory and one factorisation, at the same nodes.

A unit cube as P1 (n^3 x 6 tetrahedra) and as P2 (n/2 divisions: the same (n + 1)^3 nodes and
DOFs, 8x fewer elements), neo-Hookean nu = 0.49, at a random deformed state; gradient +
Hessian assembly (medians of ``--repeats``) on the fused Numba path (displacement) and the
NumPy path, the sparsity pattern's entries, the model's resident arrays (kinematics, scatter
maps, pattern), and a SuperLU factorisation of the Hessian with z = 0 clamped.

    python3 benchmarks/element_costs.py --divisions 16 --repeats 5
writes benchmarks/results/element_costs.md.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from tissuesim.backend import numba_available  # noqa: E402
from tissuesim.materials.registry import make_material  # noqa: E402
from tissuesim.mesh import box  # noqa: E402
from tissuesim.model import Model  # noqa: E402
from tissuesim.solve.linear import SuperLUSolver  # noqa: E402


def resident_bytes(model: Model) -> int:
    K, P = model.kinematics, model.pattern
    arrays = [K.cells, K.stencil, K.weights, K.grads, P.indptr, P.indices, P.diagonal]
    arrays += list(P.scatters)
    extra = getattr(model.elastic, "_rank_one", None)
    if extra is not None:
        arrays += list(extra) + list(model.elastic._vertex)
    return int(sum(a.nbytes for a in arrays))


def median_time(fn, repeats: int) -> float:
    fn()  # warm-up (Numba compilation, caches)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def measure(n: int, order: int, formulation: str, backend: str, repeats: int) -> dict:
    mesh = box(divisions=(n, n, n) if order == 1 else (n // 2,) * 3, order=order)
    material = make_material("neo_hookean", youngs_modulus=3e3, poisson_ratio=0.49)
    model = Model(mesh, material, np.ones(mesh.n_cells), backend=backend, formulation=formulation)
    rng = np.random.default_rng(0)
    x = mesh.points.ravel() + 0.002 * rng.standard_normal(mesh.points.size)
    t_assembly = median_time(lambda: model.evaluate(x, 2, False), repeats)
    H = model.pattern.matrix(model.evaluate(x, 2, False).hessian)
    free = np.flatnonzero(np.repeat(mesh.points[:, 2] > 1e-12, 3))
    A = H[free][:, free].tocsr()
    solver = SuperLUSolver()
    t0 = time.perf_counter()
    solver.factorize(A)
    t_factor = time.perf_counter() - t0
    return {
        "cells": mesh.n_cells,
        "dofs": model.n_dofs,
        "nnz": model.pattern.nnz,
        "assembly_s": t_assembly,
        "per_element_us": 1e6 * t_assembly / mesh.n_cells,
        "resident_MB": resident_bytes(model) / 1e6,
        "factor_s": t_factor,
        "fill_M": (solver._lu.L.nnz + solver._lu.U.nnz) / 1e6,
        "fused": bool(getattr(model.elastic, "fused", False)),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--divisions", type=int, default=16, help="P1 divisions (even)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/element_costs.md"))
    args = ap.parse_args(argv)
    backends = ["numba", "numpy"] if numba_available() else ["numpy"]
    rows = []
    for order in (1, 2):
        for form in ("displacement", "mean_dilatation"):
            for backend in backends:
                if form == "mean_dilatation" and backend == "numba":
                    continue  # the mean-dilatation path is NumPy only
                r = measure(args.divisions, order, form, backend, args.repeats)
                row = (
                    f"| P{order} | {form} | {backend}{' (fused)' if r['fused'] else ''} | "
                    f"{r['cells']} | {r['dofs']} | {r['nnz'] / 1e6:.2f} | {r['assembly_s']:.3f} | "
                    f"{r['per_element_us']:.1f} | {r['resident_MB']:.1f} | {r['factor_s']:.2f} | "
                    f"{r['fill_M']:.1f} |"
                )
                print(row, flush=True)
                rows.append(row)
    text = [
        "# Element costs at the same nodes: P1 vs P2, displacement vs mean dilatation",
        "",
        f"`python3 benchmarks/element_costs.py --divisions {args.divisions} --repeats "
        f"{args.repeats}` (unit cube, neo-Hookean nu = 0.49; medians; one thread)",
        "",
        "| element | formulation | backend | cells | DOFs | Hessian nnz (M) | assembly s | "
        "us / element | resident MB | SuperLU s | fill (M) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
    ]
    Path(args.out).write_text("\n".join(text))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
