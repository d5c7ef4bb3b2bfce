"""Hertz contact against tissuesim's barrier contact: a rigid sphere (R = 10 mm) pressed
quasistatically into a soft block (E = 10 kPa, nu = 0.3), a quarter of it (symmetry planes
x = 0 and y = 0) 3R wide and 3R deep, clamped at its base, the mesh graded towards the contact
point; the probe moves 100 um per step to d = 500 um = R / 20 (contact radius a = 0.22 R, so
the probe's facets, 0.3 mm at refinement 5, are small against it).

Hertz for a rigid sphere on a half-space: F = 4/3 E* sqrt(R) d^(3/2), E* = E / (1 - nu^2);
the quarter carries F / 4. d is the probe's depth below the rest surface minus the barrier gap
(the surface stays min_distance away from the sphere). Prints and writes the table of F / F_Hertz
per depth for each mesh (``results/hertz.md``).

    python3 benchmarks/hertz.py                     # divisions 8 12 16
    python3 benchmarks/hertz.py --divisions 8 --steps 2
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import tissuesim as ts  # noqa: E402
from tissuesim.contact.obstacles import sphere  # noqa: E402

R, E, NU = 0.01, 1e4, 0.3
DHAT = 1e-6
STEP = 1e-4  # m of probe travel per step


def run(n: int, steps: int, grading: float) -> dict:
    size = 3 * R
    mesh = ts.box((0, 0, -size), (size, size, 0), (n, n, n), grading=(grading, grading, -grading))
    material = ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=NU)
    sim = ts.Simulation(mesh, material, integrator="quasistatic", time_step=1.0)
    sim.fix("body", mesh.point_sets["zmin"], name="base")
    sim.add_dirichlet(mesh.point_sets["xmin"], components=[0], name="symmetry_x")
    sim.add_dirichlet(mesh.point_sets["ymin"], components=[1], name="symmetry_y")
    probe = sphere((0, 0, R + DHAT / 2), R, refinement=5)
    sim.add_obstacle("probe", probe, translation=lambda t: (0.0, 0.0, -STEP * t))
    sim.set_contact(dhat=DHAT)
    e_star = E / (1 - NU**2)
    rows = []
    start = time.perf_counter()
    for _ in range(steps):
        record = sim.step()
        c = record.extra["contact"]
        d = c["indentation_depth"]["probe"] - c["min_distance"]
        force = -4 * record.extra["forces"]["probe"][2]
        hertz = 4 / 3 * e_star * np.sqrt(R) * d**1.5
        rows.append(
            {
                "depth_m": d,
                "force_N": force,
                "hertz_N": hertz,
                "ratio": force / hertz,
                "newton_iterations": record.newton_iterations,
                "substeps": record.substeps,
            }
        )
    return {
        "divisions": n,
        "grading": grading,
        "tetrahedra": mesh.n_cells,
        "wall_s": time.perf_counter() - start,
        "rows": rows,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--divisions", type=int, nargs="*", default=[8, 12, 16])
    parser.add_argument("--steps", type=int, default=5)
    parser.add_argument("--grading", type=float, default=3.0)
    args = parser.parse_args()
    results = []
    for n in args.divisions:
        r = run(n, args.steps, args.grading)
        results.append(r)
        print(json.dumps(r))
    depths = [row["depth_m"] for row in results[0]["rows"]]
    lines = [
        "# Hertz indentation: F / F_Hertz per depth and mesh",
        "",
        f"`python3 benchmarks/hertz.py --divisions {' '.join(map(str, args.divisions))} "
        f"--steps {args.steps} --grading {args.grading}`; R = {R} m, E = {E} Pa, nu = {NU}, "
        f"quarter block 3R x 3R x 3R clamped at its base, dhat = {DHAT} m, probe sphere of "
        "20,480 triangles.",
        "",
        "| divisions (tets) | " + " | ".join(f"d = {d * 1e6:.0f} um" for d in depths) + " | s |",
        "| --- | " + " | ".join("---" for _ in depths) + " | --- |",
    ]
    for r in results:
        ratios = " | ".join(f"{row['ratio']:.3f}" for row in r["rows"])
        lines.append(f"| {r['divisions']} ({r['tetrahedra']}) | {ratios} | {r['wall_s']:.0f} |")
    lines.append("")
    out = Path(__file__).resolve().parent / "results" / "hertz.md"
    out.write_text("\n".join(lines))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
