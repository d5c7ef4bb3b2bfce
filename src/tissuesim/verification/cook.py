"""Cook's membrane (Cook 1974): the tapered panel (0, 0), (48, 44), (48, 60), (0, 44), clamped at
x = 0, a uniform (dead) vertical traction on x = 48, P2 triangles on a mapped n x n grid
(x = 48 s, y = 44 s + t (44 - 28 s)), quasistatic.

Three published references, each for its own setup and point:

* plane stress, E = 1, nu = 1/3, total load 1 (traction 1/16), unit thickness: the vertical
  displacement at the middle of the loaded edge, (48, 52), converges to 23.96 (the value the
  element literature quotes; FinEtools' Cook tutorials track this point and give 23.97). The
  upper corner (48, 60) converges to about 25.2 instead: quoting 23.96 for the corner is a
  common mix-up. Plane stress is the 2D law with lambda* = 2 lambda mu / (lambda + 2 mu).
* plane strain, E = 70, nu = 0.33, traction 6.25: the upper corner (48, 60) against the CoFEA
  benchmark's very fine quadratic results from three independent codes (CalculiX 32.27,
  Code_Aster 32.20, Elmer 32.28); 32.27 is used.
* plane strain, incompressible neo-Hookean (mu = 1: E = 3, nu = 0.5), traction 0.05, large
  deformation: the upper corner against 4.7011 (B. Mueller's 2015 thesis, Universitaet
  Duisburg-Essen, as quoted by Elmer's test ``fem/tests/CooksMembrane3D``). tissuesim's
  neo_hookean at nu = 0.4999 (its volumetric part then changes the result by about 0.01 %)
  with P2 mean dilatation, in 4 load steps.

The meshes are coarse (P2 8 x 8 and 16 x 16); the tolerances cover their discretisation error,
measured on finer meshes (docs/guide/verify.md). The linear cases use the small-strain law
(one step); plane stress is the 2D law with lambda* = 2 lambda mu / (lambda + 2 mu).
"""

from __future__ import annotations

import warnings

import numpy as np

from tissuesim.verification.result import Check

__all__ = ["CASES", "checks", "cook_displacement"]

#: (label, law ("linear" plane stress / strain, or "neo_hookean"), E, nu, traction, point,
#: divisions, reference, tolerance)
CASES = (
    ("plane stress, P2 8x8", "plane stress", 1.0, 1 / 3, 1 / 16, (48.0, 52.0), 8, 23.96, 3e-3),
    ("plane strain, P2 16x16", "plane strain", 70.0, 0.33, 6.25, (48.0, 60.0), 16, 32.27, 1e-2),
    ("neo-Hookean nu 0.4999, P2 8x8", "neo_hookean", 2.0 * 1.4999, 0.4999, 0.05, (48.0, 60.0),
     8, 4.7011, 1e-2),
)  # fmt: skip


def cook_displacement(
    law: str,
    E: float,
    nu: float,
    traction: float,
    point: tuple[float, float],
    n: int,
) -> float:
    """u_y at ``point`` (a node of the mesh) of Cook's membrane on the P2 n x n mesh; ``law``
    "plane stress" or "plane strain" (small strain, one step) or "neo_hookean" (P2 mean
    dilatation, 4 load steps)."""
    import tissuesim as ts
    from tissuesim.mesh import rectangle
    from tissuesim.mesh.checks import validate_mesh
    from tissuesim.mesh.queries.select import facets_on_plane, vertices_on_plane
    from tissuesim.solve.newton import NewtonOptions

    grid = rectangle(divisions=(n, n))
    s, t = grid.points[:, 0], grid.points[:, 1]
    points = np.column_stack([48.0 * s, 44.0 * s + t * (44.0 - 28.0 * s)])
    mesh = validate_mesh(points, grid.cells, source=f"cook({n})", facet_sets={})
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    if law == "plane stress":
        lam = 2 * lam * mu / (lam + 2 * mu)
    steps, formulation = (4, "mean_dilatation") if law == "neo_hookean" else (1, "displacement")
    name = "neo_hookean" if law == "neo_hookean" else "linear"
    material = ts.make_material(name, shear_modulus=mu, lame_lambda=lam)
    newton = NewtonOptions(gradient_tolerance=1e-10)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0 / steps, newton=newton)
    with warnings.catch_warnings():  # the panel is in the benchmark's own units, not metres:
        warnings.filterwarnings("ignore", "body 'cook' is", UserWarning)  # no units warning
        body = sim.add_body("cook", mesh, material, density=1.0, order=2, formulation=formulation)
    body.fix(vertices_on_plane(body.mesh, 0, 0.0), name="clamp")
    load = np.array([0.0, traction])
    body.add_traction(facets_on_plane(body.mesh, 0, 48.0), lambda X, t: load * min(t, 1.0))
    for _ in range(steps):
        sim.step()
    gap = np.linalg.norm(body.mesh.points - np.asarray(point), axis=1)
    node = int(np.argmin(gap))
    if gap[node] > 1e-9:
        raise ValueError(f"cook: no node at {point} on the {n} x {n} mesh")
    return float(sim.displacement[node, 1])


def checks(cases: tuple | None = None) -> list[Check]:
    """One check per case of ``cases`` (default ``CASES``): u_y at the case's point against its
    published reference, within the case's tolerance (relative)."""
    out = []
    for label, law, E, nu, traction, point, n, ref, tol in cases or CASES:
        got = cook_displacement(law, E, nu, traction, point, n)
        where = f"u_y at ({point[0]:g}, {point[1]:g})"
        out.append(Check(f"Cook's membrane, {label}", where, ref, got, tol))
    return out
