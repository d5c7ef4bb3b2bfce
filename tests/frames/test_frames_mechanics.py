"""Frame-based mechanics: derivatives against finite differences, rigid motions, the affine
patch test, mass, Newton's convergence on a large-rotation bend, explicit vs implicit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tissuesim.backend import numba_available
from tissuesim.frames.model import FrameModel
from tissuesim.frames.placement import grid_frames
from tissuesim.frames.sampling import sample_box
from tissuesim.materials import make_material
from tissuesim.simulation import Simulation

BACKENDS = ["numpy"] + (["numba"] if numba_available() else [])
SAMPLES = sample_box([0.0, 0.0, 0.0], [0.4, 0.4, 1.0], 0.1)
FRAMES = grid_frames([0.1, 0.2, 0.0], [0.3, 0.2, 1.0], (2, 1, 3))


def _model(kind="rigid", law="stvk", backend="numpy", mass="full", nu=0.3):
    material = make_material(law, youngs_modulus=1000.0, poisson_ratio=nu)
    return FrameModel(
        FRAMES, SAMPLES, material, density=2.0, frame_kind=kind, backend=backend, mass_kind=mass
    )


def _perturbed(model, scale=0.03, seed=0):
    dq = np.random.default_rng(seed).normal(size=model.n_dofs) * scale
    return model.frame_type.retract(model.rest_config(), dq)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("kind", ["rigid", "affine"])
@pytest.mark.parametrize("law", ["stvk", "neo_hookean", "fixed_corotated"])
def test_gradient_and_hessian_match_finite_differences(kind, law, backend):
    m = _model(kind, law, backend)
    z = _perturbed(m)
    acc = m.evaluate(z, 2)
    H = m.assembly.q_pattern.matrix(acc.hessian).toarray()

    def energy(dq):
        return m.evaluate(m.frame_type.retract(z, dq), 0).value

    eps = 1e-6
    g_fd = np.array([(energy(eps * e) - energy(-eps * e)) / (2 * eps) for e in np.eye(m.n_dofs)])
    assert np.linalg.norm(g_fd - acc.gradient) <= 1e-7 * np.linalg.norm(acc.gradient)
    # the Hessian in the chart dq -> retract(z, dq), by second differences of the energy,
    # Richardson-extrapolated (error O(eps^4))
    rng = np.random.default_rng(1)

    def second(a, b, eps):
        return (
            energy(eps * (a + b))
            - energy(eps * (a - b))
            - energy(eps * (b - a))
            + energy(-eps * (a + b))
        ) / (4 * eps * eps)

    for _ in range(4):
        a, b = rng.normal(size=(2, m.n_dofs))
        fd = (4 * second(a, b, 1e-4) - second(a, b, 2e-4)) / 3
        assert fd == pytest.approx(a @ H @ b, rel=1e-6)
    assert np.abs(H - H.T).max() <= 1e-12 * np.abs(H).max()


def test_rigid_geometric_term_is_needed():
    """Without the curvature K of the rotation chart the Hessian is wrong away from equilibrium."""
    m = _model("rigid")
    z = _perturbed(m)
    acc_z = m.evaluate_z(z, 2)
    full = m.assembly.hessian(z, acc_z.hessian, acc_z.gradient)
    without = m.assembly.hessian(z, acc_z.hessian, None)
    assert np.abs(full - without).max() > 1e-3 * np.abs(full).max()


def test_numba_and_numpy_agree():
    if "numba" not in BACKENDS:
        pytest.skip("numba not installed")
    z = _perturbed(_model())
    a, b = _model(backend="numpy").evaluate(z, 2), _model(backend="numba").evaluate(z, 2)
    assert a.value == pytest.approx(b.value, rel=1e-13)
    np.testing.assert_allclose(a.gradient, b.gradient, atol=1e-12 * np.abs(a.gradient).max())
    np.testing.assert_allclose(a.hessian, b.hessian, atol=1e-12 * np.abs(a.hessian).max())


@pytest.mark.parametrize("kind", ["rigid", "affine"])
def test_rigid_motion_gives_zero_strain_and_force(kind):
    m = _model(kind)
    R = Rotation.from_rotvec([0.7, -1.9, 0.4]).as_matrix()
    c = np.array([0.3, -2.0, 5.0])
    z = m.frame_type.join(m.frame_positions @ R.T + c, np.broadcast_to(R, (m.n_frames, 3, 3)))
    fields = m.point_fields(z)
    np.testing.assert_allclose(fields["F"], np.broadcast_to(R, fields["F"].shape), atol=1e-13)
    assert np.abs(fields["green_strain"]).max() < 1e-13
    np.testing.assert_allclose(fields["positions"], SAMPLES.points @ R.T + c, atol=1e-13)
    acc = m.evaluate(z, 1)
    assert acc.value < 1e-20
    assert np.abs(acc.gradient).max() < 1e-11


def test_affine_patch_test():
    """Affine frames carrying an affine field reproduce it exactly: F = F0 at every point."""
    m = _model("affine")
    F0 = np.array([[1.2, 0.1, -0.05], [0.03, 0.9, 0.2], [-0.1, 0.04, 1.1]])
    c = np.array([0.1, 0.2, -0.3])
    z = m.frame_type.join(m.frame_positions @ F0.T + c, np.broadcast_to(F0, (m.n_frames, 3, 3)))
    fields = m.point_fields(z)
    np.testing.assert_allclose(fields["F"], np.broadcast_to(F0, fields["F"].shape), atol=1e-13)
    np.testing.assert_allclose(fields["positions"], SAMPLES.points @ F0.T + c, atol=1e-13)
    markers = m.embed(np.array([[0.05, 0.33, 0.71], [0.2, 0.2, 0.5]]))
    np.testing.assert_allclose(markers.positions(z), markers.points @ F0.T + c, atol=1e-13)
    # and rigid frames cannot: a stretch is not a rotation
    assert not np.allclose(F0 @ F0.T, np.eye(3))


@pytest.mark.parametrize("mass", ["full", "lumped"])
@pytest.mark.parametrize("kind", ["rigid", "affine"])
def test_mass_conserves_total_mass_and_is_positive(kind, mass):
    m = _model(kind, mass=mass)
    total = float(m.masses.sum())
    assert total == pytest.approx(2.0 * 0.4 * 0.4 * 1.0, rel=1e-12)
    # a uniform translation of every frame moves every point: zdot^T M_z zdot = m_total |v|^2
    z = _perturbed(m)
    v = np.zeros((m.n_frames, m.frame_type.tangent_size))
    v[:, :3] = [0.0, 3.0, 0.0]
    assert 2 * m.kinetic_energy(z, v.ravel()) == pytest.approx(9.0 * total, rel=1e-12)
    Mq = m.tangent_mass(z).toarray()
    assert np.abs(Mq - Mq.T).max() < 1e-14 * np.abs(Mq).max()
    assert np.linalg.eigvalsh(Mq).min() > 0


def test_gravity_force_is_total_weight():
    sim = Simulation.from_frames(
        FRAMES, SAMPLES, make_material("stvk", youngs_modulus=1e3, poisson_ratio=0.3), density=3.0
    )
    sim.add_gravity([0.0, -9.81, 0.0])
    f = sim.model.external_force(0.0).reshape(-1, 4, 3)[:, 0]  # forces on the frame origins
    assert f.sum(axis=0) == pytest.approx([0.0, -9.81 * 3.0 * 0.16, 0.0], abs=1e-12)


def _bend(steps=4):
    material = make_material("stvk", youngs_modulus=1000.0, poisson_ratio=0.3)
    sim = Simulation.from_frames(
        grid_frames([0.2, 0.2, 0.0], [0.2, 0.2, 1.0], (1, 1, 5)),
        SAMPLES,
        material,
        integrator="quasistatic",
        time_step=1.0 / steps,
    )
    sim.fix_frames([0])
    angle = 2.0 * np.pi / 3.0  # 120 degrees at t = 1

    def tip(t):  # the end of a circular arc of length 1 bent by angle * t about x
        a = angle * t
        if a < 1e-12:
            return np.zeros(3), np.zeros(3)
        rho = 1.0 / a
        y, z = -rho * (1 - np.cos(a)), rho * np.sin(a)
        return np.array([0.0, y, z - 1.0]), np.array([a, 0.0, 0.0])

    sim.prescribe_frames([4], tip)
    return sim


def test_newton_converges_quadratically_on_a_large_rotation_bend():
    sim = _bend()
    records = [sim.step() for _ in range(4)]
    R = sim.frame_rotations[4]
    assert np.degrees(np.arccos((np.trace(R) - 1) / 2)) == pytest.approx(120.0, abs=1e-6)
    # the free frames turned too, beyond 90 degrees next to the tip
    R3 = sim.frame_rotations[3]
    assert np.degrees(np.arccos((np.trace(R3) - 1) / 2)) > 60.0
    for record in records:
        r = np.array(record.residual_norms[-1])
        assert r[-1] <= 1e-8 * r[0]
        # quadratic: once in the asymptotic range, r_{k+1} <= C r_k^2 with log-ratio near 2
        tail = r[r < 1e-2 * r[0]]
        tail = tail[tail > 1e-11 * r[0]]
        if tail.size >= 2:
            orders = np.log(tail[1:] / r[0]) / np.log(tail[:-1] / r[0])
            assert orders.max() > 1.7, r


def test_explicit_and_implicit_agree_at_small_steps():
    material = make_material("stvk", youngs_modulus=1000.0, poisson_ratio=0.3)
    ends = {}
    for integrator, h in (("explicit", 2e-4), ("backward_euler", 2e-4), ("backward_euler", 2e-3)):
        sim = Simulation.from_frames(
            FRAMES, SAMPLES, material, density=100.0, integrator=integrator, time_step=h
        )
        sim.fix_frames(sim.frames_where(lambda X: X[:, 2] < 1e-9))
        sim.add_gravity([0.0, -9.81, 0.0])
        for _ in range(round(0.05 / h)):
            sim.step()
        ends[(integrator, h)] = sim.frame_positions - sim.rest_frames
    ref = ends[("explicit", 2e-4)]
    scale = np.abs(ref).max()
    assert scale > 1e-3  # it did move
    fine = np.abs(ends[("backward_euler", 2e-4)] - ref).max()
    coarse = np.abs(ends[("backward_euler", 2e-3)] - ref).max()
    assert fine < 0.02 * scale
    assert fine < coarse / 5  # first order: ten times smaller step, error about ten times smaller


def test_explicit_rigid_spin_keeps_energy():
    """A free body spinning: explicit steps with the centripetal term keep the kinetic energy."""
    material = make_material("stvk", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = Simulation.from_frames(
        FRAMES, SAMPLES, material, density=10.0, integrator="explicit", time_step=1e-4
    )
    sim.set_velocity(angular=[0.0, 0.0, 2.0])
    e0 = sim.model.kinetic_energy(sim.state.x, sim.state.v)
    for _ in range(200):
        sim.step()
    e = sim.energies()
    assert e["kinetic"] + e["elastic"] == pytest.approx(e0, rel=2e-3)


def test_errors_name_the_problem():
    material = make_material("stvk", youngs_modulus=1e3, poisson_ratio=0.3)
    with pytest.raises(ValueError, match="frame type must be one of"):
        FrameModel(FRAMES, SAMPLES, material, frame_kind="bendy")
    with pytest.raises(ValueError, match="reaches no integration point"):
        FrameModel(np.vstack([FRAMES, [[5.0, 5.0, 5.0]]]), SAMPLES, material, radius=0.5)
    with pytest.raises(ValueError, match="integration point .* reached by 0"):
        FrameModel(FRAMES, SAMPLES, material, radius=0.05)
    sim = Simulation.from_frames(FRAMES, SAMPLES, material, integrator="quasistatic")
    with pytest.raises(ValueError, match="needs supports, fixed or prescribed frames"):
        sim.step()
    sim.fix_frames([0])
    with pytest.raises(ValueError, match="already fixed"):
        sim.fix_frames([0, 1])
    with pytest.raises(ValueError, match="frame indices must be in"):
        sim.fix_frames([99])
    with pytest.raises(ValueError, match="frame mass must be"):
        FrameModel(FRAMES, SAMPLES, material, mass_kind="diagonal")


def test_critical_time_step_counts_springs():
    material = make_material("stvk", youngs_modulus=1e3, poisson_ratio=0.3)
    sim = Simulation.from_frames(FRAMES, SAMPLES, material, density=10.0, integrator="explicit")
    free = sim.critical_time_step()
    sim.add_spring(SAMPLES.points[:5], 1e6)
    assert sim.critical_time_step() < 0.5 * free
