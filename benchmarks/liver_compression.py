"""A liver-like body at nu = 0.49, pressed between two plates: the force and a bulge
displacement against refinement, for P1, P2 and their mean-dilatation variants.

An ellipsoid with semi-axes 0.10 x 0.07 x 0.05 m (neo-Hookean, E = 5 kPa, nu = ``--nu``):
the bottom patch is clamped (the bed) and the top patch moved down by 10 mm in ``--steps``
quasistatic steps (a plate bonded to it). The patches are the images of the bottom and top
faces of the cube that ``ellipsoid`` maps onto the body, so they are the same surface regions
at every refinement (a "z < -0.04" selection would change with the mesh and the force with
it). Reported: the plate's force (N, z) and the outward bulge u_x of the node nearest
(0.10, 0, 0). The reference is the Richardson extrapolation of the two finest P2
mean-dilatation runs (error ~ h^2 assumed; the table shows how close each run is to it).

    python3 benchmarks/liver_compression.py --divisions 3 4 6 8 --p1 4 8 12
writes benchmarks/results/liver_compression_last_run.md (the curated table:
liver_compression.md).
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
from tissuesim.mesh import ellipsoid  # noqa: E402
from tissuesim.solve.newton import NewtonOptions  # noqa: E402

RADII = (0.10, 0.07, 0.05)


def cube_face_nodes(mesh, n: int, top: bool) -> np.ndarray:
    """The nodes on the image of the cube's z = -1 (or +1) face: the first (last) (n + 1)^2
    grid vertices (z is the slowest grid index), with the midside nodes between them."""
    layer = (n + 1) ** 2
    first = (n + 1) ** 3 - layer if top else 0
    corners = np.arange(first, first + layer)
    if mesh.order == 1:
        return corners
    from tissuesim.mesh.cells.quadratic import EDGES

    pairs = mesh.cells[:, EDGES[3]]  # (m, 6, 2) corner pairs of the midside nodes
    inside = np.isin(pairs, corners).all(axis=2)
    return np.union1d(corners, mesh.cells[:, 4:][inside])


def press(n: int, order: int, formulation: str, nu: float, steps: int) -> dict:
    mesh = ellipsoid((0, 0, 0), RADII, n, order=order)
    material = make_material("neo_hookean", youngs_modulus=5e3, poisson_ratio=nu)
    sim = Simulation(
        integrator="quasistatic", time_step=1.0 / steps, newton=NewtonOptions(max_iterations=60)
    )
    body = sim.add_body("liver", mesh, material, density=1000.0, formulation=formulation)
    body.fix(cube_face_nodes(mesh, n, top=False), name="bed")
    body.add_dirichlet(
        cube_face_nodes(mesh, n, top=True),
        lambda X, t: np.array([0.0, 0.0, -0.01 * min(t, 1.0)]),
        name="indenter",
    )
    probe = int(np.argmin(np.linalg.norm(mesh.points - [RADII[0], 0.0, 0.0], axis=1)))
    start, iterations = time.perf_counter(), 0
    for _ in range(steps):
        iterations += sim.step().newton_iterations
    return {
        "cells": mesh.n_cells,
        "dofs": body.model.n_dofs,
        "force": -float(sim.forces()["indenter"][2]),
        "bulge": float(sim.displacement[probe, 0]),
        "iterations": iterations,
        "wall_s": time.perf_counter() - start,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nu", type=float, default=0.49)
    ap.add_argument("--divisions", type=int, nargs="+", default=[3, 4, 6, 8], help="P2")
    ap.add_argument("--p1", type=int, nargs="+", default=[4, 8, 12], help="P1 divisions")
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/liver_compression_last_run.md"))
    args = ap.parse_args(argv)
    runs = []
    for label, order, form, sizes in (
        ("P2 mean dilatation", 2, "mean_dilatation", args.divisions),
        ("P2", 2, "displacement", args.divisions),
        ("P1 mean dilatation", 1, "mean_dilatation", args.p1),
        ("P1", 1, "displacement", args.p1),
    ):
        for n in sizes:
            r = press(n, order, form, args.nu, args.steps)
            runs.append((label, n, r))
            print(label, n, r, flush=True)
    best = [r for label, n, r in runs if label == "P2 mean dilatation"]
    h = np.array([1.0 / n for n in args.divisions[-2:]])
    ref = {}
    for key in ("force", "bulge"):
        f1, f2 = best[-2][key], best[-1][key]
        ref[key] = f2 + (f2 - f1) * h[1] ** 2 / (h[0] ** 2 - h[1] ** 2)
    lines = [
        f"# Liver-like ellipsoid (nu = {args.nu}) pressed 10 mm between plates",
        "",
        f"`python3 benchmarks/liver_compression.py --nu {args.nu} --divisions "
        f"{' '.join(map(str, args.divisions))} --p1 {' '.join(map(str, args.p1))} "
        f"--steps {args.steps}`",
        "",
        f"Reference (Richardson, two finest P2 mean dilatation): force {ref['force']:.5f} N, "
        f"bulge {1e3 * ref['bulge']:.4f} mm.",
        "",
        "| variant | divisions | cells | DOFs | force (N) | error | bulge u_x (mm) | error | "
        "Newton | s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for label, n, r in runs:
        ef = 100 * (r["force"] / ref["force"] - 1)
        eb = 100 * (r["bulge"] / ref["bulge"] - 1)
        lines.append(
            f"| {label} | {n} | {r['cells']} | {r['dofs']} | {r['force']:.5f} | {ef:+.2f} % | "
            f"{1e3 * r['bulge']:.4f} | {eb:+.2f} % | {r['iterations']} | {r['wall_s']:.1f} |"
        )
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
