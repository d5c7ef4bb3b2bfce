"""Coupling energy and the coupled system: values, finite differences, structure."""

from __future__ import annotations

import numpy as np
import pytest


def perturbed(system, rng, scale=0.03):
    c = system.rest_config()
    dq = scale * rng.standard_normal(system.n_dofs)
    return system.retract(c, dq)


def check_fd(system, c, rng, evaluate=None):
    """Gradient and Hessian of phi(dq) = Phi(retract(c, dq)) at dq = 0 against differences of
    the value (directional first differences; mixed second differences, Richardson)."""
    evaluate = evaluate or (lambda x, order: system.evaluate(x, order))
    acc = evaluate(c, 2)
    H = system.pattern.matrix(acc.hessian).toarray()

    def phi(dq):
        return evaluate(system.retract(c, dq), 0).value

    def second(a, b, eps):
        return (
            phi(eps * (a + b)) - phi(eps * (a - b)) - phi(eps * (b - a)) + phi(-eps * (a + b))
        ) / (4 * eps * eps)

    for _ in range(4):
        a, b = rng.standard_normal((2, system.n_dofs))
        eps = 1e-6
        slope = (phi(eps * a) - phi(-eps * a)) / (2 * eps)
        assert slope == pytest.approx(acc.gradient @ a, rel=1e-6)
        fd = (4 * second(a, b, 1e-4) - second(a, b, 2e-4)) / 3
        assert fd == pytest.approx(a @ H @ b, rel=1e-5)
    np.testing.assert_allclose(H, H.T, atol=1e-12 * np.abs(H).max())


@pytest.mark.parametrize("frame_kind", ["rigid", "affine"])
def test_total_energy_matches_finite_differences(frame_kind, scene_factory):
    make_scene = scene_factory
    rng = np.random.default_rng(1)
    system = make_scene(frame_kind)
    c = perturbed(system, rng)
    check_fd(system, c, rng)


def test_coupling_energy_alone_matches_finite_differences(scene_factory):
    make_scene = scene_factory
    """The attachments' energy alone: the full system minus the same bodies without them."""
    from tissuesim.system import System

    rng = np.random.default_rng(2)
    system = make_scene("rigid")
    other = make_scene("rigid")  # independent bodies with the same geometry
    bare = System(other.bodies, other.names, [])
    c = perturbed(system, rng, 0.05)

    def coupling_only(x, order):
        full, bodies = system.evaluate(x, order), bare.evaluate(x, order)
        full.value -= bodies.value
        if order >= 1:
            full.gradient = full.gradient - bodies.gradient
        if order >= 2:
            Hb = bare.pattern.matrix(bodies.hessian).tocoo()
            full.hessian = full.hessian.copy()
            full.hessian[system.pattern.positions(Hb.row, Hb.col)] -= Hb.data
        return full

    value = coupling_only(c, 0).value
    assert value > 0
    assert value == pytest.approx(system.evaluate(c, 0).terms["attachment"], rel=1e-8)
    check_fd(system, c, rng, coupling_only)


def test_coupling_is_zero_at_rest_and_for_rigid_motions(scene_factory):
    make_scene = scene_factory
    system = make_scene("rigid")
    c = system.rest_config()
    acc = system.evaluate(c, 1)
    assert acc.terms["attachment"] < 1e-20
    assert np.abs(acc.gradient).max() < 1e-12
    # translate everything: frames by their origins, organs by their vertices
    d = np.zeros(system.n_dofs)
    d[: system.config_slices[2].start] = np.tile(
        [0.1, -0.2, 0.3], system.config_slices[2].start // 3
    )
    t = system.bodies[2].frame_type.tangent_size
    dq = d[system.tangent_slices[2]].reshape(-1, t)
    dq[:, :3] = [0.1, -0.2, 0.3]
    d[system.tangent_slices[2]] = dq.ravel()
    moved = system.evaluate(system.retract(c, d), 1)
    assert abs(moved.value) < 1e-12
    assert np.abs(moved.gradient).max() < 1e-10


def test_cross_blocks_present_and_needed(scene_factory):
    make_scene = scene_factory
    """Dropping the organ-tissue cross blocks makes the Hessian disagree with the FD."""
    rng = np.random.default_rng(3)
    system = make_scene("rigid")
    c = perturbed(system, rng)
    acc = system.evaluate(c, 2)
    full = system.pattern.matrix(acc.hessian).toarray()
    o, t = slice(0, system.tangent_slices[2].start), system.tangent_slices[2]
    assert np.abs(full[o, t]).max() > 1.0
    system.cross = []
    without = system.pattern.matrix(system.evaluate(c, 2).hessian).toarray()
    assert np.abs(without[o, t]).max() == 0.0


def test_grasper_springs_match_finite_differences(scene_factory):
    """A spring grasper's energy on an organ, inside the coupled system (with the rest)."""
    from tissuesim.energies.vertex_springs import VertexSprings

    rng = np.random.default_rng(4)
    system = scene_factory("rigid")
    upper = system.bodies[1].mesh
    held = upper.point_sets["zmax"]
    springs = VertexSprings(held, 500.0, lambda t: upper.points[held] + [0.01, -0.02, 0.1 * t])
    energy = springs.energy(1.0)
    c = perturbed(system, rng)

    def evaluate(x, order):
        return system.evaluate(x, order, False, [[], [energy], []])

    acc = evaluate(c, 1)
    assert acc.terms["upper.grasper"] > 0
    check_fd(system, c, rng, evaluate)


def _two_blocks(gap: float = 0.0):
    from tissuesim.mesh import box
    from tissuesim.simulation import Simulation

    mat = make_material_for_ties()
    sim = Simulation(integrator="quasistatic", time_step=1.0)
    sim.add_body("lower", box((0, 0, -0.5), (1, 1, 0), (2, 2, 2)), mat, density=10.0)
    sim.add_body("upper", box((0, 0, gap), (1, 1, 0.5 + gap), (3, 3, 2)), mat, density=10.0)
    return sim


def make_material_for_ties():
    from tissuesim.materials import make_material

    return make_material("neo_hookean", youngs_modulus=1000.0, poisson_ratio=0.3)


def test_tie_between_fem_bodies_matches_finite_differences():
    sim = _two_blocks()
    tie = sim.attach("upper", "lower")
    assert tie.n > 0 and np.abs(tie.offset).max() < 1e-12  # touching: no rest offset
    system = sim.system
    rng = np.random.default_rng(5)
    c = perturbed(system, rng, 0.02)
    check_fd(system, c, rng)
    assert system.evaluate(c, 0).terms["ties"] > 0
    # zero at rest and for a rigid translation of both bodies
    rest = system.rest_config()
    moved = rest + np.tile([0.3, -0.1, 0.2], system.n_dofs // 3)
    for x in (rest, moved):
        acc = system.evaluate(x, 1)
        assert acc.terms["ties"] == pytest.approx(0.0, abs=1e-20)


def test_tie_reports_no_contact_clearly():
    sim = _two_blocks(gap=0.1)
    with pytest.raises(ValueError, match="within distance"):
        sim.attach("upper", "lower")
    tie = sim.attach("upper", "lower", distance=0.11)
    np.testing.assert_allclose(tie.offset[:, 2], 0.1, atol=1e-12)  # the gap is kept at rest


def test_frame_body_attachment_matches_finite_differences():
    """A rigid-frame body attached to a FEM block: the whole system's gradient and Hessian
    (attachment, cross blocks through the rotation chart) against differences of the value."""
    from tissuesim.frames.placement import grid_frames
    from tissuesim.frames.sampling import sample_box
    from tissuesim.mesh import box
    from tissuesim.simulation import Simulation

    mat = make_material_for_ties()
    sim = Simulation(integrator="quasistatic", time_step=1.0)
    sim.add_body("lower", box((0, 0, -0.5), (1, 1, 0), (2, 2, 1)), mat, density=10.0)
    sim.add_frame_body(
        "cap",
        grid_frames((0.25, 0.25, 0.1), (0.75, 0.75, 0.1), (2, 2, 1)),
        sample_box((0, 0, 0), (1, 1, 0.2), 0.1),
        mat,
        frame_type="rigid",
    )
    sim.attach("cap", "lower")
    system = sim.system
    assert len(system.attachments) == 1 and system.cross
    rng = np.random.default_rng(11)
    c = perturbed(system, rng, 0.02)
    check_fd(system, c, rng)
    assert system.evaluate(c, 0).terms["attachment"] > 0
