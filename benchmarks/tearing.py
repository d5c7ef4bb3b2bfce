"""Mesh dependence of a FEM body's tearing load (bodies/organ_tear.py): a strip 100 x 20 x 10 mm,
E = 10 kPa, nu = 0.3, strength 3 kPa (largest principal Cauchy stress), pulled 0.5 mm per
quasistatic step, with 10 / 20 / 40 elements along it; ends free to narrow (rollers: a uniform
stress, the predicted load) or clamped (the stress concentrates at the clamps). Per run: the
pull at which the crack starts, the pull at which the strip has parted (the pull's force back to
zero) and the peak force.

    python3 benchmarks/tearing.py
"""

from __future__ import annotations

import numpy as np

import tissuesim as ts

L, W, H, STEP, STRENGTH = 0.1, 0.02, 0.01, 0.0005, 3000.0


def run(divisions: int, clamped: bool, steps: int = 160) -> dict:
    mesh = ts.box(
        (0, 0, 0), (L, W, H), (divisions, max(divisions // 5, 2), max(divisions // 10, 2))
    )
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="quasistatic", time_step=1.0)
    P = mesh.points
    left, right = np.flatnonzero(P[:, 0] < 1e-9), np.flatnonzero(P[:, 0] > L - 1e-9)

    def pull(X, t):
        return np.column_stack([STEP * t + 0 * X[:, 0], 0 * X[:, 0], 0 * X[:, 0]])

    components = None if clamped else (0,)
    sim.add_dirichlet(left, None, components, name="left")
    sim.add_dirichlet(right, pull, components, name="right")
    if not clamped:  # no rigid motion of either piece
        for x0, name in ((0.0, "a"), (L, "b")):
            end = np.abs(P[:, 0] - x0) < 1e-9
            low = end & (P[:, 2] < 1e-9)
            sim.add_dirichlet(np.flatnonzero(low & (P[:, 1] < 1e-9)), None, (1, 2), name="p" + name)
            sim.add_dirichlet(
                np.flatnonzero(low & (P[:, 1] > W - 1e-9)), None, (2,), name="q" + name
            )
    sim.set_tearing(body="body", stress=STRENGTH)
    forces, start, parted = [], None, None
    for k in range(steps):
        record = sim.step()
        forces.append(record.extra["forces"]["right"][0])
        if start is None and record.extra["cuts"]["body.tear"].get("cells_cut", 0):
            start = k
        if len(forces) > 3 and abs(forces[-1]) < 1e-6 * max(forces):
            parted = k
            break
    mm = lambda k: None if k is None else round(1e3 * STEP * (k + 1), 1)  # noqa: E731
    return {"divisions": divisions, "clamped": clamped, "crack_starts_mm": mm(start),
            "parted_mm": mm(parted), "peak_force_N": max(forces)}  # fmt: skip


def main() -> None:
    for clamped in (False, True):
        for divisions in (10, 20, 40):
            print(run(divisions, clamped), flush=True)


if __name__ == "__main__":
    main()
