"""Time integration against closed forms: Newmark's trapezoidal rule (FEBio's dynamics) on a
free Q1 cube falling under gravity, which it integrates exactly (a constant acceleration, from
the initial acceleration M^-1 f), and on a cantilever swung by an initial velocity, whose
total energy it keeps (Backward Euler's numerical damping would lose it)."""

from __future__ import annotations

import numpy as np

import tissuesim as ts
from tissuesim.verification.result import Check

__all__ = ["checks", "free_fall", "swing"]

G, H, STEPS = 9.81, 0.01, 10


def free_fall(integrator: str = "newmark") -> tuple[float, float]:
    """(g t^2 / 2, the cube's drop) after STEPS steps of H s."""
    mesh = ts.box((0, 0, 0), (0.1, 0.1, 0.1), (2, 2, 2), element="hex")
    law = ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, law, density=1000.0, integrator=integrator, time_step=H,
                        gravity=(0.0, 0.0, -G))  # fmt: skip
    for _ in range(STEPS):
        sim.step()
    t = STEPS * H
    return 0.5 * G * t * t, float(-(sim.positions - mesh.points)[:, 2].mean())


def swing(integrator: str = "newmark") -> tuple[float, float]:
    """(the initial kinetic energy, the total energy after 50 steps) of a cantilever swung by
    a velocity growing linearly from its clamped end."""
    mesh = ts.box((0, 0, 0), (1, 0.2, 0.2), (6, 1, 1), element="hex")
    law = ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, law, density=1000.0, integrator=integrator, time_step=H)
    sim.fix(ts.select.vertices_on_plane(mesh, axis=0, value=0.0))
    v = np.zeros((mesh.n_points, 3))
    v[:, 2] = 0.5 * mesh.points[:, 0]
    sim.set_velocity(v)
    start = 0.5 * float(v.ravel() @ sim.body().model.mass.dot(v.ravel()))
    for _ in range(50):
        record = sim.step()
    return start, record.energies["elastic"] + record.energies["kinetic"]


def checks() -> list[Check]:
    """The drop to round-off (1e-10) and the energy to 1e-4."""
    drop, fallen = free_fall()
    start, end = swing()
    return [
        Check("Newmark free fall, Q1 cube", "drop after 0.1 s (m)", drop, fallen, 1e-10),
        Check("Newmark swinging cantilever, Q1", "total energy after 0.5 s (J)", start, end, 1e-4),
    ]
