"""What the soft-tissue laws cost: assembly time (energy + gradient + Hessian) per integration
point of each law against neo_hookean on the same mesh.

A unit cube of n^3 x 6 P1 tetrahedra (n = 12: 10,368, one point each) at a random deformed
state; ``Model.evaluate(x, 2)`` on the batched NumPy path (the path every law takes; the new
laws have no fused Numba kernel), median of ``--repeats``; and the law alone,
``material.evaluate(F, 2)`` at the same F. neo_hookean on the fused Numba path (what it runs on
by default at this size), timed in the same round-robin, is the last column's reference: each
law's NumPy assembly against it.

    python3 benchmarks/material_costs.py --divisions 12 --repeats 5
writes benchmarks/results/material_costs.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from tissuesim.backend import numba_available  # noqa: E402
from tissuesim.materials.registry import make_material  # noqa: E402
from tissuesim.mesh import box  # noqa: E402
from tissuesim.model import Model  # noqa: E402

LAWS = {
    "neo_hookean": dict(youngs_modulus=3e3, poisson_ratio=0.45),
    "mooney_rivlin": dict(c1=400.0, c2=100.0, k=1e4),
    "coupled_mooney_rivlin": dict(c1=400.0, c2=100.0, k=1e4),
    "ogden": dict(c=[1000.0], m=[6.0], k=1e4),
    "ogden (3 terms)": dict(c=[1000.0, -200.0, 50.0], m=[6.0, -2.0, 12.0], k=1e4),
    "ogden_unconstrained": dict(c=[1000.0], m=[6.0], cp=1e4),
    "yeoh": dict(c1=500.0, c2=50.0, c3=5.0, k=1e4),
    "coupled_yeoh": dict(c1=500.0, c2=50.0, c3=5.0, k=1e4),
    "veronda_westmann": dict(c1=300.0, c2=1.5, k=1e4),
    "coupled_veronda_westmann": dict(c1=300.0, c2=1.5, k=1e4),
    "arruda_boyce": dict(mu=900.0, N=8.0, k=1e4),
    "coupled_arruda_boyce": dict(mu=900.0, N=8.0, k=1e4),
    "holzapfel_gasser_ogden": dict(c=400.0, k1=2000.0, k2=2.0, kappa=0.1, gamma=30.0, k=1e4),
    "hgo_unconstrained": dict(c=400.0, k1=2000.0, k2=2.0, kappa=0.1, gamma=30.0, k=1e4),
    "trans_iso_mooney_rivlin": dict(c1=400.0, c2=100.0, c3=20.0, c4=8.0, c5=600.0, k=1e4),
}


def interleaved_medians(fns: dict, repeats: int) -> dict:
    """Median time of each function, timed round-robin (one call of each per round), so that
    a passing load falls on every law alike; a warm-up round first."""
    times = {key: [] for key in fns}
    for round_ in range(repeats + 1):
        for key, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            if round_:
                times[key].append(time.perf_counter() - t0)
    return {key: statistics.median(t) for key, t in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--divisions", type=int, default=12)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", default=str(ROOT / "benchmarks/results/material_costs.md"))
    args = parser.parse_args()
    n = args.divisions
    mesh = box(divisions=(n, n, n))
    rng = np.random.default_rng(0)
    x = mesh.points.ravel() + 0.003 / n * rng.standard_normal(mesh.points.size)
    assembly, alone = {}, {}
    for label, params in LAWS.items():
        material = make_material(label.split()[0], **params)
        model = Model(mesh, material, np.ones(mesh.n_cells), backend="numpy")
        F = model.kinematics.deformation_gradients(x)
        assembly[label] = lambda model=model: model.evaluate(x, 2, False)
        alone[label] = lambda m=material, F=F: m.evaluate(F, 2)
    q = model.kinematics.weights.size
    fused = None
    if numba_available():
        model = Model(
            mesh, make_material("neo_hookean", **LAWS["neo_hookean"]), 1.0, backend="numba"
        )
        assembly["fused"] = lambda: model.evaluate(x, 2, False)
    t_asm = interleaved_medians(assembly, args.repeats)
    t_law = interleaved_medians(alone, args.repeats)
    if "fused" in t_asm:
        fused = t_asm.pop("fused") / q * 1e6
    rows = [(label, t_asm[label] / q * 1e6, t_law[label] / q * 1e6) for label in LAWS]
    for label, a, b in rows:
        print(f"{label:28s} assembly {a:7.2f} us/pt   law {b:7.2f}")
    base_asm, base_law = rows[0][1], rows[0][2]
    lines = [
        "# Soft-tissue laws: assembly cost per integration point",
        "",
        f"`python3 benchmarks/material_costs.py --divisions {n} --repeats {args.repeats}`: "
        f"unit cube, {mesh.n_cells} P1 tetrahedra ({q} integration points), energy + gradient"
        f" + Hessian (`Model.evaluate(x, 2)`, NumPy path), median of {args.repeats} timed "
        "round-robin over the laws; the law "
        "alone is `material.evaluate(F, 2)` at the same F. Ratios against neo_hookean on the "
        "same path.",
        "",
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, NumPy {np.__version__}; 1-minute load average at the "
        f"end {os.getloadavg()[0]:.2f} (the benchmark itself counts about 1).",
        "",
        "| law | assembly (us / point) | ratio | law alone (us / point) | ratio "
        "| assembly / fused neo_hookean |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    if fused is not None:
        lines.append(f"| `neo_hookean`, fused Numba | {fused:.2f} | {fused / base_asm:.2f} | "
                     "- | - | 1.00 |")  # fmt: skip
    for label, asm, law in rows:
        versus = f"{asm / fused:.1f}" if fused is not None else "-"
        lines.append(
            f"| `{label}` | {asm:.2f} | {asm / base_asm:.2f} | {law:.2f} | {law / base_law:.2f} "
            f"| {versus} |"
        )
    if fused is None:
        lines += ["", "Numba is not installed: no fused neo_hookean reference in this run."]
    Path(args.out).write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
