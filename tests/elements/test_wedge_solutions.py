"""Wedges solving: a cantilever of wedges against the same cantilever of the hexahedra they were
cut from (both converge to one answer), and a bent wedge beam against FElupe.

FElupe has no wedge element; its generic ``Region`` takes any element, so the FElupe side is
given the wedge's shape functions and FEBio's 6-point rule written out here, and what is
compared is the rest: FElupe's own kinematics, law, assembly and Newton on the same mesh, law
and nodal loads (skipped without FElupe, as ``test_hex_felupe.py``)."""

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.energies.loads import Traction
from tissuesim.model import Model
from tissuesim.solve.newton import NewtonOptions

TIGHT = NewtonOptions(gradient_tolerance=1e-12, absolute_tolerance=1e-14)


def end_deflection(element: str, n: int) -> float:
    """The beam 2 x 0.4 x 0.4 m of 5n x n x n hexahedra (or the 2 wedges of each), clamped at
    x = 0, 1 N down on its end face as a uniform traction; the end face's mean u_z in mm."""
    beam = ts.box((0, 0, 0), (2.0, 0.4, 0.4), (5 * n, n, n), element=element)
    mat = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0, newton=TIGHT)
    sim.add_body("beam", beam, mat)
    sim.fix(ts.select.vertices_on_plane(beam, 0, 0.0), body="beam")
    sim.add_traction(ts.select.facets_on_plane(beam, 0, 2.0), (0, 0, -1 / 0.16), body="beam")
    assert sim.step().converged
    return 1e3 * sim.displacement[ts.select.vertices_on_plane(beam, 0, 2.0), 2].mean()


def test_cantilever_of_wedges_converges_with_the_hexahedra_it_was_cut_from():
    """n = 2, 4: hexahedra -11.036, -12.210 mm; wedges -10.965, -12.179 mm (0.64 %, then
    0.26 % apart); their Richardson extrapolations (second order) -12.602 and -12.584 agree to
    0.15 % (n = 8, not run here: -12.573 and -12.563, 0.08 % apart)."""
    hexes = [end_deflection("hex", n) for n in (2, 4)]
    wedges = [end_deflection("wedge", n) for n in (2, 4)]
    assert hexes == pytest.approx([-11.036, -12.210], abs=2e-3)
    assert wedges == pytest.approx([-10.965, -12.179], abs=2e-3)
    assert abs(wedges[1] - hexes[1]) < 0.5 * abs(wedges[0] - hexes[0])  # closing in
    assert abs(wedges[1] / hexes[1] - 1) < 0.003

    def richardson(coarse, fine):
        return fine + (fine - coarse) / 3

    assert richardson(*wedges) == pytest.approx(richardson(*hexes), rel=0.002)


#: FEBio's FEPenta6G6 points (r, s, t) and weights
RULE = (
    np.array([[a, b, c] for c in (-(3**-0.5), 3**-0.5) for a, b in ((1, 1), (4, 1), (1, 4))])
    / [6, 6, 1],
    np.full(6, 1 / 6),
)


def felupe_wedge(fe):
    """FElupe's element for its generic Region: N = L(r, s) (1 -+ t) / 2, L = (1 - r - s, r, s)."""

    class FelupeWedge(fe.Element):
        def __init__(self):
            self.points = np.array(
                [[0, 0, -1], [1, 0, -1], [0, 1, -1], [0, 0, 1], [1, 0, 1], [0, 1, 1]], dtype=float
            )
            self.cells = np.arange(6).reshape(1, -1)
            self.cell_type = "wedge"

        def function(self, rst):
            r, s, t = rst
            L = np.array([1 - r - s, r, s])
            return np.concatenate([L * (1 - t) / 2, L * (1 + t) / 2])

        def gradient(self, rst):
            r, s, t = rst
            L = np.array([1 - r - s, r, s])
            dL = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
            low = np.column_stack([dL * (1 - t) / 2, -L / 2])
            high = np.column_stack([dL * (1 + t) / 2, L / 2])
            return np.concatenate([low, high])

    return FelupeWedge()


def test_bent_wedge_beam_matches_felupe():
    """10 x 2 x 2 hexahedra cut into 160 wedges, neo-Hookean, clamped, 20 N down on the end
    face (nodal loads from tissuesim's facet integration): the end deflects 0.22 m (large
    rotation) and the displacements agree to 1e-9 of the largest (measured: 2e-15)."""
    fe = pytest.importorskip("felupe")
    mesh = ts.box((0, 0, 0), (2.0, 0.4, 0.4), (10, 2, 2), element="wedge")
    E, nu, steps = 1e5, 0.3, 2
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    fixed = ts.select.vertices_on_plane(mesh, 0, 0.0)
    end = ts.select.facets_on_plane(mesh, 0, 2.0)
    mat = ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=nu)
    h = Traction(end, lambda X, t: np.broadcast_to([0, 0, -20 / 0.16], X.shape))
    nodal = h.nodal_forces(Model(mesh, mat, np.ones(mesh.n_cells), backend="numpy"), 0.0)
    loaded = np.flatnonzero(np.abs(nodal).sum(axis=1) > 0)
    assert nodal[:, 2].sum() == pytest.approx(-20.0, rel=1e-12)

    sim = ts.Simulation(integrator="quasistatic", time_step=1.0 / steps, newton=TIGHT)
    sim.add_body("body", mesh, mat)
    sim.fix(fixed, body="body")
    sim.add_nodal_forces(loaded, lambda t: nodal[loaded] * min(t, 1.0), body="body")
    for _ in range(steps):
        assert sim.step().converged
    u = sim.displacement

    rule = fe.quadrature.Scheme(*RULE)
    region = fe.Region(fe.Mesh(mesh.points, mesh.cells, "wedge"), felupe_wedge(fe), rule)
    field = fe.FieldContainer([fe.Field(region, dim=3)])
    solid = fe.SolidBody(fe.NeoHookeCompressible(mu=mu, lmbda=lam), field)
    mask = np.zeros(mesh.n_points, dtype=bool)
    mask[fixed] = True
    dof0, dof1 = fe.dof.partition(field, {"fixed": fe.Boundary(field[0], mask=mask)})
    load = fe.PointLoad(field, loaded, nodal[loaded])
    for lf in np.linspace(1 / steps, 1.0, steps):
        load.update(lf * nodal[loaded])
        field = fe.newtonraphson(
            items=[solid, load], x0=field, dof1=dof1, dof0=dof0, tol=1e-10, verbose=0
        ).x
    v = field[0].values
    tip = ts.select.vertices_on_plane(mesh, 0, 2.0)
    assert u[tip, 2].mean() < -0.2
    assert np.abs(u - v).max() <= 1e-9 * np.abs(v).max()
