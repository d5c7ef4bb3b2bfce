"""What a law from its energy costs: assembly time per element of ``EnergyLaw`` against the
hand-written law it reproduces, at about 1e4 and 1e5 tetrahedra, one thread.

A unit cube of n^3 x 6 P1 tetrahedra at a random deformed state; energy + gradient + Hessian
(``Model.evaluate(x, 2)``) on the batched NumPy path and on the fused Numba path, medians of
``--repeats`` timed round-robin (one call of each per round, so a passing load falls on every
variant alike). Laws: the compressible neo-Hookean written on the invariants and on C's
components, against ``NeoHookean`` (NumPy and its fused kernel); FEBio's uncoupled
Mooney-Rivlin on the isochoric invariants, against ``MooneyRivlin`` (NumPy only: it has no
hand-written kernel). Also the law alone (``material.evaluate(F, 2)`` at the first mesh's F),
with tensortrax (FElupe's automatic differentiation) where it is importable, and the one-off
costs: SymPy's derivation and the kernel's generation and compilation (cold: an empty cache;
warm: loaded from it).

    python3 benchmarks/energy_law.py --divisions 12 26 --repeats 5
writes benchmarks/results/energy_law.md.
"""

from __future__ import annotations

import argparse
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"  # one thread, before NumPy and Numba load

import platform  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from threadpoolctl import threadpool_limits  # noqa: E402

from tissuesim.backend import numba_available  # noqa: E402
from tissuesim.materials import EnergyLaw, MooneyRivlin, NeoHookean  # noqa: E402
from tissuesim.mesh import box  # noqa: E402
from tissuesim.model import Model  # noqa: E402

MU, LAM = 1000.0, 9000.0
NH = "mu/2*(I1 - 3) - mu*log(J) + lam/2*log(J)**2"
NH_C = "mu/2*(C11 + C22 + C33 - 3) - mu*log(J) + lam/2*log(J)**2"
MR = "c1*(I1b - 3) + c2*(I2b - 3) + k/2*log(J)**2"
MR_PARAMS = {"c1": 400.0, "c2": 100.0, "k": 1e4}


NH_REF, MR_REF = "`neo_hookean` (hand-written)", "`mooney_rivlin` (hand-written)"


def laws() -> dict:
    """label -> (material, backends, the hand-written law it is compared with)."""
    both = ("numpy", "numba") if numba_available() else ("numpy",)
    return {
        NH_REF: (NeoHookean(shear_modulus=MU, lame_lambda=LAM), both, NH_REF),
        "EnergyLaw neo-Hookean, invariants": (EnergyLaw(NH, mu=MU, lam=LAM), both, NH_REF),
        "EnergyLaw neo-Hookean, C components": (EnergyLaw(NH_C, mu=MU, lam=LAM), both, NH_REF),
        MR_REF: (MooneyRivlin(**MR_PARAMS), ("numpy",), MR_REF),
        "EnergyLaw Mooney-Rivlin, isochoric": (EnergyLaw(MR, **MR_PARAMS), both, MR_REF),
    }


def medians(fns: dict, repeats: int) -> dict:
    """Median time of each function, round-robin, after one warm-up round."""
    times = {key: [] for key in fns}
    for round_ in range(repeats + 1):
        for key, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            if round_:
                times[key].append(time.perf_counter() - t0)
    return {key: statistics.median(t) for key, t in times.items()}


def tensortrax_law():
    """The neo-Hookean law by tensortrax's hyper-dual numbers (psi, P, A), or None."""
    try:
        import tensortrax as tr
        import tensortrax.math as tm
    except ImportError:
        return None

    def psi(F):
        J = tm.linalg.det(F)
        return MU / 2 * (tm.trace(F.T @ F) - 3) - MU * tm.log(J) + LAM / 2 * tm.log(J) ** 2

    def evaluate(F):  # F (q, 3, 3) -> tensortrax's layout (3, 3, q)
        return tr.hessian(psi, ntrax=1, full_output=True)(np.moveaxis(F, 0, -1).copy())

    return evaluate


def time_assembly(mesh, x: np.ndarray, table: dict, repeats: int) -> dict:
    """(label, backend) -> microseconds per element of ``Model.evaluate(x, 2)``."""
    fns = {}
    for label, (material, backends, _) in table.items():
        for backend in backends:
            model = Model(mesh, material, np.ones(mesh.n_cells), backend=backend)
            fns[(label, backend)] = lambda model=model: model.evaluate(x, 2, False)
    return {key: v / mesh.n_cells * 1e6 for key, v in medians(fns, repeats).items()}


def time_alone(F: np.ndarray, table: dict, repeats: int) -> dict:
    """label -> microseconds per point of ``material.evaluate(F, 2)`` (and tensortrax's)."""
    fns = {label: (lambda m=m: m.evaluate(F, 2)) for label, (m, *_) in table.items()}
    trax = tensortrax_law()
    if trax is not None:
        fns["tensortrax neo-Hookean (automatic differentiation)"] = lambda: trax(F)
    return {key: v / len(F) * 1e6 for key, v in medians(fns, repeats).items()}


def one_off() -> list[str]:
    """SymPy's derivation and the Numba kernel's generation + compilation, cold and warm."""
    rows = []
    for label, psi, params in (("neo-Hookean, invariants", NH, {"mu": MU, "lam": LAM}),
                               ("neo-Hookean, C components", NH_C, {"mu": MU, "lam": LAM}),
                               ("Mooney-Rivlin, isochoric", MR, MR_PARAMS)):  # fmt: skip
        import sympy

        sympy.core.cache.clear_cache()  # SymPy remembers results: time a first derivation
        t0 = time.perf_counter()
        law = EnergyLaw(psi, **params)
        derive = time.perf_counter() - t0
        cells = "- | -"
        if numba_available():
            spent = []
            with tempfile.TemporaryDirectory() as cache:
                os.environ["TISSUESIM_CACHE_DIR"] = cache
                for _ in range(2):  # cold, then warm: a new process reads the file again
                    fresh = EnergyLaw(psi, **params)
                    fresh._derived(3)
                    for name in [m for m in sys.modules if m.startswith("tissuesim_energy_")]:
                        del sys.modules[name]
                    t0 = time.perf_counter()
                    fresh.point_kernel(3)
                    spent.append(time.perf_counter() - t0)
                del os.environ["TISSUESIM_CACHE_DIR"]
            cells = f"{spent[0]:.2f} | {spent[1]:.2f}"
        rows.append(f"| {label} ({law.kind}) | {derive:.2f} | {cells} |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--divisions", type=int, nargs="+", default=[12, 26])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", default=str(ROOT / "benchmarks/results/energy_law.md"))
    args = parser.parse_args()
    with threadpool_limits(1):
        table = laws()
        results, alone = {}, None
        for n in args.divisions:
            mesh = box(divisions=(n, n, n))
            rng = np.random.default_rng(0)
            x = 1.02 * mesh.points.ravel() + 0.003 / n * rng.standard_normal(mesh.points.size)
            results[n] = (mesh.n_cells, time_assembly(mesh, x, table, args.repeats))
            if alone is None:
                F = Model(mesh, table[NH_REF][0], 1.0).kinematics.deformation_gradients(x)
                alone = time_alone(F, table, args.repeats)
        costs = one_off()
    write(args, table, results, alone, costs)


def write(args, table: dict, results: dict, alone: dict, costs: list[str]) -> None:
    divisions = " ".join(str(n) for n in args.divisions)
    lines = [
        "# A law from its energy: assembly cost against the hand-written law",
        "",
        f"`python3 benchmarks/energy_law.py --divisions {divisions} --repeats {args.repeats}`: "
        "unit cube of P1 tetrahedra at a random deformed state, energy + gradient + Hessian "
        f"(`Model.evaluate(x, 2)`), median of {args.repeats} timed round-robin, one thread "
        "(threadpoolctl, NUMBA_NUM_THREADS=1).",
        "",
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, NumPy {np.__version__}; 1-minute load average at "
        f"the end {os.getloadavg()[0]:.2f} (the benchmark itself counts about 1). The machine "
        "is shared: other work ran beside it, so absolute times are noisy; the round-robin "
        "keeps the ratios fairer than the absolute figures.",
        "",
        "Assembly, microseconds per tetrahedron (ratio: against the hand-written law on the same "
        "path; for the neo-Hookean twins the hand-written one is `neo_hookean`, for "
        "Mooney-Rivlin `mooney_rivlin`'s NumPy path):",
        "",
    ]
    sizes = sorted(results)
    head = " | ".join(f"{results[n][0]:,} tets | ratio" for n in sizes)
    lines += [f"| law | path | {head} |", "| --- | --- |" + " ---: | ---: |" * len(sizes)]
    keys = list(results[sizes[0]][1])
    for label, backend in keys:
        base_label = table[label][2]
        cells = []
        for n in sizes:
            t = results[n][1]
            ref = t.get((base_label, backend), t[(base_label, "numpy")])
            cells.append(f"{t[(label, backend)]:.2f} | {t[(label, backend)] / ref:.2f}")
        lines.append(f"| {label} | {backend} | {' | '.join(cells)} |")
    lines += [
        "",
        f"The law alone (`material.evaluate(F, 2)`: psi, P, dP/dF at {results[sizes[0]][0]:,} "
        "points, NumPy), microseconds per point:",
        "",
        "| law | us / point |",
        "| --- | ---: |",
        *[f"| {label} | {v:.2f} |" for label, v in alone.items()],
        "",
        "One-off costs in seconds (3D): SymPy's derivation and lambdify when the law is made; "
        "the fused path's kernel generated and compiled by Numba on a cold cache, and loaded "
        "from the cache (warm; a new process):",
        "",
        "| psi | derivation (s) | kernel, cold (s) | kernel, warm (s) |",
        "| --- | ---: | ---: | ---: |",
        *costs,
    ]
    Path(args.out).write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
