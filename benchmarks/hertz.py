"""Hertz contact against tissuesim's barrier contact: a rigid sphere (R = 10 mm) pressed
quasistatically into a soft block (E = 10 kPa, nu = 0.3).

The half-space is a quarter block (symmetry planes x = 0 and y = 0) L = 150 mm wide and deep
(L / a > 100 at the largest depth: a finite block is stiffer than the half-space by about
0.9 a / L when clamped at its base), clamped at its base. Its tetrahedra are graded by gmsh
(an optional tool for this benchmark, ``pip install gmsh``): size h0 within 1.2 a_max of the
contact point, growing linearly at ``--growth`` per metre of distance to L / 8. The probe is a
30-degree cap of an icosphere of refinement 7 (facets R / 110). The probe moves
``--step`` per step (quasistatic, moving obstacle).

Hertz for a rigid sphere on a half-space: F = 4/3 E* sqrt(R) d^(3/2), E* = E / (1 - nu^2); the
quarter carries F / 4. d is the probe's travel since it touched the block minus the barrier gap (the
surface stays ``min_distance`` away from the sphere). Prints and writes the table of F / F_Hertz
per depth for each h0 (``results/hertz_<material>_last_run.md``; the README's table,
collected from several runs, is ``results/hertz_linear.md``).

    python3 benchmarks/hertz.py --steps 2 --material linear   # the README's table
    python3 benchmarks/hertz.py --h0 0.2 --steps 2 --material linear
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import tissuesim as ts  # noqa: E402
from tissuesim.contact.obstacles import sphere  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from hertz_mesh import L, graded_block  # noqa: E402

R, E, NU = 0.01, 1e4, 0.3
DHAT = 1e-7


def run(
    h0: float,
    steps: int,
    step: float,
    growth: float,
    r_fine: float,
    material: str,
    dhat: float = DHAT,
    stiffness=None,
    max_iterations: int = 150,
) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        mesh = ts.read_mesh(graded_block(Path(tmp) / "block.msh", h0, r_fine, growth))
    p = mesh.points
    tol = 1e-9
    law = ts.make_material(material, youngs_modulus=E, poisson_ratio=NU)
    newton = ts.NewtonOptions(max_iterations=max_iterations)
    sim = ts.Simulation(mesh, law, integrator="quasistatic", time_step=1.0, newton=newton)
    sim.fix("body", np.unique(mesh.facet_sets["base"]), name="base")
    sim.add_dirichlet(np.flatnonzero(p[:, 0] < tol), components=[0], name="symmetry_x")
    sim.add_dirichlet(np.flatnonzero(p[:, 1] < tol), components=[1], name="symmetry_y")
    probe = sphere((0, 0, R + dhat / 2), R, refinement=7, cap_angle=30)
    sim.add_obstacle("probe", probe, translation=lambda t: (0.0, 0.0, -step * t))
    # only the top face touches: the probe passes the symmetry planes' faces (x = 0, y = 0)
    sim.set_contact(dhat=dhat, stiffness=stiffness, surfaces={"body": "top"})
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
                "gap_m": c["min_distance"],
                "force_N": force,
                "hertz_N": hertz,
                "ratio": force / hertz,
                "newton_iterations": record.newton_iterations,
                "substeps": record.substeps,
                "stiffness_Pa": c["stiffness_Pa"],
            }
        )
        print(json.dumps(rows[-1]), flush=True)
    return {
        "h0_m": h0,
        "tetrahedra": mesh.n_cells,
        "vertices": mesh.n_points,
        "wall_s": time.perf_counter() - start,
        "rows": rows,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h0", type=float, nargs="*", default=[0.2e-3, 0.14e-3, 0.1e-3])
    parser.add_argument("--steps", type=int, default=4)
    parser.add_argument("--step", type=float, default=5e-5, help="probe travel per step (m)")
    parser.add_argument("--growth", type=float, default=0.25)
    parser.add_argument("--r-fine", type=float, default=1.7e-3, help="radius of the h0 region (m)")
    parser.add_argument("--material", default="neo_hookean")
    parser.add_argument("--dhat", type=float, default=DHAT, help="barrier activation distance (m)")
    parser.add_argument("--stiffness", default=None, help='kappa (Pa) or "adaptive"')
    parser.add_argument("--max-iterations", type=int, default=150, help="Newton, per solve")
    args = parser.parse_args()
    stiffness = args.stiffness
    if stiffness is not None and stiffness != "adaptive":
        stiffness = float(stiffness)
    results = []
    for h0 in args.h0:
        r = run(
            h0,
            args.steps,
            args.step,
            args.growth,
            args.r_fine,
            args.material,
            args.dhat,
            stiffness,
            args.max_iterations,
        )
        results.append(r)
        print(json.dumps({k: v for k, v in r.items() if k != "rows"}), flush=True)
    depths = [row["depth_m"] for row in results[0]["rows"]]
    lines = [
        "# Hertz indentation: F / F_Hertz per depth and mesh",
        "",
        f"`python3 benchmarks/hertz.py --h0 {' '.join(f'{h:g}' for h in args.h0)} "
        f"--steps {args.steps} --step {args.step:g} --growth {args.growth} "
        f"--material {args.material} --dhat {args.dhat:g}"
        + (f" --stiffness {args.stiffness}" if args.stiffness else "")
        + f"`; R = {R} m, E = {E} Pa, nu = {NU}, quarter block "
        f"{L} m wide and deep clamped at its base, graded by gmsh, dhat = {args.dhat} m, "
        f"stiffness {args.stiffness or 'adaptive (from E)'}, probe a "
        "30-degree cap of an icosphere of refinement 7.",
        "",
        "| h0 (tets) | "
        + " | ".join(f"d = {d * 1e6:.0f} um (a = {np.sqrt(R * d) * 1e3:.2f} mm)" for d in depths)
        + " | s | Newton iterations per step |",
        "| --- | " + " | ".join("---" for _ in depths) + " | --- | --- |",
    ]
    for r in results:
        ratios = " | ".join(f"{row['ratio']:.4f}" for row in r["rows"])
        lines.append(
            f"| {r['h0_m'] * 1e3:g} mm ({r['tetrahedra']}) | {ratios} | {r['wall_s']:.0f} | "
            f"{[row['newton_iterations'] for row in r['rows']]} |"
        )
    lines.append("")
    # the run's own table; results/hertz_linear.md is the curated table of many runs
    out = Path(__file__).resolve().parent / "results" / f"hertz_{args.material}_last_run.md"
    out.write_text("\n".join(lines))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
