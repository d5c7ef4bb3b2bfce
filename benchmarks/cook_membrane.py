"""Cook's membrane, plane strain, neo-Hookean: the tip deflection against mesh size for P1, P1
mean dilatation, P2 and P2 mean dilatation, at several Poisson ratios.

The trapezoid (0, 0), (48, 44), (48, 60), (0, 44) (mm) is clamped at x = 0 and carries a dead
vertical traction on x = 48 of total ``--force`` N per unit thickness; mu = 80.194 MPa (deal.II
step-44's), lambda from nu. Units mm, N, MPa (consistent). The quantity is u_y at the top right
corner (48, 60). The mesh maps an n x n "alternate" triangle grid of the unit square onto the
trapezoid (x = 48 s, y = 44 s + t (44 + 16 s - 44 s)).

    python3 benchmarks/cook_membrane.py --nu 0.3 0.49 0.4999 --divisions 4 8 16 32
writes benchmarks/results/cook_membrane_last_run.md (the curated table is cook_membrane.md).
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
from tissuesim.mesh import rectangle  # noqa: E402
from tissuesim.mesh.checks import validate_mesh  # noqa: E402
from tissuesim.mesh.queries.select import facets_on_plane, vertices_on_plane  # noqa: E402
from tissuesim.solve.newton import NewtonOptions  # noqa: E402

MU = 80.194
VARIANTS = (
    ("P1", 1, "displacement"),
    ("P1 mean dilatation", 1, "mean_dilatation"),
    ("P2", 2, "displacement"),
    ("P2 mean dilatation", 2, "mean_dilatation"),
)


def cook_mesh(n: int):
    r = rectangle(divisions=(n, n))
    s, t = r.points[:, 0], r.points[:, 1]
    p = np.column_stack([48.0 * s, 44.0 * s + t * (44.0 + 16.0 * s - 44.0 * s)])
    return validate_mesh(p, r.cells, source=f"cook({n})", facet_sets={})


def solve(mesh, material, formulation: str, force: float, steps: int) -> np.ndarray:
    """Positions (n, 2) of the loaded membrane."""
    sim = _simulation(mesh, material, None, formulation, force, steps, 1e-8)[0]
    for _ in range(steps):
        sim.step()
    return sim.positions


def _simulation(mesh, material, order, formulation, force, steps, tolerance):
    sim = Simulation(
        integrator="quasistatic",
        time_step=1.0 / steps,
        newton=NewtonOptions(max_iterations=60, gradient_tolerance=tolerance),
    )
    body = sim.add_body("cook", mesh, material, density=1.0, order=order, formulation=formulation)
    body.fix(vertices_on_plane(body.mesh, 0, 0.0), name="clamp")
    traction = force / 16.0
    body.add_traction(
        facets_on_plane(body.mesh, 0, 48.0), lambda X, t: np.array([0.0, traction * min(t, 1.0)])
    )
    return sim, body


def tip_deflection(
    n: int,
    order: int,
    formulation: str,
    nu: float,
    force: float,
    steps: int,
    tolerance: float = 1e-8,
):
    mesh = cook_mesh(n)
    material = make_material("neo_hookean", youngs_modulus=2 * MU * (1 + nu), poisson_ratio=nu)
    sim, body = _simulation(mesh, material, order, formulation, force, steps, tolerance)
    tip = int(np.argmin(np.linalg.norm(body.mesh.points - [48.0, 60.0], axis=1)))
    start = time.perf_counter()
    iterations = 0
    for _ in range(steps):
        record = sim.step()
        iterations += record.newton_iterations
    wall = time.perf_counter() - start
    return {
        "dofs": body.model.n_dofs,
        "uy": float(sim.displacement[tip, 1]),
        "iterations": iterations,
        "wall_s": wall,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nu", type=float, nargs="+", default=[0.3, 0.49, 0.4999])
    ap.add_argument("--divisions", type=int, nargs="+", default=[4, 8, 16, 32])
    ap.add_argument("--force", type=float, default=100.0, help="N per unit thickness")
    ap.add_argument("--steps", type=int, default=4, help="load steps")
    ap.add_argument("--gradient-tolerance", type=float, default=1e-8, help="Newton's (relative)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/cook_membrane_last_run.md"))
    args = ap.parse_args(argv)
    lines = [
        "# Cook's membrane, plane strain neo-Hookean: u_y (mm) at (48, 60)",
        "",
        f"`python3 benchmarks/cook_membrane.py --nu {' '.join(map(str, args.nu))} --divisions "
        f"{' '.join(map(str, args.divisions))} --force {args.force:g} --steps {args.steps} "
        f"--gradient-tolerance {args.gradient_tolerance:g}`",
        "",
        f"mu = {MU} MPa, total vertical force {args.force:g} N per unit thickness.",
        "",
    ]
    for nu in args.nu:
        lines += [
            f"## nu = {nu}",
            "",
            "| variant | n | DOFs | u_y (mm) | Newton | s |",
            "|---|---|---|---|---|---|",
        ]
        for label, order, form in VARIANTS:
            for n in args.divisions:
                r = tip_deflection(
                    n, order, form, nu, args.force, args.steps, args.gradient_tolerance
                )
                row = (
                    f"| {label} | {n} | {r['dofs']} | {r['uy']:.5f} | {r['iterations']} | "
                    f"{r['wall_s']:.2f} |"
                )
                print(f"nu {nu}: {row}", flush=True)
                lines.append(row)
        lines.append("")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
