"""Barrier contact (contact/model.py through ipctk): the energy's gradient and Hessian against
finite differences through the system DOFs, no intersection after any step (checked with an
exact intersection test), CCD stopping a body that would cross the barrier in one step,
obstacle forces balancing the weight at rest, quadratic-enough Newton on contact steps."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts

ipctk = pytest.importorskip("ipctk")

from tissuesim.contact.obstacles import Obstacle, plane, sphere  # noqa: E402
from tissuesim.frames.sampling import box_surface  # noqa: E402

MATERIAL = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)


def two_blocks(gap: float = 0.004, dhat: float = 0.01) -> ts.Simulation:
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01)
    sim.add_body("low", ts.box((0, 0, 0), (1, 1, 0.3), (3, 3, 1)), MATERIAL, density=100.0)
    top = ts.box((0.2, 0.1, 0.3 + gap), (0.9, 0.8, 0.6 + gap), (2, 2, 1))
    sim.add_body("high", top, MATERIAL, density=100.0)
    sim.fix("low", ts.select.vertices_on_plane(sim.bodies["low"].mesh, axis=2, value=0.0))
    sim.set_contact(dhat=dhat)
    return sim


def test_contact_energy_gradient_and_hessian_match_finite_differences():
    sim = two_blocks()
    s = sim.system
    rng = np.random.default_rng(3)
    x = sim.state.x + 1e-4 * rng.standard_normal(sim.state.x.size)
    value, grad, hess = s.contact.evaluate(x, 2)
    assert value > 0 and np.count_nonzero(grad) > 0
    h = 1e-7
    for _ in range(6):
        d = rng.standard_normal(x.size)
        fd = (s.contact.evaluate(x + h * d, 0)[0] - s.contact.evaluate(x - h * d, 0)[0]) / (2 * h)
        assert fd == pytest.approx(grad @ d, rel=1e-5, abs=1e-9 * abs(value))
    # the exact (unprojected) Hessian against differences of the gradient
    exact = s.contact.evaluate(x, 2, project=False)[2]
    for _ in range(3):
        d = rng.standard_normal(x.size)
        fd = (s.contact.evaluate(x + h * d, 1)[1] - s.contact.evaluate(x - h * d, 1)[1]) / (2 * h)
        assert np.linalg.norm(fd - exact @ d) <= 1e-4 * np.linalg.norm(exact @ d)
    # what Newton uses, PSD-projected per collision: positive semi-definite
    eig = np.linalg.eigvalsh(hess.toarray())
    assert eig.min() >= -1e-9 * eig.max()


def test_the_collision_set_of_the_positions_just_built_is_reused():
    """Newton evaluates a point's Hessian right after its line search evaluated the gradient
    there: the same positions take the set just built (the same object), other positions
    build their own, and the reused set gives what a fresh build does (to round-off)."""
    sim = two_blocks()
    contact = sim.system.contact
    x = sim.state.x.copy()
    V = contact.vertices(x)
    first = contact._collisions(V)
    assert len(first) > 0 and contact._collisions(V.copy()) is first
    moved = contact._collisions(contact.vertices(x + 1e-5))
    assert moved is not first
    contact.evaluate(x, 1)  # a line search's trial at x builds the set ...
    built = contact._last_collisions[1]
    value, grad, hess = contact.evaluate(x, 2)  # ... which the Hessian there reuses
    assert contact._last_collisions[1] is built
    contact._last_collisions = None
    fresh = contact.evaluate(x, 2)  # built afresh
    # to round-off: ipctk sums the barrier over threads, in no fixed order
    assert value == pytest.approx(fresh[0], rel=1e-12)
    assert np.allclose(grad, fresh[1], rtol=1e-12, atol=1e-12 * np.abs(grad).max())
    assert abs(hess - fresh[2]).max() <= 1e-12 * abs(hess).max()


def test_the_system_energy_includes_contact_and_its_gradient_is_consistent():
    sim = two_blocks()
    s = sim.system
    x = sim.state.x.copy()
    acc = s.evaluate(x, 2)
    assert acc.terms["contact"] > 0 and acc.extra_hessian is not None
    rng = np.random.default_rng(5)
    d = rng.standard_normal(x.size) * 1e-3
    h = 1e-6
    fd = (s.evaluate(x + h * d, 0).value - s.evaluate(x - h * d, 0).value) / (2 * h)
    assert fd == pytest.approx(acc.gradient @ d, rel=1e-5)


def _above(sim) -> bool:
    """The upper block's lowest vertex is above the lower block's centroid (a block that
    tunnelled through would be intersection-free at the end of a step, but below)."""
    high = sim.body_state("high")[1].reshape(-1, 3)
    low = sim.body_state("low")[1].reshape(-1, 3)
    return bool(high[:, 2].min() > low[:, 2].mean())


def _no_intersection_after_every_step(sim, steps: int) -> list:
    records = []
    for _ in range(steps):
        records.append(sim.step())
        contact = sim.system.contact
        assert not contact.intersecting(sim.state.x, sim.time), f"intersecting at t = {sim.time}"
    return records


def test_a_block_dropped_on_a_block_never_intersects_and_comes_to_rest():
    sim = two_blocks(gap=0.05)
    sim.add_gravity([0.0, 0.0, -9.81])
    records = _no_intersection_after_every_step(sim, 40)
    assert all(r.converged for r in records)
    last = records[-1].extra["contact"]
    assert 0 < last["min_distance"] < sim.system.contact.dhat and last["active_pairs"] > 0
    assert _above(sim)  # it rests on the lower block, it did not tunnel through it


def test_ccd_stops_a_block_that_would_cross_the_barrier_in_one_step():
    """10 m/s towards the other block, 0.01 s steps: it would move 0.1 m, 20 x the gap, in the
    first step; the line search never leaves the intersection-free set."""
    sim = two_blocks(gap=0.005, dhat=0.002)
    high = sim.bodies["high"]
    sim.set_velocity(np.tile([0.0, 0.0, -10.0], (high.mesh.n_points, 1)), body="high")
    records = _no_intersection_after_every_step(sim, 5)
    assert all(r.converged for r in records)
    assert _above(sim)  # it did not pass through


def test_a_block_resting_on_a_floor_obstacle_weighs_its_weight():
    mesh = ts.box((0, 0, 0), (1, 1, 0.5), (3, 3, 2))
    sim = ts.Simulation(mesh, MATERIAL, density=100.0, integrator="backward_euler", time_step=0.05)
    sim.add_gravity([0.0, 0.0, -9.81])
    sim.add_obstacle("floor", plane((0.5, 0.5, -0.004), (0, 0, 1), 4.0))
    sim.set_contact(dhat=0.01)
    records = _no_intersection_after_every_step(sim, 60)
    weight = 100.0 * 0.5 * 9.81
    force = np.asarray(records[-1].extra["forces"]["floor"])
    assert force[2] == pytest.approx(weight, rel=0.02)
    assert np.abs(force[:2]).max() < 0.01 * weight
    assert max(r.newton_iterations for r in records[-10:]) <= 8  # Newton converges at rest


def test_a_moving_probe_indents_and_the_steps_halve_when_it_would_cross():
    mesh = ts.box((0, 0, 0), (1, 1, 0.5), (4, 4, 2))
    sim = ts.Simulation(mesh, MATERIAL, integrator="quasistatic", time_step=0.1)
    sim.fix("body", ts.select.vertices_on_plane(mesh, axis=2, value=0.0))
    probe = sphere((0.5, 0.5, 0.5 + 0.2 + 0.003), 0.2, refinement=2)
    sim.add_obstacle("probe", probe, translation=lambda t: (0.0, 0.0, -0.02 * t))
    sim.set_contact(dhat=0.005)
    records = _no_intersection_after_every_step(sim, 5)
    forces = [r.extra["forces"]["probe"][2] for r in records]
    assert forces[-1] < 0 and np.all(np.diff(forces) < 0)  # pushes down, harder and harder
    assert all(r.converged for r in records)


def test_obstacle_motion_and_validation():
    ob = Obstacle(
        "box",
        box_surface((0, 0, 0), (1, 1, 1), (1, 1, 1)),
        translation=lambda t: (t, 0, 0),
        rotation=lambda t: (0, 0, np.pi / 2 * t),
    )
    x = ob.positions(1.0)
    c = ob.rest.mean(axis=0)
    assert np.allclose(x.mean(axis=0), c + [1, 0, 0])
    assert np.allclose(
        np.linalg.norm(x - x.mean(axis=0), axis=1), np.linalg.norm(ob.rest - c, axis=1)
    )
    with pytest.raises(ts.InputError, match="normal must not be zero"):
        plane((0, 0, 0), (0, 0, 0), 1.0)
    sim = ts.Simulation(ts.box(), MATERIAL, integrator="explicit", time_step=1e-4)
    with pytest.raises(ts.InputError, match="implicit integrator"):
        sim.set_contact()


def test_a_graded_box_is_finer_where_asked_and_stays_positive():
    mesh = ts.box((0, 0, -1), (1, 1, 0), (4, 4, 4), grading=(2.0, 1.0, -2.0))
    xs = np.unique(mesh.points[:, 0])
    zs = np.unique(mesh.points[:, 2])
    np.testing.assert_allclose(xs, (np.arange(5) / 4) ** 2)
    np.testing.assert_allclose(zs, -1 + (1 - (1 - np.arange(5) / 4) ** 2))
    np.testing.assert_allclose(np.unique(mesh.points[:, 1]), np.arange(5) / 4)
    with pytest.raises(ts.MeshError, match="grading must be 1"):
        ts.box(grading=(0.5, 1, 1))


def test_newton_moves_an_obstacle_that_outruns_the_barrier_gap_without_halving():
    """The probe moves 10 x dhat per step into the block: the start of every step is
    unreachable with the probe at its target, so Newton moves it (contact/barrier/kinematic.py)."""
    mesh = ts.box((0, 0, 0), (1, 1, 0.5), (4, 4, 2))
    sim = ts.Simulation(mesh, MATERIAL, integrator="quasistatic", time_step=0.1)
    sim.fix("body", ts.select.vertices_on_plane(mesh, axis=2, value=0.0))
    dhat = 0.001
    probe = sphere((0.5, 0.5, 0.5 + 0.2 + dhat / 2), 0.2, refinement=2)
    sim.add_obstacle("probe", probe, translation=lambda t: (0.0, 0.0, -0.1 * t))  # 0.01 / step
    sim.set_contact(dhat=dhat)
    records = _no_intersection_after_every_step(sim, 4)
    assert all(r.converged and r.substeps == 1 for r in records)
    # the probe's lowest vertex lands on the block's centre vertex (the mirrored box): 34
    assert max(r.newton_iterations for r in records) <= 40
    contact = sim.system.contact
    target = contact.obstacle_positions(sim.time)
    assert np.abs(contact.obstacle_state - target).max() <= 0.01 * dhat  # landed on its target
    depth = records[-1].extra["contact"]["indentation_depth"]["probe"]
    assert depth == pytest.approx(0.04 - dhat / 2, rel=1e-9)
    forces = [-r.extra["forces"]["probe"][2] for r in records]
    assert np.all(np.diff(forces) > 0)


def test_the_augmented_energy_with_obstacle_unknowns_matches_finite_differences():
    """contact/barrier/kinematic.py: bodies' energy + barrier over bodies and obstacle vertices +
    the augmented Lagrangian pull of the obstacles to their targets."""
    from tissuesim.contact.barrier.kinematic import _Augmented

    mesh = ts.box((0, 0, 0), (1, 1, 0.5), (3, 3, 2))
    sim = ts.Simulation(mesh, MATERIAL, integrator="quasistatic", time_step=0.1)
    sim.fix("body", ts.select.vertices_on_plane(mesh, axis=2, value=0.0))
    dhat = 0.01
    sim.add_obstacle(
        "probe", sphere((0.5, 0.5, 0.7 + dhat / 3), 0.2, 1), translation=lambda t: (0, 0, -t)
    )
    sim.set_contact(dhat=dhat)
    system = sim.system
    contact = system.contact
    problem = _Augmented(system, contact, sim.step_energies(0.1, None, 0.1))
    problem.target = contact.obstacle_positions(0.1)
    rng = np.random.default_rng(2)
    problem.multiplier = rng.standard_normal(contact.n_obstacle)
    z = np.concatenate([sim.state.x, contact.obstacle_positions(0.0)])
    z = z + 1e-4 * rng.standard_normal(z.size) * (np.arange(z.size) >= system.n_config)
    acc = problem.evaluate(z, 2, False)
    assert acc.terms["contact"] > 0
    h = 1e-7
    for _ in range(4):
        d = rng.standard_normal(z.size)
        fd = (
            problem.evaluate(z + h * d, 0, False).value
            - problem.evaluate(z - h * d, 0, False).value
        ) / (2 * h)
        assert fd == pytest.approx(acc.gradient @ d, rel=1e-5)
    H = acc.pattern.matrix(acc.hessian) + acc.extra_hessian
    d = rng.standard_normal(z.size)
    fd = (
        problem.evaluate(z + h * d, 1, False).gradient
        - problem.evaluate(z - h * d, 1, False).gradient
    ) / (2 * h)
    assert np.linalg.norm(fd - H @ d) <= 1e-4 * np.linalg.norm(H @ d)


def test_obstacle_names_clash_with_nothing():
    sim = ts.Simulation(ts.box(), MATERIAL, name="liver")
    with pytest.raises(ts.InputError, match="taken"):
        sim.add_obstacle("liver", plane((0, 0, 0), (0, 0, 1), 1.0))
    with pytest.raises(ts.InputError, match="taken"):
        sim.add_obstacle("manifest", plane((0, 0, 0), (0, 0, 1), 1.0))
    sim.add_obstacle("probe", sphere((0, 0, 2), 0.1, 1))
    with pytest.raises(ts.InputError, match="taken"):
        sim.add_obstacle("probe", sphere((0, 0, 3), 0.1, 1))
    with pytest.raises(ts.InputError, match="taken"):
        sim.add_body("probe", ts.box(), MATERIAL)
    assert [o.name for o in sim.obstacles] == ["probe"]


def _closed_and_outward(surface) -> float:
    """Every edge in exactly two triangles, once each way; returns the enclosed volume."""
    T = surface.triangles
    edges = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    directed = {tuple(e) for e in edges.tolist()}
    assert len(directed) == len(edges)  # no directed edge twice: consistently oriented
    assert all((b, a) in directed for a, b in directed)  # closed: each edge has its twin
    P = surface.points
    return float(np.einsum("ij,ij->i", P[T[:, 0]], np.cross(P[T[:, 1]], P[T[:, 2]])).sum() / 6)


def test_capsule_and_cylinder_obstacles_are_closed_outward_surfaces_of_their_shape():
    from tissuesim.contact.obstacles import capsule, cylinder

    a, b, r = np.array([0.1, 0.2, 0.3]), np.array([0.4, -0.1, 0.5]), 0.05
    length = np.linalg.norm(b - a)
    cap = capsule(a, b, r, segments=48)
    volume = _closed_and_outward(cap)
    exact = np.pi * r**2 * length + 4 / 3 * np.pi * r**3
    assert 0.97 * exact < volume < exact  # inscribed facets: slightly less
    s = np.clip((cap.points - a) @ (b - a) / length**2, 0, 1)
    gap = np.linalg.norm(cap.points - (a + s[:, None] * (b - a)), axis=1)
    np.testing.assert_allclose(gap, r, rtol=1e-12)  # every vertex on the capsule
    cyl = cylinder(a, b, r, segments=48)
    assert 0.99 * np.pi * r**2 * length < _closed_and_outward(cyl) < np.pi * r**2 * length
    with pytest.raises(ts.InputError, match="start and end must differ"):
        capsule(a, a, r)
    with pytest.raises(ts.InputError, match="radius"):
        cylinder(a, b, -1.0)


def test_a_capsule_jaw_presses_a_block_and_reports_its_force_but_no_depth():
    from tissuesim.contact.obstacles import capsule

    mesh = ts.box((0, 0, 0), (1, 1, 0.5), (4, 4, 2))
    sim = ts.Simulation(mesh, MATERIAL, integrator="quasistatic", time_step=0.1)
    sim.fix("body", ts.select.vertices_on_plane(mesh, axis=2, value=0.0))
    jaw = capsule((0.1, 0.5, 0.6 + 0.003), (0.9, 0.5, 0.6 + 0.003), 0.1, segments=24)
    sim.add_obstacle("jaw", jaw, translation=lambda t: (0.0, 0.0, -0.02 * t))
    sim.set_contact(dhat=0.005)
    records = _no_intersection_after_every_step(sim, 4)
    assert all("jaw" not in r.extra["contact"]["indentation_depth"] for r in records)
    forces = [r.extra["forces"]["jaw"][2] for r in records]
    assert forces[-1] < 0 and np.all(np.diff(forces[1:]) < 0)


@pytest.mark.parametrize("pattern", ["mirrored", "uniform"])
def test_a_centred_frictionless_press_on_the_default_box_has_no_lateral_force(pattern):
    """A sphere pressed straight down on the centre of a block (friction 0): the default
    mirrored split leaves a lateral force at round-off; the uniform Kuhn split biases it."""
    top = 0.01
    mesh = ts.box((0, 0, 0), (0.02, 0.02, top), (8, 8, 4), pattern=pattern)
    sim = ts.Simulation(mesh, MATERIAL, integrator="quasistatic", time_step=1.0)
    sim.fix("body", ts.select.vertices_on_plane(mesh, axis=2, value=0.0))
    sim.set_contact(dhat=1e-5)
    probe = sphere((0.01, 0.01, top + 0.005 + 1e-5), 0.005, refinement=6, cap_angle=40)
    sim.add_obstacle("probe", probe, translation=lambda t: (0.0, 0.0, -5e-4 * t))
    force = np.array([sim.step() for _ in range(2)][-1].extra["forces"]["probe"])
    lateral = np.hypot(force[0], force[1]) / abs(force[2])
    if pattern == "mirrored":
        assert lateral < 1e-8
    else:
        assert lateral > 1e-3  # the bias the mirrored split removes
