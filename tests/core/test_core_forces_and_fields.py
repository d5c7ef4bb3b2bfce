"""Reactions balance the loads; stresses written for every body match the closed form; every
body kind writes the same field names and shapes."""

from __future__ import annotations

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.frames.placement import grid_frames
from tissuesim.frames.sampling import sample_box
from tissuesim.materials.measures import FIELD_NAMES
from tissuesim.mesh import select
from tissuesim.solve.newton import NewtonOptions
from tissuesim.time.state import State

TIGHT = NewtonOptions(gradient_tolerance=1e-12, absolute_tolerance=1e-12)


def test_fem_support_reaction_balances_gravity_traction_and_nodal_forces():
    mesh = ts.box((0, 0, 0), (1.0, 0.3, 0.2), (6, 2, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=2e4, poisson_ratio=0.3)
    rho, g = 50.0, np.array([0.0, 0.0, -9.81])
    sim = ts.Simulation(mesh, material, density=rho, integrator="quasistatic", newton=TIGHT)
    name = sim.add_dirichlet(select.vertices_on_plane(mesh, axis=0, value=0.0), name="wall")
    sim.add_gravity(g)
    traction = np.array([0.0, 3.0, -5.0])  # Pa on the x = 1 face (0.3 x 0.2 m^2)
    sim.add_traction(select.facets_on_plane(mesh, axis=0, value=1.0), traction)
    tip = select.vertices_on_plane(mesh, axis=0, value=1.0)[:3]
    point = np.array([1.0, 0.0, -2.0])  # N on each of 3 vertices
    sim.add_nodal_forces(tip, point)
    record = sim.step()
    applied = rho * 0.06 * g + traction * 0.3 * 0.2 + 3 * point
    reaction = np.array(record.extra["forces"][name])
    assert name == "wall"
    np.testing.assert_allclose(reaction + applied, 0.0, atol=1e-8 * np.abs(applied).max())
    assert reaction[2] > 0  # the wall holds the beam up


def test_frame_body_fixed_frames_reaction_balances_weight_and_point_forces():
    samples = sample_box([0, 0, 0], [0.4, 0.4, 1.0], 0.1)
    sim = ts.Simulation.from_frames(
        grid_frames([0.2, 0.2, 0.0], [0.2, 0.2, 1.0], (1, 1, 4)),
        samples,
        ts.make_material("stvk", youngs_modulus=1e4, poisson_ratio=0.3),
        density=20.0,
        integrator="quasistatic",
        newton=TIGHT,
    )
    name = sim.fix_frames(sim.frames_where(lambda X: X[:, 2] < 1e-9))
    g = np.array([0.0, -9.81, 0.0])
    sim.add_gravity(g)
    sim.add_point_forces(np.array([[0.2, 0.2, 1.0], [0.1, 0.3, 0.9]]), [0.5, 0.0, 0.25])
    record = sim.step()
    applied = 20.0 * samples.volume * g + 2 * np.array([0.5, 0.0, 0.25])
    reaction = np.array(record.extra["forces"][name])
    np.testing.assert_allclose(reaction + applied, 0.0, atol=1e-8 * np.abs(applied).max())


def _neo_hookean_principal_stress(material, stretches):
    """Closed form: sigma_i = (mu lambda_i^2 + lam ln J - mu) / J for F = diag(stretches)."""
    lam = np.asarray(stretches, dtype=float)
    J = lam.prod()
    return (material.mu * lam**2 + material.lam * np.log(J) - material.mu) / J


def _von_mises(s):
    return np.sqrt(0.5 * ((s[0] - s[1]) ** 2 + (s[1] - s[2]) ** 2 + (s[2] - s[0]) ** 2))


@pytest.mark.parametrize("dim", [2, 3])
def test_fem_homogeneous_stretch_writes_the_closed_form_stress(tmp_path, dim):
    material = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    if dim == 2:
        mesh, stretch = ts.rectangle((0, 0), (1, 1), (3, 3)), [1.3, 0.9]
        principal = [1.3, 0.9, 1.0]  # plane strain: F_33 = 1, sigma_zz from the law
    else:
        mesh, stretch = ts.box((0, 0, 0), (1, 1, 1), (2, 2, 2)), [1.3, 0.9, 1.1]
        principal = stretch
    sim = ts.Simulation(mesh, material)
    x = (mesh.points * np.asarray(stretch)).ravel()
    sim.state = State(0.0, x, np.zeros_like(x))
    sim.run(0, tmp_path, progress=False, render=False)
    out = meshio.read(tmp_path / "body_00000.vtu")
    sigma = out.cell_data["cauchy_stress"][0].reshape(-1, 3, 3)
    expected = _neo_hookean_principal_stress(material, principal)
    np.testing.assert_allclose(sigma, np.broadcast_to(np.diag(expected), sigma.shape), atol=1e-9)
    np.testing.assert_allclose(out.cell_data["von_mises"][0], _von_mises(expected), rtol=1e-12)
    green = 0.5 * (np.asarray(principal) ** 2 - 1)
    E = out.cell_data["green_strain"][0].reshape(-1, 3, 3)
    np.testing.assert_allclose(E, np.broadcast_to(np.diag(green), E.shape), atol=1e-12)
    np.testing.assert_allclose(out.cell_data["J"][0], np.prod(principal), rtol=1e-12)
    # rest points, and the warp by displacement gives the stretched body
    np.testing.assert_allclose(out.points[:, :dim], mesh.points)
    warped = out.points + out.point_data["displacement"]
    np.testing.assert_allclose(warped[:, :dim], mesh.points * np.asarray(stretch), atol=1e-12)


def test_affine_frame_homogeneous_stretch_writes_the_closed_form_stress(tmp_path):
    material = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    samples = sample_box([0, 0, 0], [1, 1, 1], 0.25)
    sim = ts.Simulation.from_frames(
        grid_frames([0.25, 0.25, 0.25], [0.75, 0.75, 0.75], (2, 2, 2)),
        samples,
        material,
        frame_type="affine",
    )
    F = np.diag([1.3, 0.9, 1.1])
    body = sim.body()
    origins = body.rest_frames @ F.T
    z = body.model.frame_type.join(origins, np.broadcast_to(F, (body.n_frames, 3, 3)))
    sim.state = State(0.0, z, np.zeros_like(sim.state.v))
    sim.run(0, tmp_path, progress=False, render=False)
    out = meshio.read(tmp_path / "body_00000.vtu")
    expected = _neo_hookean_principal_stress(material, np.diag(F))
    sigma = out.point_data["cauchy_stress"].reshape(-1, 3, 3)
    np.testing.assert_allclose(sigma, np.broadcast_to(np.diag(expected), sigma.shape), atol=1e-9)
    np.testing.assert_allclose(out.point_data["von_mises"], _von_mises(expected), rtol=1e-10)
    np.testing.assert_allclose(out.points, samples.points)
    np.testing.assert_allclose(
        out.points + out.point_data["displacement"], samples.points @ F.T, atol=1e-12
    )


def test_every_body_kind_writes_the_same_fields(tmp_path):
    lower = ts.box((0, 0, -0.5), (1, 1, 0), (2, 2, 1))
    upper = ts.box((0, 0, 0.2), (1, 1, 0.7), (2, 2, 1))
    organ = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    sim = ts.Simulation(integrator="quasistatic", time_step=0.5, gravity=(0, 0, -9.81))
    sim.add_body("lower", lower, organ, density=10.0)
    sim.add_body("upper", upper, organ, density=10.0)
    sim.add_frame_body(
        "sheet",
        grid_frames([2.25, 0.25, 0.05], [2.75, 0.75, 0.05], (2, 2, 1)),
        sample_box([2, 0, 0], [3, 1, 0.1], 0.1),
        ts.make_material("stvk", youngs_modulus=100.0, poisson_ratio=0.3),
        density=10.0,
    )
    sim.fix("lower", lower.point_sets["zmin"])
    sim.fix_frames([0, 1], body="sheet")
    sim.add_tissue(
        ts.make_material("stvk", youngs_modulus=300.0, poisson_ratio=0.3),
        thickness=0.2,
        spacing=0.1,
        frames=4,
        density=10.0,
    )
    sim.grasp("upper", upper.point_sets["zmax"], (0, 0, 0.02))
    sim.run(1, tmp_path, progress=False, render=False)
    shapes = {}
    for series, data in (("lower", "cell"), ("sheet", "point"), ("tissue_points", "point")):
        out = meshio.read(tmp_path / f"{series}_00001.vtu")
        fields = out.cell_data if data == "cell" else out.point_data
        assert set(FIELD_NAMES) <= set(fields), series
        assert {"displacement", "velocity"} <= set(out.point_data)
        shapes[series] = {
            k: (np.asarray(fields[k][0] if data == "cell" else fields[k])).shape[1:]
            for k in FIELD_NAMES
        }
    assert shapes["lower"] == shapes["sheet"] == shapes["tissue_points"]
    assert shapes["lower"]["cauchy_stress"] == (9,) and shapes["lower"]["J"] == ()


def test_explicit_step_moves_fem_and_frame_bodies_together_in_free_fall():
    """Symplectic Euler under gravity alone: every body falls as x_n = x_0 + g h^2 n (n + 1) / 2
    (no elastic force under a uniform translation), FEM and frame bodies in one system."""
    h, n, g = 1e-3, 5, np.array([0.0, 0.0, -9.81])
    sim = ts.Simulation(integrator="explicit", time_step=h, gravity=g)
    soft = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    sim.add_body("block", ts.box((0, 0, 0), (1, 1, 1), (2, 2, 2)), soft, density=10.0)
    sim.add_frame_body(
        "column",
        grid_frames([2.2, 0.2, 0.0], [2.2, 0.2, 1.0], (1, 1, 3)),
        sample_box([2, 0, 0], [2.4, 0.4, 1.0], 0.1),
        soft,
        density=10.0,
    )
    sim.set_velocity(linear=[0.0, 0.0, 0.0], body="column")
    for _ in range(n):
        sim.step()
    drop = g * h * h * n * (n + 1) / 2
    np.testing.assert_allclose(
        sim.body_positions("block") - sim.bodies["block"].mesh.points,
        np.broadcast_to(drop, (27, 3)),
        atol=1e-12,
    )
    column = sim.bodies["column"]
    np.testing.assert_allclose(
        sim.body_positions("column") - column.model.samples.points,
        np.broadcast_to(drop, (column.model.samples.n, 3)),
        atol=1e-12,
    )
    assert sim.time == pytest.approx(n * h, rel=1e-15)


def test_critical_time_step_counts_the_ties_and_explicit_steps_below_it_stay_bounded():
    soft = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    sim = ts.Simulation(integrator="explicit", time_step=1.0)
    lower = sim.add_body("lower", ts.box((0, 0, -0.5), (1, 1, 0), (2, 2, 2)), soft, density=10.0)
    sim.add_body("upper", ts.box((0, 0, 0), (1, 1, 0.5), (2, 2, 2)), soft, density=10.0)
    free = sim.critical_time_step()
    sim.attach("upper", "lower")
    tied = sim.critical_time_step()
    assert tied < 0.5 * free  # the stiff glue lowers the limit
    sim.fix("lower", lower.mesh.point_sets["zmin"])
    sim.set_velocity(np.tile([0.0, 0.0, 0.1], (27, 1)), body="upper")
    sim.time_step = 0.9 * tied
    for _ in range(200):
        sim.step()
    assert np.abs(sim.body_positions("upper") - sim.bodies["upper"].mesh.points).max() < 0.1
