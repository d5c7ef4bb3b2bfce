"""Volumetric locking of Q1 quadrilaterals and hexahedra, and the mean-dilatation cure (Q1/P0).

1. Cook's membrane, plane strain, neo-Hookean, nu = 0.499: the trapezoid (0, 0), (48, 44),
   (48, 60), (0, 44) mm clamped at x = 0, a dead vertical traction of 100 N in total on x = 48,
   mu = 80.194 MPa; u_y at (48, 60) on n x n quadrilaterals (a uniform grid of the unit square
   mapped onto the trapezoid), plain Q1 against Q1/P0 (``formulation = "mean_dilatation"``).
2. A cantilever 2 x 0.4 x 0.4 m of hexahedra (n along the height and width, 5 n along the
   length), neo-Hookean E = 1e5 Pa, nu = 0.499, clamped at x = 0, 1 N down on the end face as a
   traction: the mean u_z of the end face (a small load: the linear regime).

References: Cook's from FElupe's mixed u-p-J biquadratic quads (Q9 / discontinuous P1, the same
energy) at 32 x 32 on the same uniform mesh; the cantilever from tissuesim's own Q1/P0 at the
finest level and, for comparison, Q1/P0 one level coarser.

    python3 benchmarks/hex_locking.py [--cook 2 4 8 16 32] [--cantilever 1 2 4 8]
writes benchmarks/results/hex_locking.md.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import tissuesim as ts  # noqa: E402
from tissuesim.mesh.checks import validate_mesh  # noqa: E402
from tissuesim.solve.newton import NewtonOptions  # noqa: E402

MU, NU = 80.194, 0.499
TIGHT = NewtonOptions(gradient_tolerance=1e-10)


def cook_mesh(n: int):
    r = ts.rectangle((0, 0), (1, 1), (n, n), element="quad")
    s, t = r.points[:, 0], r.points[:, 1]
    p = np.column_stack([48.0 * s, 44.0 * s + t * (44.0 + 16.0 * s - 44.0 * s)])
    return validate_mesh(p, r.cells, source=f"cook({n})")


def cook(n: int, formulation: str) -> tuple[float, float]:
    mesh = cook_mesh(n)
    mat = ts.make_material("neo_hookean", youngs_modulus=2 * MU * (1 + NU), poisson_ratio=NU)
    sim = ts.Simulation(integrator="quasistatic", time_step=0.25, newton=TIGHT)
    sim.add_body("cook", mesh, mat, formulation=formulation)
    sim.fix(ts.select.vertices_on_plane(mesh, 0, 0.0), body="cook")
    right = ts.select.facets_on_plane(mesh, 0, 48.0)
    sim.add_traction(
        right,
        lambda X, t: np.column_stack([0 * X[:, 0], 0 * X[:, 0] + 6.25 * min(t, 1)]),
        body="cook",
    )
    t0 = time.perf_counter()
    for _ in range(4):
        sim.step()
    corner = np.flatnonzero(np.isclose(mesh.points[:, 0], 48) & np.isclose(mesh.points[:, 1], 60))
    return float(sim.displacement[corner[0], 1]), time.perf_counter() - t0


def felupe_cook(n: int) -> float:
    import felupe as fe

    lam = 2 * MU * NU / (1 - 2 * NU)
    r = fe.Rectangle(a=(0.0, 0.0), b=(1.0, 1.0), n=(n + 1, n + 1))
    s, t = r.points[:, 0], r.points[:, 1]
    p = np.column_stack([48.0 * s, 44.0 * s + t * (44.0 + 16.0 * s - 44.0 * s)])
    m = fe.Mesh(p, r.cells, r.cell_type).add_midpoints_edges().add_midpoints_faces()
    region = fe.RegionBiQuadraticQuad(m)
    field = fe.FieldsMixed(region, n=3, planestrain=True)
    law = fe.NearlyIncompressible(
        fe.NeoHookeCompressible(mu=MU),
        bulk=lam,
        dUdJ=lambda J, b: b * np.log(J) / J,
        d2UdJdJ=lambda J, b: b * (1.0 - np.log(J)) / J**2,
    )
    solid = fe.SolidBody(law, field)
    dof0, dof1 = fe.dof.partition(field, {"left": fe.Boundary(field[0], fx=0.0)})
    right = np.flatnonzero(np.isclose(m.points[:, 0], 48.0))
    right = right[np.argsort(m.points[right, 1])]
    w = np.zeros(len(right))  # Simpson weights of the quadratic edges
    for k in range(0, len(right) - 2, 2):
        L = m.points[right[k + 2], 1] - m.points[right[k], 1]
        w[k : k + 3] += np.array([1, 4, 1]) * L / 6
    values = np.zeros((len(right), 2))
    values[:, 1] = 6.25 * w
    load = fe.PointLoad(field, right, values)
    for lf in (0.25, 0.5, 0.75, 1.0):
        load.update(lf * values)
        field = fe.newtonraphson(
            items=[solid, load],
            x0=field,
            dof1=dof1,
            dof0=dof0,
            tol=1e-8,
            verbose=0,
            plugins=[fe.LinesearchPlugin()],
        ).x
    tip = np.flatnonzero(np.isclose(m.points[:, 0], 48) & np.isclose(m.points[:, 1], 60))
    return float(field[0].values[tip[0], 1])


def cantilever(n: int, formulation: str) -> tuple[float, float]:
    mesh = ts.box((0, 0, 0), (2.0, 0.4, 0.4), (5 * n, n, n), element="hex")
    mat = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=NU)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0, newton=TIGHT)
    sim.add_body("beam", mesh, mat, formulation=formulation)
    sim.fix(ts.select.vertices_on_plane(mesh, 0, 0.0), body="beam")
    sim.add_traction(ts.select.facets_on_plane(mesh, 0, 2.0), (0.0, 0.0, -1.0 / 0.16), body="beam")
    t0 = time.perf_counter()
    sim.step()
    end = ts.select.facets_on_plane(mesh, 0, 2.0)
    # the mean u_z of the end face: the face's nodal weights int N_a dA / area
    from tissuesim.energies.loads import quad_traction_nodal_forces

    unit = np.broadcast_to([0.0, 0.0, 1.0 / 0.16], (end.size, 3)).reshape(*end.shape, 3)
    weights = quad_traction_nodal_forces(mesh.points, end, unit)[:, 2]
    return float(weights @ sim.displacement[:, 2]), time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cook", type=int, nargs="*", default=[2, 4, 8, 16, 32])
    ap.add_argument("--cantilever", type=int, nargs="*", default=[1, 2, 4, 8])
    ap.add_argument("--reference", type=int, default=32, help="FElupe Q9 mixed level (Cook)")
    args = ap.parse_args()
    lines = [f"# Locking of Q1 elements at nu = {NU} (`benchmarks/hex_locking.py`)", ""]
    ref = felupe_cook(args.reference)
    lines += [
        f"Cook's membrane, u_y at (48, 60) in mm; reference: FElupe Q9 u-p-J at "
        f"{args.reference} x {args.reference}: {ref:.4f}.",
        "",
        "| n x n | Q1 | Q1/P0 (mean dilatation) | seconds (Q1, Q1/P0) |",
        "| --- | --- | --- | --- |",
    ]
    for n in args.cook:
        (a, ta), (b, tb) = cook(n, "displacement"), cook(n, "mean_dilatation")
        lines.append(
            f"| {n} | {a:.4f} ({100 * (a / ref - 1):+.1f} %) | "
            f"{b:.4f} ({100 * (b / ref - 1):+.2f} %) | {ta:.2f}, {tb:.2f} |"
        )
        print(lines[-1], flush=True)
    rows = [
        (n, cantilever(n, "displacement"), cantilever(n, "mean_dilatation"))
        for n in args.cantilever
    ]
    cref = rows[-1][2][0]
    lines += [
        "",
        f"Cantilever 2 x 0.4 x 0.4 m, mean end-face u_z in mm; reference: Q1/P0 at the finest "
        f"level ({5 * args.cantilever[-1]} x {args.cantilever[-1]} x {args.cantilever[-1]}): "
        f"{1e3 * cref:.4f} mm.",
        "",
        "| hexahedra | Q1 | Q1/P0 (mean dilatation) | seconds (Q1, Q1/P0) |",
        "| --- | --- | --- | --- |",
    ]
    for n, (a, ta), (b, tb) in rows:
        lines.append(
            f"| {5 * n} x {n} x {n} | {1e3 * a:.4f} ({100 * (a / cref - 1):+.1f} %) | "
            f"{1e3 * b:.4f} ({100 * (b / cref - 1):+.2f} %) | {ta:.2f}, {tb:.2f} |"
        )
        print(lines[-1], flush=True)
    out = ROOT / "benchmarks" / "results" / "hex_locking.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
