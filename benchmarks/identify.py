"""What identifying tissue parameters costs and how well it recovers them (issue 44).

    python3 benchmarks/identify.py [--write benchmarks/results/identify.md]

1. Gradients: ``ts.sensitivities`` against central differences of whole runs (relative step
   1e-5) on a P1, a P2 and a hex8 cantilever pressed at its tip (Young's modulus, the press
   depth), and on a P1, a P2 and a hex8 block pressed against a fixed sphere through IPC's
   barrier (its modulus, the press's depth, the sphere's place; observed: the sphere's
   contact force, the table's reaction, three top vertices' displacements), quasistatic: the
   largest difference over the largest derivative (``--gradients-only``: this table alone).
   (Newton's tolerances 100 times tighter than the default for these runs: the differences
   divide the runs' stopping error by the step.)
2. Recovery from synthetic data with 1 % noise (seeded): a liver-like ellipsoid (Neo-Hookean,
   E = 3 kPa, nu = 0.45) indented by a patch of its top pressed 8 mm down in 10 steps, its
   force-depth curve and the bulge of a marker fitting (E, nu); two HGO strips (one pulled along the
   fibres' mean direction, one across) fitting (c, k1, k2, gamma) from their force curves and
   contractions.
3. Cost: runs per fit of ``ts.identify`` against SciPy's least squares with a 2-point
   finite-difference Jacobian (one more run per parameter per Jacobian) on a bar of 2, 4 and 8
   regions of unknown stiffness (markers between them, the pull's force), from the same start;
   and the derivatives' time against the forward run's (medians of the fits' runs).
"""

from __future__ import annotations

import argparse
import statistics

import numpy as np

import tissuesim as ts
from tissuesim.mesh import select

RNG_SEED = 3


def noisy(values: np.ndarray, seed: int = RNG_SEED) -> np.ndarray:
    return values * (1 + 0.01 * np.random.default_rng(seed).standard_normal(values.shape))


# -- 1. gradients ---------------------------------------------------------------------------
def cantilever(p, element="tet", order=1):
    mesh = ts.box((0, 0, 0), (1.0, 0.3, 0.3), (6, 2, 2), element=element, order=order)
    # tight Newton tolerances: the whole runs' differences divide their residual by 1e-5
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3),
                        integrator="quasistatic", time_step=0.25,
                        newton=ts.NewtonOptions().tighter(100))  # fmt: skip
    sim.fix(select.vertices_on_plane(mesh, 0, 0.0), name="wall")
    tip = select.vertices_on_plane(mesh, 0, 1.0)
    sim.add_dirichlet(tip, lambda X, t: np.full(len(X), -p["depth"] * t)[:, None],
                      components=[2], name="press")  # fmt: skip
    return sim


def worst_difference(r, run, params: dict) -> float:
    """The largest difference between the last step's derivatives ``r.jacobian[-1]`` and
    central differences (relative step 1e-5) of whole runs ``run(params)``, over the largest
    derivative, across the parameters."""
    worst = 0.0
    for j, k in enumerate(params):
        d = 1e-5 * params[k]
        fd = (run({**params, k: params[k] + d}) - run({**params, k: params[k] - d})) / (2 * d)
        worst = max(worst, float(np.abs(r.jacobian[-1][:, j] - fd).max() / np.abs(fd).max()))
    return worst


def gradient_check(element: str, order: int) -> float:
    params = {"E": 5e4, "depth": 0.3}
    mesh = cantilever(params, element, order).bodies["body"].mesh
    mid = select.vertices_on_plane(mesh, 0, 0.5)[:3]
    obs = [ts.Reaction("press"), ts.Displacement(mid)]
    r = ts.sensitivities(lambda p: cantilever(p, element, order), params, obs, 4)

    def run(p):
        sim = cantilever(p, element, order)
        for _ in range(4):
            sim.step()
        return np.concatenate([sim.forces()["press"], sim.body_displacement()[mid].ravel()])

    return worst_difference(r, run, params)


def indentation(p, element="tet", order=1):
    """A block pressed by its rising table against a fixed sphere (IPC's barrier, a fixed
    stiffness): its modulus, the press's depth and the sphere's place are the parameters."""
    mesh = ts.box((0, 0, 0), (1.0, 1.0, 0.4), (4, 4, 2), element=element, order=order)
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3),
                        integrator="quasistatic", time_step=0.5,
                        newton=ts.NewtonOptions().tighter(100))  # fmt: skip
    bottom = select.vertices_on_plane(mesh, 2, 0.0)
    sim.add_dirichlet(bottom, lambda X, t: np.tile([0.0, 0.0, p["depth"] * t], (len(X), 1)),
                      name="table")  # fmt: skip
    sim.set_contact(dhat=0.01, stiffness=2e5, mode="barrier")
    # off the block's centre: a press on a symmetric mesh's axis may lean either way
    sim.add_obstacle("probe", ts.sphere((0.43, 0.57, 0.7 + p["gap"]), 0.3))
    return sim


def contact_gradient_check(element: str, order: int) -> float:
    params = {"E": 5e4, "depth": 0.06, "gap": 0.012}
    mesh = indentation(params, element, order).bodies["body"].mesh
    top = np.flatnonzero(np.isclose(mesh.points[:, 2], 0.4))[:3]
    obs = [ts.ContactForce("probe"), ts.Reaction("table"), ts.Displacement(top)]
    r = ts.sensitivities(lambda p: indentation(p, element, order), params, obs, 2)

    def run(p):
        sim = indentation(p, element, order)
        for _ in range(2):
            sim.step()
        f = sim.forces()
        return np.concatenate([f["probe"], f["table"], sim.body_displacement()[top].ravel()])

    return worst_difference(r, run, params)


# -- 2. recovery ----------------------------------------------------------------------------
def liver(p):
    mesh = ts.ellipsoid((0, 0, 0), (0.08, 0.05, 0.03), 8)
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=p["nu"]),
                        integrator="quasistatic", time_step=0.1)  # fmt: skip
    pts = mesh.points
    sim.fix(np.flatnonzero(pts[:, 2] < -0.024), name="table")
    patch = np.flatnonzero((pts[:, 2] > 0.02) & (np.hypot(pts[:, 0], pts[:, 1]) < 0.015))
    sim.add_dirichlet(patch, lambda X, t: np.full(len(X), -0.008 * t)[:, None], components=[2],
                      name="indenter")  # fmt: skip
    return sim


def liver_observations():
    pts = liver({"E": 3e3, "nu": 0.45}).bodies["body"].mesh.points
    side = int(np.argmax(pts[:, 0]))  # the far tip's bulge along x
    return [ts.Reaction("indenter", component=2), ts.Displacement([side], component=0)]


def strips(p):
    law = ts.HolzapfelGasserOgden(c=p["c"], k1=p["k1"], k2=p["k2"], gamma=p["gamma"], k=50 * p["c"])
    sim = ts.Simulation(integrator="quasistatic", time_step=0.2)
    for name, axis in (("along", 0), ("across", 1)):
        size = [0.01, 0.01, 0.002]
        size[axis] = 0.04
        mesh = ts.box((0, 0, 0), size, (8, 2, 1) if axis == 0 else (2, 8, 1), element="hex")
        sim.add_body(name, mesh, law)
        sim.fix(select.vertices_on_plane(mesh, axis, 0.0), body=name, name=f"{name}_clamp")
        end = select.vertices_on_plane(mesh, axis, 0.04)
        sim.add_dirichlet(end, lambda X, t, a=axis: np.full(len(X), 0.006 * t)[:, None],
                          components=[axis], body=name, name=f"{name}_pull")  # fmt: skip
    return sim


def strip_observations():
    sim = strips({"c": 5e3, "k1": 2e4, "k2": 5.0, "gamma": 30.0})
    out = []
    for name, axis in (("along", 0), ("across", 1)):
        pts = sim.bodies[name].mesh.points
        mid = np.flatnonzero(np.isclose(pts[:, axis], 0.02) & np.isclose(pts[:, 1 - axis], 0.01))
        out += [ts.Reaction(f"{name}_pull", component=axis),
                ts.Displacement(mid[:1], body=name, component=1 - axis)]  # fmt: skip
    return out


def recovery(build, truth, start, bounds, observations, steps):
    clean = ts.sensitivities(build, truth, observations, steps).values
    fit = ts.identify(build, start, observations, noisy(clean), steps, bounds=bounds)
    errors = {k: fit.parameters[k] / v - 1 for k, v in truth.items()}
    return fit, errors


# -- 3. cost --------------------------------------------------------------------------------
def bar(p, regions: int, k: int = 0):
    """A bar in ``regions`` parts of their own modulus, pulled; 24 regions tetrahedra, or
    60 k^3 with ``k`` (the derivatives' time on a model of useful size)."""
    divisions = (4 * regions, 1, 1) if not k else (10 * k, k, k)
    mesh = ts.box((0, 0, 0), (1.0, 0.1, 0.1), divisions)
    centres = mesh.points[mesh.cells].mean(axis=1)[:, 0]
    parts = {f"r{i}": (np.flatnonzero((centres >= i / regions) & (centres < (i + 1) / regions)),
                       ts.NeoHookean(youngs_modulus=p[f"E{i}"], poisson_ratio=0.3))
             for i in range(regions)}  # fmt: skip
    sim = ts.Simulation(integrator="quasistatic", time_step=0.5)
    sim.add_body("bar", mesh, ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3),
                 regions=parts)  # fmt: skip
    sim.fix(select.vertices_on_plane(mesh, 0, 0.0), name="wall")
    sim.add_dirichlet(select.vertices_on_plane(mesh, 0, 1.0),
                      lambda X, t: np.full(len(X), 0.1 * t)[:, None], components=[0],
                      name="pull")  # fmt: skip
    return sim


def cost(regions: int) -> dict:
    from scipy.optimize import least_squares

    truth = {f"E{i}": 1e4 * (1 + 0.5 * i) for i in range(regions)}
    start = {k: 2e4 for k in truth}
    build = lambda p: bar(p, regions)  # noqa: E731
    mesh = build(truth).bodies["bar"].mesh
    markers = [int(np.flatnonzero(np.isclose(mesh.points[:, 0], (i + 1) / regions))[0])
               for i in range(regions - 1)]  # fmt: skip
    obs = [ts.Reaction("pull", component=0), ts.Displacement(markers, component=0)]
    steps = 2
    clean = ts.sensitivities(build, truth, obs, steps).values
    data = noisy(clean)
    bounds = {k: (1e3, 1e6) for k in truth}
    fit = ts.identify(build, start, obs, data, steps, bounds=bounds)
    # the same least squares with a finite-difference Jacobian: every residual is a run
    runs = 0
    scale = np.abs(data).max(axis=0)
    names = list(truth)

    def residual(x):
        nonlocal runs
        runs += 1
        sim = build(dict(zip(names, x, strict=True)))
        rows = []
        for _ in range(steps):
            sim.step()
            rows.append(np.concatenate([[sim.forces()["pull"][0]],
                                        sim.body_displacement("bar")[markers, 0]]))  # fmt: skip
        return ((np.array(rows) - data) / scale).ravel()

    lo, hi = np.full(regions, 1e3), np.full(regions, 1e6)
    fd = least_squares(residual, np.array([start[k] for k in names]), jac="2-point",
                       bounds=(lo, hi), x_scale="jac")  # fmt: skip
    ratio, big = (
        timing(build, truth, obs, steps),
        timing(lambda p: bar(p, regions, BIG), truth, [ts.Reaction("pull", component=0)], steps),
    )
    worst = max(abs(fit.parameters[k] / v - 1) for k, v in truth.items())
    worst_fd = max(abs(x / truth[k] - 1) for k, x in zip(names, fd.x, strict=True))
    return {"regions": regions, "runs": fit.runs, "fd_runs": runs, "error": worst,
            "fd_error": worst_fd, "ratio": ratio, "big": big}  # fmt: skip


#: the larger bar's divisions across (60 BIG^3 tetrahedra: 12,960)
BIG = 6


def timing(build, truth, obs, steps) -> float:
    """The derivatives' time against the forward run's, the median of three (the copies'
    builds count to the derivatives)."""
    ratios = []
    for _ in range(3):
        r = ts.sensitivities(build, truth, obs, steps)
        ratios.append(r.sensitivity_s / r.forward_s)
    return statistics.median(ratios)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", help="write the tables to this markdown file")
    parser.add_argument("--gradients-only", action="store_true", help="the first table only")
    parser.add_argument("--cost-only", action="store_true", help="the cost table only")
    args = parser.parse_args()
    lines = ["# Identifying parameters (benchmarks/identify.py)", ""]
    if args.cost_only:
        return finish(args, lines + cost_table())
    lines += ["## Gradients against central differences of whole runs", "",
              "| model | largest difference / largest derivative |", "| --- | --- |"]  # fmt: skip
    for label, element, order in (("P1 tetrahedra", "tet", 1), ("P2 tetrahedra", "tet", 2),
                                  ("hex8", "hex", 1)):  # fmt: skip
        lines.append(f"| {label} | {gradient_check(element, order):.1e} |")
        print(lines[-1], flush=True)
    for label, element, order in (("P1 tetrahedra", "tet", 1), ("P2 tetrahedra", "tet", 2),
                                  ("hex8", "hex", 1)):  # fmt: skip
        worst = contact_gradient_check(element, order)
        lines.append(f"| {label}, pressed against an instrument (barrier contact) | {worst:.1e} |")
        print(lines[-1], flush=True)
    if args.gradients_only:
        print("\n".join(lines))
        return
    lines += ["", "## Recovery from 1 % noise", "",
              "| model | parameters | errors | runs |", "| --- | --- | --- | --- |"]  # fmt: skip
    for label, args_ in (
        ("liver-like ellipsoid, indentation", (liver, {"E": 3e3, "nu": 0.45},
         {"E": 1.5e3, "nu": 0.35}, {"E": (1e2, 1e5), "nu": (0.2, 0.49)},
         liver_observations(), 10)),
        ("HGO strips, along and across", (strips, {"c": 5e3, "k1": 2e4, "k2": 5.0, "gamma": 30.0},
         {"c": 3e3, "k1": 1e4, "k2": 3.0, "gamma": 20.0},
         {"c": (1e2, 1e5), "k1": (1e2, 1e6), "k2": (0.1, 50.0), "gamma": (1.0, 60.0)},
         strip_observations(), 5)),
    ):  # fmt: skip
        fit, errors = recovery(*args_)
        errs = ", ".join(f"{k} {e:+.2%}" for k, e in errors.items())
        lines.append(f"| {label} | {', '.join(errors)} | {errs} | {fit.runs} |")
        print(lines[-1], flush=True)
    finish(args, lines + cost_table())


def cost_table() -> list[str]:
    lines = ["", "## Cost: runs per fit, and the derivatives' time", "",
             "| parameters | runs (ts.identify) | runs (finite-difference least squares) | "
             "worst error (ts / FD) | derivatives / forward run, 24 x p tetrahedra | "
             f"the same, {60 * BIG**3:,} tetrahedra |",
             "| --- | --- | --- | --- | --- | --- |"]  # fmt: skip
    for regions in (2, 4, 8):
        c = cost(regions)
        lines.append(f"| {regions} | {c['runs']} | {c['fd_runs']} | {c['error']:.1e} / "
                     f"{c['fd_error']:.1e} | {c['ratio']:.2f} | {c['big']:.2f} |")  # fmt: skip
        print(lines[-1], flush=True)
    return lines


def finish(args, lines: list[str]) -> None:
    text = "\n".join(lines) + "\n"
    if args.write:
        with open(args.write, "w") as f:
            f.write(text)
    print(text)


if __name__ == "__main__":
    main()
