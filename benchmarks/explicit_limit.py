"""How close ``Simulation.critical_time_step()`` (the CFL estimate h_min / c) is to the true
explicit stability limit 2 / omega_max, omega_max^2 the largest eigenvalue of M_lumped^-1 K at
rest (Lanczos, scipy's eigsh). The refusal threshold ``STABILITY_MARGIN`` in simulation/checks.py
(time steps above 1.5 x the estimate are refused before the first step) rests on this table:
no mesh here has its true limit above 1.5 x its estimate. Not a timing: no repeats needed.

    python3 benchmarks/explicit_limit.py        # writes benchmarks/results/explicit_limit.md
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import tissuesim as ts
from tissuesim.simulation.checks import STABILITY_MARGIN


def true_limit(sim: ts.Simulation) -> float:
    s = sim.system
    acc = s.evaluate(sim.state.x, 2, False, sim.step_energies(0.0, None, sim.time_step))
    p = acc.pattern
    K = sp.csr_matrix((acc.hessian, p.indices, p.indptr), shape=(p.n, p.n))
    m = sim.bodies["body"].model.mass.lumped
    scale = sp.diags(1.0 / np.sqrt(m))
    top = spla.eigsh(scale @ K @ scale, k=1, which="LA", return_eigenvectors=False)[0]
    return 2.0 / float(np.sqrt(top))


def main() -> None:
    meshes = {
        "rectangle 8x8": ts.rectangle((0, 0), (1, 1), (8, 8)),
        "rectangle 16x4 (cross)": ts.rectangle((0, 0), (4, 1), (16, 4), pattern="cross"),
        "box 4x4x4": ts.box((0, 0, 0), (1, 1, 1), (4, 4, 4)),
        "box 10x2x2": ts.box((0, 0, 0), (2, 0.4, 0.4), (10, 2, 2)),
        "ellipsoid 6": ts.ellipsoid((0, 0, 0), (1.0, 0.6, 0.4), 6),
    }
    rows = []
    for name, mesh in meshes.items():
        for nu in (0.3, 0.45, 0.49):
            material = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=nu)
            sim = ts.Simulation(mesh, material, density=1.0, integrator="explicit", time_step=1e-4)
            estimate = sim.critical_time_step()
            true = true_limit(sim)
            rows.append((name, nu, estimate, true, true / estimate))
            print(
                f"{name:24s} nu {nu:<5} estimate {estimate:.4g} s  true {true:.4g} s  "
                f"true/estimate {true / estimate:.3f}"
            )
    ratios = [r[4] for r in rows]
    lines = [
        "# Explicit stability: CFL estimate against the true limit 2 / omega_max",
        "",
        "`python3 benchmarks/explicit_limit.py` (neo-Hookean, E = 1e3 Pa, rho = 1, lumped mass,",
        "at rest). Time steps above "
        f"{STABILITY_MARGIN} x the estimate are refused before the first step.",
        "",
        "| mesh | nu | estimate (s) | true limit (s) | true / estimate |",
        "| --- | --- | --- | --- | --- |",
        *[f"| {n} | {nu} | {e:.4g} | {t:.4g} | {r:.3f} |" for n, nu, e, t, r in rows],
        "",
        f"true / estimate from {min(ratios):.3f} to {max(ratios):.3f}: within "
        f"{100 * max(abs(r - 1) for r in ratios):.0f} % of the true limit, and no true limit "
        f"reaches {STABILITY_MARGIN} x its estimate, so a refused time step is unstable. In 3D "
        "the true limit lies below the estimate (P1 tetrahedra, lumped mass): explicit 3D runs "
        "want time_step <= 0.85 x the estimate; the blow-up check stops those that do not.",
        "",
    ]
    out = Path(__file__).resolve().parent / "results" / "explicit_limit.md"
    out.write_text("\n".join(lines))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
