"""How far the derivative through IPC's lagged friction is from whole runs (issue 44).

    python3 benchmarks/friction_sensitivity.py [--write benchmarks/results/friction_sensitivity.md]

A 100 x 100 x 50 mm block (E = 50 kPa, 3 x 3 x 2 boxes of tetrahedra) starting 1.2 mm above a
table (dhat 1 mm), its top pressed 3 mm down and slid 3 mm along over three quasistatic steps,
mu = 0.3: ``ts.sensitivities`` of the table's force, the press's reaction and a bottom
marker's displacement with respect to (E, depth, slide, mu, gap), against central differences
of whole runs (relative step 1e-5), for ``friction_iterations`` 2 (the default) and 6 and
both ``friction_lag`` modes; and the held derivative against whole runs whose lags are the base
run's (``hold_lags``). Each figure: per observation, the largest |error| x parameter over the
largest |value| (the change per unit relative change of a parameter).
"""

from __future__ import annotations

import argparse

import numpy as np

import tissuesim as ts
from tissuesim.identification.held_friction import HeldFriction, hold_lags
from tissuesim.mesh import select

STEPS = 3
PARAMS = {"E": 5e4, "depth": 3e-3, "slide": 3e-3, "mu": 0.3, "gap": 1.2e-3}
PARTS = (slice(0, 3), slice(3, 6), slice(6, None))


def slab(p, iterations=2):
    mesh = ts.box((0, 0, p["gap"]), (0.1, 0.1, 0.05 + p["gap"]), (3, 3, 2))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3),
                        integrator="quasistatic", time_step=1.0 / STEPS)  # fmt: skip
    top = select.vertices_on_plane(mesh, 2, 0.05 + p["gap"])
    sim.add_dirichlet(top, lambda X, t: np.tile([p["slide"] * t, 0.0, -p["depth"] * t],
                                                (len(X), 1)), name="press")  # fmt: skip
    sim.set_contact(dhat=1e-3, stiffness=1e5, friction=p["mu"], friction_iterations=iterations)
    sim.add_obstacle("table", ts.plane((0.05, 0.05, 0.0), (0, 0, 1), 1.0))
    return sim


def run(p, marker, iterations, held=None):
    sim = slab(p, iterations)
    if held is not None:
        hold_lags(sim, held)
    lags = []
    for _ in range(STEPS):
        sim.step()
        lags.append(HeldFriction.of(sim.system.contact))
    f = sim.forces()
    return np.concatenate([f["table"], f["press"], sim.body_displacement()[marker].ravel()]), lags


def central(fn, k):
    d = 1e-5 * PARAMS[k]
    return (fn({**PARAMS, k: PARAMS[k] + d}) - fn({**PARAMS, k: PARAMS[k] - d})) / (2 * d)


def errors(jacobian, fd, values) -> list[float]:
    """Per observation: the largest |error| x parameter over its largest |value|."""
    theta = np.array(list(PARAMS.values()))
    return [
        float((np.abs(jacobian[part] - fd[part]) * theta).max() / np.abs(values[part]).max())
        for part in PARTS
    ]


def cells(found: list[float]) -> str:
    return " / ".join(f"{e:.1e}" for e in found)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", help="write the table to this markdown file")
    args = parser.parse_args()
    mesh = slab(PARAMS).bodies["body"].mesh
    marker = np.flatnonzero(np.isclose(mesh.points[:, 2], mesh.points[:, 2].min()))[:1]
    obs = [ts.ContactForce("table"), ts.Reaction("press"), ts.Displacement(marker)]
    lines = [
        "# Derivatives through friction against whole runs (benchmarks/friction_sensitivity.py)",
        "",
        "Per observation (the table's force / the press's reaction / the marker's displacement):"
        " the largest |error| x parameter over the observation's largest |value|.",
        "",
        "| friction_iterations | friction_lag | against plain whole runs | against whole runs "
        "with the base run's lags |",
        "| ---: | --- | ---: | ---: |",
    ]
    for iterations in (2, 6):
        values, lags = run(PARAMS, marker, iterations)

        def plain_run(q, iterations=iterations):
            return run(q, marker, iterations)[0]

        def held_run(q, iterations=iterations, lags=lags):
            return run(q, marker, iterations, lags)[0]

        def build(q, iterations=iterations):
            return slab(q, iterations)

        plain = np.column_stack([central(plain_run, k) for k in PARAMS])
        held_runs = np.column_stack([central(held_run, k) for k in PARAMS])
        for mode in ("converged", "held"):
            r = ts.sensitivities(build, PARAMS, obs, STEPS, friction_lag=mode)
            jac = r.jacobian[-1]
            lines.append(f"| {iterations} | {mode} | {cells(errors(jac, plain, values))} | "
                         f"{cells(errors(jac, held_runs, values))} |")  # fmt: skip
            print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    print(text)
    if args.write:
        with open(args.write, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
