"""P2 bodies in the rest of the pipeline: contact, ties, dynamics, explicit steps, pictures."""

import numpy as np
import pytest

import tissuesim as ts

MATERIAL = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.45)


def test_a_p2_block_on_a_floor_rests_with_its_weight_and_never_intersects():
    pytest.importorskip("ipctk")
    from tissuesim.contact.obstacles import plane

    mesh = ts.box((0, 0, 0), (1, 1, 0.5), (2, 2, 1), order=2)
    sim = ts.Simulation(integrator="backward_euler", time_step=0.05)
    sim.add_body("body", mesh, MATERIAL, density=100.0, formulation="mean_dilatation")
    sim.add_gravity([0.0, 0.0, -9.81])
    sim.add_obstacle("floor", plane((0.5, 0.5, -0.004), (0, 0, 1), 4.0))
    sim.set_contact(dhat=0.01)
    for _ in range(50):
        record = sim.step()
        assert not sim.system.contact.intersecting(sim.state.x, sim.time)
    weight = 100.0 * 0.5 * 9.81
    assert record.extra["forces"]["floor"][2] == pytest.approx(weight, rel=0.02)


def test_two_p2_bodies_tied_carry_the_upper_ones_weight():
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0, gravity=(0, 0, -9.81))
    lower = sim.add_body("lower", ts.box((0, 0, 0), (1, 1, 0.5), (2, 2, 1)), MATERIAL, order=2)
    upper = sim.add_body(
        "upper", ts.box((0, 0, 0.5), (1, 1, 1.0), (2, 2, 1), order=2), MATERIAL, density=500.0
    )
    sim.fix("lower", lower.mesh.point_sets["zmin"])
    sim.attach("upper", "lower", name="glue")
    record = sim.step()
    assert record.converged
    weight_upper = 500.0 * 0.5 * 9.81
    weight_lower = 1000.0 * 0.5 * 9.81
    forces = sim.forces()
    assert forces["lower.support"][2] == pytest.approx(weight_upper + weight_lower, rel=1e-6)
    assert upper.mesh.order == 2


def test_free_fall_of_a_p2_body_is_exact_and_explicit_steps_run():
    for integrator, mass in (("backward_euler", "consistent"), ("explicit", "lumped")):
        sim = ts.Simulation(integrator=integrator, time_step=1e-4)
        sim.add_body("b", ts.box(divisions=(1, 1, 1), order=2), MATERIAL, mass=mass)
        sim.add_gravity([0.0, 0.0, -9.81])
        for _ in range(10):
            sim.step()
        u = sim.displacement[:, 2]
        # rigid free fall: every node (corners and midside) falls alike
        assert np.ptp(u) < 1e-9
        t = sim.time
        expected = -0.5 * 9.81 * t**2
        # Backward Euler and symplectic Euler differ from the exact parabola by O(h)
        assert u.mean() == pytest.approx(expected, rel=0.15)


def test_a_p2_run_writes_quadratic_series_and_pictures(tmp_path):
    mesh = ts.rectangle((0, 0), (2, 0.5), (4, 1), order=2)
    sim = ts.Simulation(mesh, MATERIAL, integrator="quasistatic", time_step=0.5)
    sim.fix("body", ts.select.vertices_on_plane(mesh, axis=0, value=0.0))
    sim.add_gravity([0.0, -9.81])
    sim.run(2, tmp_path / "out")
    assert (tmp_path / "out" / "final.png").stat().st_size > 1000
    import meshio

    series = sorted((tmp_path / "out").glob("body_*.vtu"))
    back = meshio.read(series[-1])
    assert back.cells[0].type == "triangle6"
    assert set(back.cell_data) >= {"J", "von_mises", "cauchy_stress"}
