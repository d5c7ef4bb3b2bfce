"""Hertz contact on a coarse mesh: a rigid sphere (R = 10 mm) pressed 100 um into a linear
elastic block (E = 10 kPa, nu = 0.3) with tissuesim's barrier contact, the force against Hertz's
F = 4/3 E* sqrt(R) d^(3/2), E* = E / (1 - nu^2).

The half-space is a quarter block (symmetry planes x = 0, y = 0) 60 mm wide and deep, clamped at
its base, of 10 x 10 x 10 Q1 hexahedra graded towards the contact point: 0.35 mm up to 1.4 mm
from it (the contact radius is a = sqrt(R d) = 1 mm), then each cell 2.3 times the previous one. The
probe is a 15-degree cap of an icosphere of refinement 6 (facets of R / 55), starting dhat / 2
above the block and moved 100 um in one quasistatic step; dhat = 1 um. The depth d is the
probe's travel since it touched, less the barrier's gap; the quarter carries F / 4.

The coarse mesh is stiff: it reads 12.6 % above Hertz (finer meshes of the same kind and the
gmsh-graded meshes of ``benchmarks/hertz.py`` approach Hertz, docs/guide/verify.md), so the
tolerance is 15 %: the row checks the curved contact's force within this mesh's error (E for
E*, 9 %, or the quarter's share fail it), not the last percent. The sharp check of contact is
the flat press (``press``): a rigid plane pushed 100 um into a laterally held block, a uniform
uniaxial strain that Q1 elements represent exactly, so its force must equal M A d / L (M the
oedometric modulus, d the plane's travel less its start dhat / 2 plus the barrier's gap at
the end) to the solver's tolerance: tolerance 1e-4 (it reads 2.5e-5). Both problems run
on the NumPy backend, so that a fresh install's verify does not wait for numba's first
compilation of the hexahedral and contact kernels (11 s here, minutes on a loaded machine; the
answers agree to 1e-13). The mesh is this coarse so that the step takes seconds with SciPy's
SuperLU too.
"""

from __future__ import annotations

import numpy as np

from tissuesim.verification.result import Check

__all__ = ["DEPTH", "PRESS_TOL", "TOL", "checks", "graded_nodes", "indentation", "press"]

R, E, NU = 0.01, 1e4, 0.3
DEPTH, DHAT = 1e-4, 1e-6
H0, R_FINE, GROWTH, SIZE = 0.35e-3, 1.4e-3, 2.3, 0.06
TOL = 0.15
PRESS_SIDE, PRESS_DHAT, PRESS_TOL = 0.01, 1e-7, 1e-4
#: the verification problems' backend: the answer without numba's first compilation
BACKEND = "numpy"


def graded_nodes(h0: float, r_fine: float, growth: float, size: float) -> np.ndarray:
    """Grid coordinates from 0: steps of h0 up to r_fine, then each step ``growth`` times the
    previous one until ``size`` (the last node moved to ``size``)."""
    x = list(np.arange(0.0, r_fine + 0.5 * h0, h0))
    h = h0
    while x[-1] < size:
        h *= growth
        x.append(x[-1] + h)
    x[-1] = size
    return np.array(x)


def indentation(depth: float = DEPTH) -> tuple[float, float]:
    """(the indentation depth d (m), the whole sphere's force (N)) of one quasistatic step."""
    import tissuesim as ts
    from tissuesim.contact.obstacles import sphere

    xs = graded_nodes(H0, R_FINE, GROWTH, SIZE)
    n = len(xs) - 1
    grid = ts.box((0, 0, 0), (1, 1, 1), (n, n, n), element="hex")
    s = np.linspace(0.0, 1.0, n + 1)
    p = grid.points.copy()
    p[:, 0], p[:, 1] = np.interp(p[:, 0], s, xs), np.interp(p[:, 1], s, xs)
    p[:, 2] = -np.interp(1.0 - p[:, 2], s, xs)  # top at z = 0, fine at the top
    mesh = ts.Mesh(p, grid.cells, point_sets=grid.point_sets, facet_sets=grid.facet_sets)
    law = ts.make_material("linear", youngs_modulus=E, poisson_ratio=NU)
    newton = ts.NewtonOptions(max_iterations=150)
    sim = ts.Simulation(
        mesh, law, integrator="quasistatic", time_step=1.0, newton=newton, backend=BACKEND
    )
    tol = 1e-12
    sim.fix("body", np.flatnonzero(p[:, 2] < tol - SIZE), name="base")
    sim.add_dirichlet(np.flatnonzero(p[:, 0] < tol), components=[0], name="symmetry_x")
    sim.add_dirichlet(np.flatnonzero(p[:, 1] < tol), components=[1], name="symmetry_y")
    probe = sphere((0.0, 0.0, R + DHAT / 2), R, refinement=6, cap_angle=15)
    sim.add_obstacle("probe", probe, translation=lambda t: (0.0, 0.0, -depth * t))
    sim.set_contact(dhat=DHAT, surfaces={"body": "zmax"})  # not the symmetry planes
    record = sim.step()
    contact = record.extra["contact"]
    d = contact["indentation_depth"]["probe"] - contact["min_distance"]
    return float(d), float(-4.0 * record.extra["forces"]["probe"][2])


def hertz_force(d: float) -> float:
    """Hertz's force (N) of the rigid sphere at depth ``d`` (m)."""
    return 4.0 / 3.0 * E / (1.0 - NU**2) * np.sqrt(R) * d**1.5


def press(depth: float = DEPTH) -> tuple[float, float]:
    """(the press's depth d (m), its force (N)) of a rigid plane pushed ``depth`` into a cube
    of side PRESS_SIDE on rollers (its sides and base slide, held normal to themselves) in one
    quasistatic step: a uniform uniaxial strain d / L."""
    import tissuesim as ts
    from tissuesim.contact.obstacles import plane

    side, dhat = PRESS_SIDE, PRESS_DHAT
    mesh = ts.box((0, 0, 0), (side, side, side), (2, 2, 2), element="hex")
    law = ts.make_material("linear", youngs_modulus=E, poisson_ratio=NU)
    sim = ts.Simulation(mesh, law, integrator="quasistatic", time_step=1.0, backend=BACKEND)
    p, tol = mesh.points, 1e-12 * side
    for axis, name in ((0, "roller_x"), (1, "roller_y")):
        sides = (p[:, axis] < tol) | (p[:, axis] > side - tol)
        sim.add_dirichlet(np.flatnonzero(sides), components=[axis], name=name)
    sim.add_dirichlet(np.flatnonzero(p[:, 2] < tol), components=[2], name="base")
    start = (side / 2, side / 2, side + dhat / 2)
    sim.add_obstacle(
        "press", plane(start, (0, 0, -1), 3 * side), translation=lambda t: (0, 0, -depth * t)
    )
    sim.set_contact(dhat=dhat, surfaces={"body": "zmax"})
    record = sim.step()
    d = depth - dhat / 2 + record.extra["contact"]["min_distance"]
    return float(d), float(-record.extra["forces"]["press"][2])


def press_force(d: float) -> float:
    """The uniaxial-strain force (N) of the press at depth ``d`` (m): M A d / L, M the
    oedometric modulus E (1 - nu) / ((1 + nu) (1 - 2 nu))."""
    modulus = E * (1.0 - NU) / ((1.0 + NU) * (1.0 - 2.0 * NU))
    return modulus * PRESS_SIDE * d


def checks() -> list[Check]:
    """The flat press's force against uniaxial strain's (``PRESS_TOL``: sharp), and the
    sphere's against Hertz's (``TOL``: within the coarse mesh's 12.6 %)."""
    d, force = press()
    what = f"force (N) at d = {d * 1e6:.1f} um"
    flat = Check("Rigid plane on a block, uniaxial strain, Q1", what, press_force(d), force,
                 PRESS_TOL)  # fmt: skip
    d, force = indentation()
    what = f"force (N) at d = {d * 1e6:.1f} um"
    problem = "Hertz sphere, Q1 10x10x10 (mesh: +12.6 %)"
    return [flat, Check(problem, what, hertz_force(d), force, TOL)]
