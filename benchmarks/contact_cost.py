"""What contact adds to a Newton iteration, on a scene whose surfaces touch over a large area:
two boxes stacked with a gap of dhat / 2, the lower one clamped at its base, the upper one
pressed down at its top (quasistatic, 0.5 % of its height per step), so the whole interface is
in contact. The same scene is run with contact off (the boxes then do not interact), with the
boxes tied instead (``attach``: the same coupling of the two bodies in the matrix, so the
same factorisation cost) and with contact on;
the figure is the median over steps of wall time / Newton iterations, and with contact its
split into candidates + barrier assembly, CCD and the rest (elasticity, linear solve, line
search). One thread (set before NumPy loads).

    python3 benchmarks/contact_cost.py                 # about 1e4 and 1e5 tetrahedra
    python3 benchmarks/contact_cost.py --sizes 6 --steps 2
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import tissuesim as ts  # noqa: E402


def scene(n: int, contact: bool | str) -> ts.Simulation:
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    dhat = 1e-3
    sim = ts.Simulation(integrator="quasistatic", time_step=0.1)
    low = ts.box((0, 0, 0), (1, 1, 0.4), (n, n, max(1, int(0.4 * n))))
    high = ts.box((0.05, 0.05, 0.4 + dhat / 2), (0.95, 0.95, 0.8), (n, n, max(1, int(0.4 * n))))
    sim.add_body("low", low, material)
    sim.add_body("high", high, material)
    sim.fix("low", ts.select.vertices_on_plane(low, axis=2, value=0.0))
    top = ts.select.vertices_on_plane(high, axis=2, value=0.8)
    sim.bodies["high"].add_dirichlet(top, lambda X, t: [0.0, 0.0, -0.002 * t] + 0 * X)
    if contact == "tied":
        sim.attach("high", "low", distance=dhat)
    elif contact:
        sim.set_contact(dhat=dhat)
    return sim


def measure(n: int, steps: int, contact: bool | str) -> dict:
    sim = scene(n, contact)
    cells = sum(b.mesh.n_cells for b in sim.bodies.values())
    sim.step()  # JIT, analysis, first contact: not timed
    per_iteration, split = [], {"candidates_and_barrier_s": [], "candidates_s": [], "ccd_s": []}
    iterations = []
    for _ in range(steps):
        start = time.perf_counter()
        record = sim.step()
        wall = time.perf_counter() - start
        its = max(1, record.newton_iterations)
        iterations.append(record.newton_iterations)
        per_iteration.append(wall / its)
        if contact is True:
            c = record.extra["contact"]
            for key in split:
                split[key].append(c[key] / its)
    out = {
        "tetrahedra": cells,
        "contact": contact,
        "steps": steps,
        "newton_iterations": iterations,
        "s_per_iteration": statistics.median(per_iteration),
        "linear_solver": sim.linear_solver_info()["name"],
    }
    if contact is True:
        out.update({k: statistics.median(v) for k, v in split.items()})
        out["active_pairs"] = record.extra["contact"]["active_pairs"]
        out["min_distance_m"] = record.extra["contact"]["min_distance"]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=[12, 26])
    parser.add_argument("--steps", type=int, default=3)
    args = parser.parse_args()
    rows = []
    for n in args.sizes:
        for contact in (False, "tied", True):
            row = measure(n, args.steps, contact)
            rows.append(row)
            print(json.dumps(row))
    lines = [
        "# Contact cost per Newton iteration (two stacked boxes pressed together)",
        "",
        f"`python3 benchmarks/contact_cost.py --sizes {' '.join(map(str, args.sizes))} "
        f"--steps {args.steps}`, one thread, median over steps.",
        "",
        "| tetrahedra | contact | s / iteration | candidates | barrier | CCD | rest | "
        "iterations per step | active pairs | linear solver |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        if r["contact"] is True:
            rest = r["s_per_iteration"] - r["candidates_and_barrier_s"] - r["ccd_s"]
            barrier = r["candidates_and_barrier_s"] - r["candidates_s"]
            lines.append(
                f"| {r['tetrahedra']} | on | {r['s_per_iteration']:.3f} | "
                f"{r['candidates_s']:.3f} | {barrier:.3f} | {r['ccd_s']:.3f} | {rest:.3f} | "
                f"{r['newton_iterations']} | {r['active_pairs']} | {r['linear_solver']} |"
            )
        else:
            kind = "tied" if r["contact"] == "tied" else "off"
            lines.append(
                f"| {r['tetrahedra']} | {kind} | {r['s_per_iteration']:.3f} | | | | | "
                f"{r['newton_iterations']} | | {r['linear_solver']} |"
            )
    for off, tied, on in zip(rows[::3], rows[1::3], rows[2::3], strict=True):
        lines.append("")
        lines.append(
            f"{on['tetrahedra']} tetrahedra: an iteration with contact costs "
            f"{on['s_per_iteration'] / off['s_per_iteration']:.2f} x one without contact and "
            f"{on['s_per_iteration'] / tied['s_per_iteration']:.2f} x one of the tied boxes."
        )
    out = Path(__file__).resolve().parent / "results" / "contact_cost.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
