"""Assembly time of Q1 hexahedra against FElupe's on the same mesh and law.

A unit cube of n^3 hexahedra (about 1e4 and 5e4), neo-Hookean (tissuesim's ``neo_hookean`` =
FElupe's ``NeoHookeCompressible`` up to a constant), nu = 0.3, at one random deformed state.
Timed (median of ``--repeats`` after a warm-up): tissuesim's gradient + Hessian into its fixed
CSR pattern (``Model.evaluate(x, 2)``) on the fused Numba path and on the NumPy path, and
FElupe's ``SolidBody.assemble.vector`` + ``assemble.matrix`` (its internal force vector and its
sparse stiffness matrix, 2 x 2 x 2 Gauss points as tissuesim) on the same state. One thread for
BLAS, OpenMP and Numba (set before the imports). The two agree to round-off (checked: the
largest difference of the force vectors is printed).

    python3 benchmarks/hex_costs.py --divisions 22 37 --repeats 5
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


def median_time(fn, repeats: int) -> float:
    fn()  # warm-up (Numba compilation, caches)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def measure(n: int, repeats: int) -> dict:
    import felupe as fe

    mesh = box(divisions=(n, n, n), element="hex")
    rng = np.random.default_rng(0)
    u = 0.02 / n * rng.standard_normal(mesh.points.shape)
    x = (mesh.points + u).ravel()
    material = make_material("neo_hookean", youngs_modulus=E, poisson_ratio=NU)
    out = {"cells": mesh.n_cells, "dofs": mesh.points.size}
    gradients = {}
    for backend in ("numba", "numpy"):
        model = Model(mesh, material, np.ones(mesh.n_cells), backend=backend)
        out[backend] = median_time(lambda m=model: m.evaluate(x, 2, False), repeats)
        gradients[backend] = model.evaluate(x, 1, False).gradient
    mu, lam = material.mu, material.lam
    region = fe.RegionHexahedron(fe.Mesh(mesh.points, mesh.cells, "hexahedron"))
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
    ap.add_argument("--divisions", type=int, nargs="*", default=[22, 37])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    import felupe

    lines = [
        "# Q1 hexahedra: assembly against FElupe (`benchmarks/hex_costs.py`)",
        "",
        f"Gradient + Hessian (tissuesim) / force vector + stiffness matrix (FElupe "
        f"{felupe.__version__}), neo-Hookean, unit cube of n^3 hexahedra, one thread, median of "
        f"{args.repeats}; {platform.processor() or platform.machine()}, "
        f"{os.cpu_count()} cores.",
        "",
        "| n^3 hexahedra | DOFs | tissuesim Numba (s) | tissuesim NumPy (s) | FElupe (s) | "
        "FElupe / Numba | force difference (relative) |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for n in args.divisions:
        r = measure(n, args.repeats)
        lines.append(
            f"| {n}^3 = {r['cells']:,} | {r['dofs']:,} | {r['numba']:.3f} | {r['numpy']:.3f} | "
            f"{r['felupe']:.3f} | {r['felupe'] / r['numba']:.1f} | {r['difference']:.1e} |"
        )
        print(lines[-1], flush=True)
    out = ROOT / "benchmarks" / "results" / "hex_costs.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
