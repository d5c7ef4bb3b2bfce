"""Quadratic quadrilaterals and hexahedra against FElupe's (QuadraticHexahedron,
TriQuadraticHexahedron, QuadraticQuad, BiQuadraticQuad, 3^d Gauss points as here) on the same
mesh, law and nodal loads: the displacements agree to the solvers' tolerance. Neo-Hookean as in
``test_hex_felupe.py``; the mean-dilatation form of hexahedron20 / quad8 against FElupe's mixed
fields, whose pressure and dilatation are constant per cell for these two (Q2/P0)."""

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.model import Model
from tissuesim.solve.newton import NewtonOptions

fe = pytest.importorskip("felupe")

TIGHT = NewtonOptions(gradient_tolerance=1e-12, absolute_tolerance=1e-14)
ELEMENT = {"quad8": "quad8", "quad9": "quad9", "hexahedron20": "hex20", "hexahedron27": "hex27"}


def region(mesh):
    m = fe.Mesh(mesh.points, mesh.cells, mesh.cell_type)
    return {
        "quad8": fe.RegionQuadraticQuad,
        "quad9": fe.RegionBiQuadraticQuad,
        "hexahedron20": fe.RegionQuadraticHexahedron,
        "hexahedron27": fe.RegionTriQuadraticHexahedron,
    }[mesh.cell_type](m)


def cantilever(kind):
    """A beam 2 x 0.4 (x 0.4) fixed at x = 0, 20 N (per unit thickness in 2D) down on its end
    facets as a uniform traction, through tissuesim's facet integration."""
    from tissuesim.energies.loads import Traction

    if kind.startswith("quad"):
        mesh = ts.rectangle((0, 0), (2.0, 0.4), (6, 1), element=ELEMENT[kind])
        h = [0.0, -20.0 / 0.4]
    else:
        mesh = ts.box((0, 0, 0), (2.0, 0.4, 0.4), (4, 1, 1), element=ELEMENT[kind])
        h = [0.0, 0.0, -20.0 / 0.16]
    fixed = ts.select.vertices_on_plane(mesh, 0, 0.0)
    tip = ts.select.facets_on_plane(mesh, 0, 2.0)
    mat = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    model = Model(mesh, mat, np.ones(mesh.n_cells), backend="numpy")
    nodal = Traction(tip, lambda X, t: np.broadcast_to(h, X.shape)).nodal_forces(model, 0.0)
    return mesh, fixed, nodal


def tissuesim_solve(mesh, E, nu, fixed, nodal, formulation="displacement", steps=2):
    mat = ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=nu)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0 / steps, newton=TIGHT)
    sim.add_body("body", mesh, mat, formulation=formulation)
    sim.fix(fixed, body="body")
    loaded = np.flatnonzero(np.abs(nodal).sum(axis=1) > 0)
    sim.add_nodal_forces(loaded, lambda t: nodal[loaded] * min(t, 1.0), body="body")
    for _ in range(steps):
        assert sim.step().converged
    return sim.displacement


def felupe_solve(mesh, E, nu, fixed, nodal, mixed=False, steps=2):
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    d = mesh.dim
    reg = region(mesh)
    if mixed:
        field = fe.FieldsMixed(reg, n=3, planestrain=d == 2)
        law = fe.NearlyIncompressible(
            fe.NeoHookeCompressible(mu=mu),
            bulk=lam,
            dUdJ=lambda J, b: b * np.log(J) / J,
            d2UdJdJ=lambda J, b: b * (1.0 - np.log(J)) / J**2,
        )
    else:
        u = fe.Field(reg, dim=3) if d == 3 else fe.FieldPlaneStrain(reg, dim=2)
        field = fe.FieldContainer([u])
        law = fe.NeoHookeCompressible(mu=mu, lmbda=lam)
    solid = fe.SolidBody(law, field)
    mask = np.zeros(mesh.n_points, dtype=bool)
    mask[fixed] = True
    bounds = {"fixed": fe.Boundary(field[0], mask=mask)}
    dof0, dof1 = fe.dof.partition(field, bounds)
    loaded = np.flatnonzero(np.abs(nodal).sum(axis=1) > 0)
    load = fe.PointLoad(field, loaded, nodal[loaded])
    for lf in np.linspace(1.0 / steps, 1.0, steps):
        load.update(lf * nodal[loaded])
        res = fe.newtonraphson(
            items=[solid, load], x0=field, dof1=dof1, dof0=dof0, tol=1e-10, maxiter=40, verbose=0
        )
        field = res.x
    return field[0].values


@pytest.mark.parametrize("kind", list(ELEMENT))
def test_cantilever_matches_felupe(kind):
    mesh, fixed, nodal = cantilever(kind)
    assert nodal[:, -1].sum() == pytest.approx(-20.0, rel=1e-12)
    u = tissuesim_solve(mesh, 1e5, 0.3, fixed, nodal)
    v = felupe_solve(mesh, 1e5, 0.3, fixed, nodal)
    tip = ts.select.vertices_on_plane(mesh, 0, 2.0)
    assert u[tip, -1].mean() < -0.05  # a large deflection (geometrically nonlinear)
    assert np.abs(u - v).max() <= 1e-8 * np.abs(v).max()


@pytest.mark.parametrize("kind", ["hexahedron20", "quad8"])
def test_mean_dilatation_matches_felupe_q2p0(kind):
    mesh, fixed, nodal = cantilever(kind)
    u = tissuesim_solve(mesh, 1e5, 0.499, fixed, nodal, "mean_dilatation")
    v = felupe_solve(mesh, 1e5, 0.499, fixed, nodal, mixed=True)
    assert np.abs(u - v).max() <= 1e-8 * np.abs(v).max()
