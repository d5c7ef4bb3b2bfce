"""Assembly time of Q1 and quadratic hexahedra against FElupe's on the same mesh and law.

A unit cube of n^3 hexahedra, neo-Hookean (tissuesim's ``neo_hookean`` = FElupe's
``NeoHookeCompressible`` up to a constant), nu = 0.3, at one random deformed state: Q1
(``element="hex"``, 2 x 2 x 2 Gauss points, FElupe's ``RegionHexahedron``; about 1e4 and 5e4
cells) and the quadratic hexahedra (``"hex20"`` serendipity against FElupe's
``RegionQuadraticHexahedron``, ``"hex27"`` triquadratic against its
``RegionTriQuadraticHexahedron``; both 3 x 3 x 3 Gauss points, FElupe's ``GaussLegendre(order=2,
dim=3)``; 11^3 and 18^3 cells, the DOFs of hex27 those of the Q1 rows' 22^3 and 36^3 cells).
Timed (median of ``--repeats`` after a warm-up): tissuesim's gradient + Hessian into its fixed
CSR pattern (``Model.evaluate(x, 2)``) on the fused Numba path and on the NumPy path, and
FElupe's ``SolidBody.assemble.vector`` + ``assemble.matrix`` (its internal force vector and its
sparse stiffness matrix, the same Gauss points as tissuesim) on the same state; each time also
per integration point (cells x Gauss points per cell). One thread for BLAS, OpenMP and Numba
(set before the imports). The two agree to round-off (checked: the largest difference of the
force vectors is printed).

    python3 benchmarks/hex_costs.py --divisions 22 37 --quadratic-divisions 11 18 --repeats 5
writes benchmarks/results/hex_costs.md.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from tissuesim.materials.registry import make_material  # noqa: E402
from tissuesim.mesh import box  # noqa: E402
from tissuesim.model import Model  # noqa: E402

E, NU = 1e4, 0.3
#: element -> (FElupe's cell type, its region, Gauss points per cell in both codes)
ELEMENTS = {
    "hex": ("hexahedron", "RegionHexahedron", 8),
    "hex20": ("hexahedron20", "RegionQuadraticHexahedron", 27),
    "hex27": ("hexahedron27", "RegionTriQuadraticHexahedron", 27),
}


def median_time(fn, repeats: int) -> float:
    fn()  # warm-up (Numba compilation, caches)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def measure(element: str, n: int, repeats: int) -> dict:
    import felupe as fe

    cell_type, region_name, points_per_cell = ELEMENTS[element]
    mesh = box(divisions=(n, n, n), element=element)
    rng = np.random.default_rng(0)
    u = 0.02 / n * rng.standard_normal(mesh.points.shape)
    x = (mesh.points + u).ravel()
    material = make_material("neo_hookean", youngs_modulus=E, poisson_ratio=NU)
    out = {
        "cells": mesh.n_cells,
        "dofs": mesh.points.size,
        "points": mesh.n_cells * points_per_cell,
    }
    gradients = {}
    for backend in ("numba", "numpy"):
        model = Model(mesh, material, np.ones(mesh.n_cells), backend=backend)
        assert model.kinematics.points_per_cell == points_per_cell
        out[backend] = median_time(lambda m=model: m.evaluate(x, 2, False), repeats)
        gradients[backend] = model.evaluate(x, 1, False).gradient
    mu, lam = material.mu, material.lam
    region = getattr(fe, region_name)(fe.Mesh(mesh.points, mesh.cells, cell_type))
    assert len(region.quadrature.weights) == points_per_cell
    field = fe.FieldContainer([fe.Field(region, dim=3)])
    field[0].values[:] = u
    solid = fe.SolidBody(fe.NeoHookeCompressible(mu=mu, lmbda=lam), field)

    def felupe_assembly():
        solid.assemble.vector(field)
        solid.assemble.matrix(field)

    out["felupe"] = median_time(felupe_assembly, repeats)
    r = np.asarray(solid.assemble.vector(field).todense()).ravel()
    scale = np.abs(r).max()
    out["difference"] = max(np.abs(gradients[b] - r).max() / scale for b in gradients)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--divisions", type=int, nargs="*", default=[22, 37], help="Q1 hexahedra")
    ap.add_argument(
        "--quadratic-divisions", type=int, nargs="*", default=[11, 18], help="hex20 and hex27"
    )
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    import felupe

    load_start = os.getloadavg()[0]
    lines = [
        "# Hexahedra: assembly against FElupe (`benchmarks/hex_costs.py`)",
        "",
        f"Gradient + Hessian (tissuesim) / force vector + stiffness matrix (FElupe "
        f"{felupe.__version__}), neo-Hookean, unit cube of n^3 hexahedra (Q1: 2 x 2 x 2 Gauss "
        f"points per cell; hex20 / hex27: 3 x 3 x 3, FElupe's QuadraticHexahedron / "
        f"TriQuadraticHexahedron), one thread, median of {args.repeats}; "
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores. Per point: the "
        f"time divided by the integration points (cells x Gauss points per cell).",
        "",
        "| element | n^3 cells | DOFs | integration points | tissuesim Numba (s) | "
        "tissuesim NumPy (s) | FElupe (s) | per point, Numba / NumPy / FElupe (us) | "
        "FElupe / Numba | NumPy / FElupe | force difference (relative) |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    runs = [("hex", n) for n in args.divisions]
    runs += [(e, n) for e in ("hex20", "hex27") for n in args.quadratic_divisions]
    for element, n in runs:
        r = measure(element, n, args.repeats)
        per_point = " / ".join(
            f"{1e6 * r[k] / r['points']:.2f}" for k in ("numba", "numpy", "felupe")
        )
        lines.append(
            f"| {element} | {n}^3 = {r['cells']:,} | {r['dofs']:,} | {r['points']:,} | "
            f"{r['numba']:.3f} | {r['numpy']:.3f} | {r['felupe']:.3f} | {per_point} | "
            f"{r['felupe'] / r['numba']:.1f} | {r['numpy'] / r['felupe']:.1f} | "
            f"{r['difference']:.1e} |"
        )
        print(lines[-1], flush=True)
    lines += [
        "",
        f"1-minute load average of the machine: {load_start:.2f} at the start, "
        f"{os.getloadavg()[0]:.2f} at the end (this process counts 1).",
    ]
    out = ROOT / "benchmarks" / "results" / "hex_costs.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
