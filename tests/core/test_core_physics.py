"""Physics checks of the FEM core: patch test, mass, gravity under Backward Euler, energy
behaviour, uniaxial stretch against the closed form, quadratic Newton convergence."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.energies.loads import ExternalForce
from tissuesim.mesh import select
from tissuesim.model import Model
from tissuesim.solve.linear import SuperLUSolver
from tissuesim.solve.newton import NewtonOptions, minimize


def affine_map(d, seed=0):
    rng = np.random.default_rng(seed)
    A = np.eye(d) + 0.2 * rng.standard_normal((d, d))
    if np.linalg.det(A) <= 0:
        A[0] *= -1
    return A, rng.standard_normal(d)


def test_patch_test_affine_motion_gives_exact_F_and_equilibrium(small_mesh):
    d = small_mesh.dim
    A, b = affine_map(d)
    model = Model(small_mesh, ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), 1.0)
    x = (small_mesh.points @ A.T + b).ravel()
    F = model.kinematics.deformation_gradients(x)
    np.testing.assert_allclose(F, np.broadcast_to(A, F.shape), atol=1e-12)
    # Interior vertices are in equilibrium under a homogeneous stress (zero traction needed
    # only on the boundary): their internal force vanishes.
    g = model.evaluate(x, 1, False).gradient.reshape(-1, d)
    interior = np.setdiff1d(np.arange(small_mesh.n_points), select.boundary_vertices(small_mesh))
    scale = np.abs(g).max()
    assert scale > 1.0
    if interior.size:
        np.testing.assert_allclose(g[interior], 0.0, atol=1e-10 * scale)
    # The boundary forces equal the traction P n integrated over the boundary facets.
    P = ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3).stress(A[None])[0]
    from tissuesim.energies.loads import traction_nodal_forces
    from tissuesim.mesh import facet_measures, facet_normals  # noqa: F401

    facets = select.all_boundary_facets(small_mesh)
    normals = facet_normals(small_mesh.points, facets)
    h = np.repeat((normals @ P.T)[:, None, :], d, axis=1)
    f = traction_nodal_forces(small_mesh.points, facets, h)
    np.testing.assert_allclose(g, f, atol=1e-10 * scale)


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_mass_sums_to_density_times_volume(small_mesh, mass):
    rho = 3.5
    model = Model(small_mesh, ts.LinearElastic(youngs_modulus=1.0, poisson_ratio=0.2), rho, mass)
    d = small_mesh.dim
    volume = np.prod(small_mesh.points.max(0) - small_mesh.points.min(0))
    M = model.mass.matrix()
    ones = np.zeros(model.n_dofs)
    ones[0::d] = 1.0
    assert ones @ M @ ones == pytest.approx(rho * volume, rel=1e-12)
    np.testing.assert_allclose(M.toarray(), M.toarray().T)


def test_consistent_triangle_mass_is_the_notes_matrix():
    mesh = ts.Mesh(np.array([[0.0, 0], [2, 0], [0, 1]]), np.array([[0, 1, 2]]))
    model = Model(mesh, ts.LinearElastic(youngs_modulus=1.0, poisson_ratio=0.2), 1.0)
    M = model.mass.matrix().toarray()[0::2, 0::2]
    np.testing.assert_allclose(M, 1.0 * np.array([[2, 1, 1], [1, 2, 1], [1, 1, 2]]) / 12)


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_free_body_falls_as_backward_euler_predicts(small_mesh, mass):
    d = small_mesh.dim
    g = np.zeros(d)
    g[-1] = -9.81
    h = 0.01
    sim = ts.Simulation(
        small_mesh,
        ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3),
        density=10.0,
        time_step=h,
        mass=mass,
    )
    sim.add_gravity(g)
    for _ in range(5):
        sim.step()
    # Backward Euler: v_n = n h g, x_n = x_0 + h^2 g n (n + 1) / 2, with no deformation.
    n = 5
    np.testing.assert_allclose(
        sim.velocity, np.broadcast_to(n * h * g, sim.velocity.shape), atol=1e-9
    )
    np.testing.assert_allclose(
        sim.displacement,
        np.broadcast_to(h * h * g * n * (n + 1) / 2, sim.velocity.shape),
        atol=1e-9,
    )


def test_backward_euler_energy_does_not_grow_without_forcing(small_mesh):
    sim = ts.Simulation(
        small_mesh,
        ts.CourseNeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
        density=1.0,
        time_step=0.02,
    )
    rng = np.random.default_rng(2)
    sim.set_velocity(rng.standard_normal(small_mesh.points.shape))
    total = []
    for _ in range(30):
        sim.step()
        e = sim.energies()
        total.append(e["elastic"] + e["kinetic"])
    # initial energy is all kinetic
    assert np.all(np.diff(total) <= 1e-9 * total[0])
    assert total[-1] < total[0]


def test_symplectic_euler_conserves_energy_approximately():
    mesh = ts.rectangle(lower=(0, 0), upper=(1, 1), divisions=(4, 4))
    sim = ts.Simulation(
        mesh,
        ts.StVenantKirchhoff(youngs_modulus=100.0, poisson_ratio=0.3),
        density=1.0,
        time_step=2e-3,
        integrator="symplectic_euler",
    )
    rng = np.random.default_rng(5)
    sim.set_velocity(0.1 * rng.standard_normal(mesh.points.shape))
    e0 = sim.energies()["kinetic"]
    for _ in range(200):
        sim.step()
    e = sim.energies()
    assert abs(e["kinetic"] + e["elastic"] - e0) < 0.02 * e0


@pytest.mark.parametrize("name", ["neo_hookean", "stvk", "course_neo_hookean"])
def test_uniaxial_stretch_matches_closed_form(name):
    """A bar pulled by a traction T on x = L, with roller supports, is a homogeneous state
    F = diag(s, t, t) with P11 = T and P22 = P33 = 0: check both against the material law."""
    mesh = ts.box(lower=(0, 0, 0), upper=(2, 1, 1), divisions=(4, 2, 2))
    material = ts.make_material(name, youngs_modulus=100.0, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, integrator="quasistatic", time_step=1.0)
    sim.add_dirichlet(select.vertices_on_plane(mesh, 0, 0.0), components=[0])
    sim.add_dirichlet(select.vertices_on_plane(mesh, 1, 0.0), components=[1])
    sim.add_dirichlet(select.vertices_on_plane(mesh, 2, 0.0), components=[2])
    T = 15.0
    sim.add_traction(select.facets_on_plane(mesh, 0, 2.0), lambda X, t: np.array([T * t, 0, 0]))
    sim.step()
    F = sim.model.kinematics.deformation_gradients(sim.state.x)
    F_mean = F.mean(axis=0)
    np.testing.assert_allclose(F, np.broadcast_to(F_mean, F.shape), atol=1e-8)
    P = material.stress(F_mean[None])[0]
    np.testing.assert_allclose(P, np.diag([T, 0, 0]), atol=1e-7 * T)
    assert F_mean[0, 0] > 1.05 and F_mean[1, 1] < 1.0  # stretched, laterally contracted


def test_newton_converges_quadratically_near_solution():
    mesh = ts.rectangle(lower=(0, 0), upper=(4, 1), divisions=(16, 4))
    model = Model(mesh, ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), 1.0)
    from tissuesim.constraints.dirichlet import DirichletCondition

    left = select.vertices_on_plane(mesh, 0, 0.0)
    model.set_conditions([DirichletCondition(left, lambda X, t: np.zeros_like(X))])
    f = np.zeros((mesh.n_points, 2))
    f[select.vertices_on_plane(mesh, 0, 4.0), 1] = -4.0
    load = ExternalForce(f.ravel())

    def evaluate(x, order, project):
        return model.evaluate(x, order, project, (load,))

    options = NewtonOptions(
        hessian_projection="never", gradient_tolerance=1e-13, absolute_tolerance=1e-13
    )
    x, result = minimize(
        evaluate,
        mesh.points.ravel(),
        model.elimination,
        SuperLUSolver(),
        options,
        force_scale=model.force_scale,
        length_scale=model.length_scale,
    )
    assert result.converged
    g = np.array(result.gradient_norms)
    tip = x.reshape(-1, 2)[select.vertices_on_plane(mesh, 0, 4.0), 1].mean() - 0.5
    assert tip < -0.2  # a real large-deflection problem
    # near the solution each residual is below C * previous^2 (quadratic), with full steps
    tail = [(g[k], g[k + 1]) for k in range(len(g) - 1) if g[k] < 1e-1 * g[0] and g[k + 1] > 1e-10]
    assert len(tail) >= 2
    ratios = [b / a**2 for a, b in tail]
    assert max(ratios) < 10 * min(ratios) + 1.0
    assert all(b < a * 0.1 for a, b in tail)
    assert result.step_lengths[-1] == 1.0
