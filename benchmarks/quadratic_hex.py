"""Quadratic hexahedra (hexahedron20, hexahedron27) against Q1 on the bending cantilever, each
checked against FElupe on the same mesh in the same run.

A cantilever 2 x 0.4 x 0.4 m (n cells along the height and width, 5 n along the length),
neo-Hookean E = 1e5 Pa, clamped at x = 0, 1 N down on the end face as a uniform traction (the
linear regime); the mean u_z of the end face's nodes, for nu = 0.3 and (with Q1/P0 and Q2/P0,
mean dilatation) nu = 0.499. FElupe (``QuadraticHexahedron``, ``TriQuadraticHexahedron``,
``Hexahedron``, 3 / 2 Gauss points per direction as here) solves the same mesh, law and nodal
loads; "FElupe diff" is the largest nodal difference over the largest displacement. Q2/P0
is compared with FElupe's mixed fields for hexahedron20 and hexahedron8 (constant pressure and
dilatation per cell, the same functional); FElupe's hexahedron27 mixed form is Q2/Q1 (not
compared). Reference: hexahedron27 at the finest n.

    python3 benchmarks/quadratic_hex.py [--n 1 2 4] [--q1 1 2 4 8]
writes benchmarks/results/quadratic_hex.md and docs/img/quadratic_hex.png.
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
from tissuesim.energies.loads import Traction  # noqa: E402
from tissuesim.model import Model  # noqa: E402
from tissuesim.solve.newton import NewtonOptions  # noqa: E402

E = 1e5
TIGHT = NewtonOptions(gradient_tolerance=1e-11, absolute_tolerance=1e-14)
ELEMENT = {"hexahedron": "hex", "hexahedron20": "hex20", "hexahedron27": "hex27"}


def beam(kind: str, n: int):
    mesh = ts.box((0, 0, 0), (2.0, 0.4, 0.4), (5 * n, n, n), element=ELEMENT[kind])
    fixed = ts.select.vertices_on_plane(mesh, 0, 0.0)
    tip = ts.select.facets_on_plane(mesh, 0, 2.0)
    mat = ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=0.3)
    model = Model(mesh, mat, np.ones(mesh.n_cells), backend="numpy")
    h = (0.0, 0.0, -1.0 / 0.16)
    nodal = Traction(tip, lambda X, t: np.broadcast_to(h, X.shape)).nodal_forces(model, 0.0)
    return mesh, fixed, nodal


def ours(mesh, fixed, nodal, nu: float, formulation: str) -> np.ndarray:
    mat = ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=nu)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0, newton=TIGHT)
    sim.add_body("beam", mesh, mat, formulation=formulation)
    sim.fix(fixed, body="beam")
    loaded = np.flatnonzero(np.abs(nodal).sum(axis=1) > 0)
    sim.add_nodal_forces(loaded, lambda t: nodal[loaded], body="beam")
    assert sim.step().converged
    return sim.displacement


def felupe(mesh, fixed, nodal, nu: float, mixed: bool) -> np.ndarray:
    import felupe as fe

    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    region = {
        "hexahedron": fe.RegionHexahedron,
        "hexahedron20": fe.RegionQuadraticHexahedron,
        "hexahedron27": fe.RegionTriQuadraticHexahedron,
    }[mesh.cell_type](fe.Mesh(mesh.points, mesh.cells, mesh.cell_type))
    if mixed:
        field = fe.FieldsMixed(region, n=3)
        law = fe.NearlyIncompressible(
            fe.NeoHookeCompressible(mu=mu),
            bulk=lam,
            dUdJ=lambda J, b: b * np.log(J) / J,
            d2UdJdJ=lambda J, b: b * (1.0 - np.log(J)) / J**2,
        )
    else:
        field = fe.FieldContainer([fe.Field(region, dim=3)])
        law = fe.NeoHookeCompressible(mu=mu, lmbda=lam)
    solid = fe.SolidBody(law, field)
    mask = np.zeros(mesh.n_points, dtype=bool)
    mask[fixed] = True
    dof0, dof1 = fe.dof.partition(field, {"fixed": fe.Boundary(field[0], mask=mask)})
    loaded = np.flatnonzero(np.abs(nodal).sum(axis=1) > 0)
    load = fe.PointLoad(field, loaded, nodal[loaded])
    res = fe.newtonraphson(
        items=[solid, load], x0=field, dof1=dof1, dof0=dof0, tol=1e-9, maxiter=40, verbose=0
    )
    return res.x[0].values


def run(kind: str, n: int, nu: float, formulation: str) -> dict:
    mesh, fixed, nodal = beam(kind, n)
    t0 = time.perf_counter()
    u = ours(mesh, fixed, nodal, nu, formulation)
    wall = time.perf_counter() - t0
    tip = ts.select.vertices_on_plane(mesh, 0, 2.0)
    row = {"kind": kind, "n": n, "nu": nu, "form": formulation, "dofs": mesh.points.size}
    row["uz"], row["wall"] = float(u[tip, 2].mean()), wall
    compare = formulation == "displacement" or kind != "hexahedron27"
    try:
        v = felupe(mesh, fixed, nodal, nu, formulation != "displacement") if compare else None
    except Exception as exc:  # FElupe missing, or its Newton did not converge
        print(f"FElupe: {type(exc).__name__}: {exc}", flush=True)
        v = None
    row["diff"] = None if v is None else float(np.abs(u - v).max() / np.abs(v).max())
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[1, 2, 4])
    ap.add_argument("--q1", type=int, nargs="+", default=[1, 2, 4, 8])
    args = ap.parse_args()
    rows = []
    for nu, form in ((0.3, "displacement"), (0.499, "mean_dilatation")):
        for kind in ("hexahedron", "hexahedron20", "hexahedron27"):
            for n in args.q1 if kind == "hexahedron" else args.n:
                rows.append(run(kind, n, nu, form))
                print(rows[-1], flush=True)
    lines = [
        "# Quadratic hexahedra on the bending cantilever",
        "",
        f"`python3 benchmarks/quadratic_hex.py --n {' '.join(map(str, args.n))} --q1 "
        f"{' '.join(map(str, args.q1))}`; mean end-face u_z in mm, error against hexahedron27 "
        "at the finest n of the same nu; FElupe diff: max |u - u_FElupe| / max |u_FElupe| on "
        "the same mesh.",
        "",
        "| nu | form | cells | n | DOFs | u_z (mm) | error | FElupe diff | solve (s) |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        ref = [q for q in rows if q["kind"] == "hexahedron27" and q["nu"] == r["nu"]][-1]["uz"]
        diff = "-" if r["diff"] is None else f"{r['diff']:.1e}"
        lines.append(
            f"| {r['nu']} | {r['form']} | {r['kind']} | {r['n']} | {r['dofs']} | "
            f"{1e3 * r['uz']:.4f} | {100 * (r['uz'] / ref - 1):+.2f} % | {diff} | "
            f"{r['wall']:.2f} |"
        )
    out = ROOT / "benchmarks" / "results" / "quadratic_hex.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for ax, (nu, form) in zip(
        axes, ((0.3, "displacement"), (0.499, "mean_dilatation")), strict=True
    ):
        for kind, mark in (("hexahedron", "o-"), ("hexahedron20", "s-"), ("hexahedron27", "^-")):
            sel = [r for r in rows if r["kind"] == kind and r["nu"] == nu]
            ax.semilogx([r["dofs"] for r in sel], [1e3 * r["uz"] for r in sel], mark, label=kind)
            fel = [r for r in sel if r["diff"] is not None]
            ax.semilogx(
                [r["dofs"] for r in fel],
                [1e3 * r["uz"] for r in fel],
                "k+",
                ms=10,
                label="FElupe, same mesh" if kind == "hexahedron" else None,
            )
        ax.set_title(f"nu = {nu}, {form}")
        ax.set_xlabel("DOFs")
        ax.set_ylabel("mean end-face u_z (mm)")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(ROOT / "docs" / "img" / "quadratic_hex.png", dpi=110)


if __name__ == "__main__":
    main()
