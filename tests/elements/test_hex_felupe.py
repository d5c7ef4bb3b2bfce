"""Q1 hexahedra and quadrilaterals against FElupe's on the same mesh, law and loads: the
displacement fields agree to the solvers' tolerance (the same discrete equations, derived and
coded independently). Neo-Hookean: FElupe's ``NeoHookeCompressible(mu, lmbda)`` is tissuesim's
``neo_hookean`` plus the constant 3 mu / 2; the mean-dilatation form against FElupe's mixed
u-p-J fields with p and J constant per cell (``FieldsMixed``, Q1/P0), the same functional."""

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.solve.newton import NewtonOptions

fe = pytest.importorskip("felupe")

TIGHT = NewtonOptions(gradient_tolerance=1e-12, absolute_tolerance=1e-14)


def lame(E, nu):
    return E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))


def tissuesim_solve(mesh, E, nu, fixed, nodal, formulation="displacement", steps=2):
    """Quasistatic solve through the Simulation API; nodal forces (n, d) ramped over steps."""
    mat = ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=nu)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0 / steps, newton=TIGHT)
    sim.add_body("body", mesh, mat, formulation=formulation)
    sim.fix(fixed, body="body")
    loaded = np.flatnonzero(np.abs(nodal).sum(axis=1) > 0)
    sim.add_nodal_forces(loaded, lambda t: nodal[loaded] * min(t, 1.0), body="body")
    for _ in range(steps):
        sim.step()
    return sim.displacement


def felupe_solve(mesh, E, nu, fixed, nodal, mixed=False, steps=2):
    mu, lam = lame(E, nu)
    d = mesh.dim
    m = fe.Mesh(mesh.points, mesh.cells, mesh.cell_type)
    region = fe.RegionHexahedron(m) if d == 3 else fe.RegionQuad(m)
    if mixed:
        field = fe.FieldsMixed(region, n=3, planestrain=d == 2)
        law = fe.NearlyIncompressible(
            fe.NeoHookeCompressible(mu=mu),
            bulk=lam,
            dUdJ=lambda J, b: b * np.log(J) / J,
            d2UdJdJ=lambda J, b: b * (1.0 - np.log(J)) / J**2,
        )
    else:
        u = fe.Field(region, dim=3) if d == 3 else fe.FieldPlaneStrain(region, dim=2)
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
            items=[solid, load],
            x0=field,
            dof1=dof1,
            dof0=dof0,
            tol=1e-10,
            maxiter=40,
            verbose=0,
        )
        field = res.x
    return field[0].values


def cantilever(nx=10, n=2):
    mesh = ts.box((0, 0, 0), (2.0, 0.4, 0.4), (nx, n, n), element="hex")
    fixed = ts.select.vertices_on_plane(mesh, 0, 0.0)
    tip = ts.select.facets_on_plane(mesh, 0, 2.0)
    from tissuesim.energies.loads import quad_traction_nodal_forces

    t = np.broadcast_to([0.0, 0.0, -20.0 / 0.16], (tip.size, 3)).reshape(*tip.shape, 3)
    nodal = quad_traction_nodal_forces(mesh.points, tip, t)  # 20 N down on the end face
    return mesh, fixed, nodal


def cook(n=6):
    """Cook's membrane with Q1 quadrilaterals (mm; a 100 N shear load on the right edge)."""
    r = ts.rectangle((0, 0), (1, 1), (n, n), element="quad")
    xi, eta = r.points[:, 0], r.points[:, 1]
    x = 48.0 * xi
    y = 44.0 * xi + eta * (44.0 + 16.0 * xi - 44.0 * xi)
    from tissuesim.mesh.checks import validate_mesh

    mesh = validate_mesh(np.column_stack([x, y]), r.cells, source="cook")
    fixed = ts.select.vertices_on_plane(mesh, 0, 0.0)
    right = ts.select.facets_on_plane(mesh, 0, 48.0)
    from tissuesim.energies.loads import traction_nodal_forces

    h = np.zeros((len(right), 2, 2))
    h[..., 1] = 100.0 / 16.0
    return mesh, fixed, traction_nodal_forces(mesh.points, right, h)


def test_cantilever_hexahedra_match_felupe():
    mesh, fixed, nodal = cantilever()
    assert nodal[:, 2].sum() == pytest.approx(-20.0, rel=1e-12)
    u = tissuesim_solve(mesh, 1e5, 0.3, fixed, nodal)
    v = felupe_solve(mesh, 1e5, 0.3, fixed, nodal)
    tip = ts.select.vertices_on_plane(mesh, 0, 2.0)
    assert u[tip, 2].mean() < -0.1  # a large deflection (geometrically nonlinear)
    assert np.abs(u - v).max() <= 1e-8 * np.abs(v).max()


def test_cantilever_mean_dilatation_matches_felupe_q1p0():
    mesh, fixed, nodal = cantilever(8, 2)
    u = tissuesim_solve(mesh, 1e5, 0.499, fixed, nodal, "mean_dilatation")
    v = felupe_solve(mesh, 1e5, 0.499, fixed, nodal, mixed=True)
    assert np.abs(u - v).max() <= 1e-8 * np.abs(v).max()


@pytest.mark.parametrize("formulation", ["displacement", "mean_dilatation"])
def test_cook_membrane_quadrilaterals_match_felupe(formulation):
    mesh, fixed, nodal = cook(6)
    mu = 80.194
    nu = 0.49
    E = 2 * mu * (1 + nu)
    u = tissuesim_solve(mesh, E, nu, fixed, nodal, formulation, steps=4)
    v = felupe_solve(mesh, E, nu, fixed, nodal, mixed=formulation != "displacement", steps=4)
    corner = np.flatnonzero(np.isclose(mesh.points[:, 0], 48) & np.isclose(mesh.points[:, 1], 60))
    assert u[corner, 1] > 3.0  # mm (plain Q1 locks: 3.8 against 6.4 with mean dilatation)
    assert np.abs(u - v).max() <= 1e-8 * np.abs(v).max()
