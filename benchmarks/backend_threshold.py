"""Where the Numba assembly pays for itself: per evaluation (energy, gradient, Hessian) with
the NumPy and the Numba backends at several sizes, and Numba's fixed cost per process (loading
its cached kernels and the first call), each in fresh processes. ``backend = "auto"`` picks
NumPy below the size where Numba's saving over a short run is less than its fixed cost.

    python3 benchmarks/backend_threshold.py            # prints a table, writes results/
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPEATS = 5


def child(dim: int, n: int, backend: str) -> dict:
    import time

    start = time.perf_counter()
    import numpy as np

    import tissuesim as ts
    from tissuesim.model import Model

    if dim == 2:
        mesh = ts.rectangle((0.0, 0.0), (1.0, 1.0), (n, n))
    else:
        mesh = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (n, n, n))
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    model = Model(mesh, material, np.full(mesh.n_cells, 1000.0), backend=backend)
    x = mesh.points.ravel() * 1.01
    ready = time.perf_counter()
    model.evaluate(x, 2, False)  # the first call: Numba loads (or compiles) its kernels
    first = time.perf_counter() - ready
    times = []
    for _ in range(REPEATS):
        t = time.perf_counter()
        model.evaluate(x, 2, False)
        times.append(time.perf_counter() - t)
    return {
        "dim": dim,
        "cells": int(mesh.n_cells),
        "backend": model.backend,
        "setup_s": ready - start,
        "first_call_s": first,
        "evaluation_s": statistics.median(times),
    }


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        print(json.dumps(child(int(sys.argv[2]), int(sys.argv[3]), sys.argv[4])))
        return
    env = dict(os.environ, OMP_NUM_THREADS="1", NUMBA_NUM_THREADS="1")
    env.pop("TISSUESIM_BACKEND", None)
    rows = []
    cases = [(2, 4), (2, 16), (2, 45), (2, 100), (3, 3), (3, 6), (3, 12), (3, 26)]
    for dim, n in cases:
        for backend in ("numpy", "numba"):
            runs = []
            for _ in range(3):  # fresh processes: Numba's per-process cost each time
                out = subprocess.run(
                    [sys.executable, __file__, "--child", str(dim), str(n), backend],
                    env=env,
                    capture_output=True,
                    text=True,
                    check=True,
                )
                runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
            row = dict(runs[0])
            for key in ("setup_s", "first_call_s", "evaluation_s"):
                row[key] = statistics.median(r[key] for r in runs)
            rows.append(row)
            print(json.dumps(row), flush=True)
    lines = [
        "# NumPy against Numba assembly by size (benchmarks/backend_threshold.py)",
        "",
        "One thread; medians of 3 fresh processes (evaluation: median of 5 calls after the "
        "first); order-2 evaluation (energy, gradient, Hessian) of a Neo-Hookean P1 mesh.",
        "",
        "| dim | cells | numba's fixed cost s (import + first call, over NumPy's) "
        "| numpy eval ms | numba eval ms | saving per eval ms | evaluations to repay it |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for a, b in zip(rows[0::2], rows[1::2], strict=True):
        saving = a["evaluation_s"] - b["evaluation_s"]
        extra = (b["setup_s"] + b["first_call_s"]) - (a["setup_s"] + a["first_call_s"])
        repay = f"{max(extra, 0.0) / saving:.0f}" if saving > 0 else "never"
        lines.append(
            f"| {a['dim']} | {a['cells']:,} | {extra:.3f} "
            f"| {1e3 * a['evaluation_s']:.3f} | {1e3 * b['evaluation_s']:.3f} "
            f"| {1e3 * saving:.3f} | {repay} |"
        )
    text = "\n".join(lines) + "\n"
    (HERE / "results" / "backend_threshold.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
