"""Rigid bodies in the Newton solve (rigid/, simulation/rigid.py): the reduced gradient and
Hessian against finite differences, a prescribed rigid motion equal to the same motion
prescribed on the vertices, free DOFs in equilibrium with their load, free fall and rotation
against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.errors import InputError
from tissuesim.materials import make_material
from tissuesim.mesh import box
from tissuesim.simulation import Simulation

MESH = box((0, 0, 0), (1, 1, 1), (2, 2, 2))
MAT = make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
P = MESH.points
BOTTOM = np.flatnonzero(P[:, 2] < 1e-9)
TOP = np.flatnonzero(P[:, 2] > 1 - 1e-9)


def _block(integrator: str = "quasistatic", **rigid) -> Simulation:
    sim = Simulation(integrator=integrator, time_step=0.5)
    sim.add_body("b", MESH, MAT)
    sim.fix(BOTTOM, body="b")
    sim.add_rigid_body("plate", vertices={"b": TOP}, **rigid)
    return sim


def test_reduced_gradient_and_hessian_against_finite_differences():
    """Phi along retractions from a deformed, rotated state: the first difference against the
    reduced gradient, the second against the reduced Hessian's quadratic form (which is what
    a symmetric Hessian on a rotation chart is: its value on every direction). No moment: a
    constant moment in space does no path-independent work under 3D rotations (it is a load
    vector, as FEBio's; exact about a fixed axis, as in the test of a moment below)."""
    sim = _block(fixed=("x",), force=(0.3, -0.2, -5.0))
    s = sim.system
    rng = np.random.default_rng(1)
    free = np.ones(s.n_dofs, dtype=bool)
    free[s.elimination.dofs] = False
    dq = np.where(free, rng.normal(scale=0.05, size=s.n_dofs), 0.0)
    c = s.apply_prescribed(s.retract(s.rest_config(), dq), 0.0)
    s.load_time = 0.0

    def phi(cc):
        return s.evaluate(cc, 0).value

    acc = s.evaluate(c, 2)
    pat = s.pattern
    import scipy.sparse as sp

    H = sp.csr_matrix((acc.hessian, pat.indices, pat.indptr), shape=(pat.n, pat.n))
    for _ in range(4):
        d = np.where(free, rng.normal(size=s.n_dofs), 0.0)
        e = 1e-5
        plus, minus = phi(s.retract(c, e * d)), phi(s.retract(c, -e * d))
        slope = (plus - minus) / (2 * e)
        assert slope == pytest.approx(acc.gradient[free] @ d[free], rel=1e-6)
        e = 1e-4
        curvature = (plus_2 := phi(s.retract(c, e * d))) + phi(s.retract(c, -e * d)) - 2 * phi(c)
        del plus_2
        assert curvature / e**2 == pytest.approx(d @ (H @ d), rel=1e-4)


def test_the_spring_of_a_soft_prescribed_dof_against_finite_differences():
    """With contact a prescribed rigid DOF is pulled to its value by a spring (rigid/body.py
    soft): its energy, gradient and Hessian along retractions that move the plate's centre
    (its rotations held), against finite differences."""
    sim = _block(fixed=("rx", "ry", "rz"), prescribed={"z": lambda t: -0.1 * t})
    s = sim.system
    (plate,) = s.rigid
    plate.soft, plate.length = 5e3, 1.0
    s.set_prescribed()
    assert 2 not in plate.prescribed_dofs  # pulled, not set
    s.load_time = 0.7
    rng = np.random.default_rng(2)
    free = np.ones(s.n_dofs, dtype=bool)
    free[s.elimination.dofs] = False
    c = s.retract(s.rest_config(), np.where(free, rng.normal(scale=0.02, size=s.n_dofs), 0.0))
    acc = s.evaluate(c, 2)
    import scipy.sparse as sp

    H = sp.csr_matrix((acc.hessian, s.pattern.indices, s.pattern.indptr), shape=(s.n_dofs,) * 2)
    spring = plate.spring_forces(c[s.rigid_config_slices[0]], 0.7)
    assert spring[2] == pytest.approx(-5e3 * (c[s.rigid_config_slices[0]][2] - 1.0 + 0.07))
    for _ in range(3):
        d = np.where(free, rng.normal(size=s.n_dofs), 0.0)
        e = 1e-6
        plus, minus = (
            s.evaluate(s.retract(c, e * d), 0).value,
            s.evaluate(s.retract(c, -e * d), 0).value,
        )
        assert (plus - minus) / (2 * e) == pytest.approx(acc.gradient[free] @ d[free], rel=1e-6)
        e = 1e-4
        plus, minus = (
            s.evaluate(s.retract(c, e * d), 0).value,
            s.evaluate(s.retract(c, -e * d), 0).value,
        )
        assert (plus + minus - 2 * acc.value) / e**2 == pytest.approx(d @ (H @ d), rel=1e-4)


def test_prescribed_rigid_motion_equals_it_prescribed_on_the_vertices():
    """A plate pressed and turned through its rigid body and the same motion as a Dirichlet
    condition on its vertices: the same positions and the same force; the moment is the
    vertices' reactions' moment about the centre."""
    angle = 0.3
    a = _block(fixed=("x", "y", "rx", "ry"), prescribed={"z": lambda t: -0.2 * t, "rz": angle})
    b = Simulation(integrator="quasistatic", time_step=0.5)
    b.add_body("b", MESH, MAT)
    b.fix(BOTTOM, body="b")
    centre = P[TOP].mean(axis=0)

    def motion(X, t):
        c, s = np.cos(angle), np.sin(angle)
        R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        return (X - centre) @ R.T + centre - X + np.array([0, 0, -0.2 * t])

    b.add_dirichlet(TOP, motion, body="b", name="top")
    for sim in (a, b):
        sim.step()
        sim.step()
    xa, xb = a.body_positions("b"), b.body_positions("b")
    assert np.abs(xa - xb).max() < 1e-12
    fa, fb = a.forces(), b.forces()
    assert np.allclose(fa["plate"], fb["top"], rtol=1e-10, atol=1e-9)
    # the moment about the centre of the vertices' reactions in the Dirichlet run
    g = b._last_gradient.reshape(-1, 3)[TOP]
    moment = np.cross(xb[TOP] - (centre + [0, 0, -0.2]), g).sum(axis=0)
    assert np.allclose(fa["plate.moment"], moment, atol=1e-9)
    assert fa["plate.b"] == pytest.approx(fb["top"])  # the interface's force on the block
    centre_now, R = a.rigid_state("plate")
    assert centre_now == pytest.approx(centre + [0, 0, -0.2])
    assert R[0, 1] == pytest.approx(-np.sin(angle))


def test_free_dofs_balance_their_load_and_newton_converges_quadratically():
    """A plate free to sink and tilt under a dead force and moment (x, y and rz held): its
    free DOFs carry no reaction, the support under the block and the plate's held DOFs
    together hold the force, and Newton's last residuals fall quadratically."""
    force = np.array([0.0, 0.0, -150.0])
    sim = _block(fixed=("x", "y", "rz"), force=force, moment=(20.0, -12.0, 0.0))
    sim.time_step = 1.0
    sim.step()
    f = sim.forces()
    assert f["plate"][2] == pytest.approx(0.0, abs=1e-7)
    assert f["plate.moment"][:2] == pytest.approx([0.0, 0.0], abs=1e-7)
    total = np.asarray(f["b.support"]) + np.asarray(f["plate"]) + force
    assert total == pytest.approx(np.zeros(3), abs=1e-6)
    res = sim.history[-1].residual_norms[-1]
    assert len(res) >= 4 and res[-1] < 1e-6
    rates = [np.log(res[k + 1] / res[k]) / np.log(res[k] / res[k - 1]) for k in (-3, -2)]
    assert max(rates) > 1.8, res
    c, R = sim.rigid_state("plate")
    assert c[2] < 0.95 and abs(R[0, 2]) > 1e-3  # it sank and tilted


def test_a_rigid_body_falls_as_backward_euler_says():
    """A whole body made rigid, under gravity, no support: Backward Euler's centre
    x_n+1 = x_n + h v_n+1, v_n+1 = v_n + h g, exactly, and no rotation."""
    sim = Simulation(integrator="backward_euler", time_step=0.01, gravity=(0, 0, -9.81))
    sim.add_body("bone", MESH, MAT, density=1500.0)
    sim.add_rigid_body("bone_rigid", ["bone"])
    x0, _ = sim.rigid_state("bone_rigid")
    for _ in range(5):
        sim.step()
    n, h = 5, 0.01
    drop = 9.81 * h * h * n * (n + 1) / 2  # sum over k of h * (k h g)
    c, R = sim.rigid_state("bone_rigid")
    assert c - x0 == pytest.approx([0, 0, -drop], rel=1e-9, abs=1e-12)
    assert R == pytest.approx(np.eye(3), abs=1e-12)
    assert x0 == pytest.approx([0.5, 0.5, 0.5])  # the centre of mass


def test_a_moment_turns_a_free_body_as_its_inertia_says():
    """A free cube of side 1 and mass m under a moment M about z: theta(t) -> M t^2 / (2 J)
    with J = m / 6; Backward Euler's error is O(h) (a few per cent at 50 steps)."""
    sim = Simulation(integrator="backward_euler", time_step=0.002)
    sim.add_body("cube", MESH, MAT, density=6.0)
    sim.add_rigid_body("cube_rigid", ["cube"], moment=(0.0, 0.0, 0.5))
    for _ in range(50):
        sim.step()
    _, R = sim.rigid_state("cube_rigid")
    theta = np.arctan2(R[1, 0], R[0, 0])
    t, J = 0.1, 6.0 / 6.0
    assert theta == pytest.approx(0.5 * t * t / (2 * J), rel=0.05)
    assert abs(R[0, 2]) < 1e-9 and abs(R[2, 2] - 1) < 1e-9


def test_refusals_name_what_is_wrong():
    sim = Simulation(integrator="quasistatic")
    sim.add_body("b", MESH, MAT)
    with pytest.raises(InputError, match="DOFs are x, y, z, rx, ry, rz"):
        sim.add_rigid_body("r", ["b"], fixed=("u",))
    with pytest.raises(InputError, match="give the bodies"):
        sim.add_rigid_body("r")
    with pytest.raises(InputError, match="both fixed and prescribed"):
        sim.add_rigid_body("r", ["b"], fixed=("x",), prescribed={"x": 1.0})
    sim.add_rigid_body("r", ["b"])
    with pytest.raises(InputError, match="exists"):
        sim.add_rigid_body("r", ["b"])
    with pytest.raises(InputError, match="moves with rigid body 'r'"):
        sim.set_tearing(body="b", stress=1e3)
    other = Simulation(integrator="quasistatic")
    other.add_body("b", MESH, MAT)
    other.set_tearing(body="b", stress=1e3)
    with pytest.raises(InputError, match="is cut or cutting"):
        other.add_rigid_body("r", ["b"])


def test_newmark_drops_a_rigid_body_exactly():
    """The trapezoidal rule is exact under a constant acceleration: a body made rigid falls
    g t^2 / 2 from rest, its first step from the initial acceleration of its own weight."""
    sim = Simulation(integrator="newmark", time_step=0.02, gravity=(0, 0, -9.81))
    sim.add_body("bone", MESH, MAT, density=1500.0)
    sim.add_rigid_body("bone_rigid", ["bone"])
    x0, _ = sim.rigid_state("bone_rigid")
    for _ in range(6):
        sim.step()
    c, R = sim.rigid_state("bone_rigid")
    t = 6 * 0.02
    assert c - x0 == pytest.approx([0, 0, -0.5 * 9.81 * t * t], rel=1e-9, abs=1e-12)
    assert R == pytest.approx(np.eye(3), abs=1e-12)


def test_explicit_steps_refuse_rigid_bodies():
    sim = Simulation(integrator="explicit", time_step=1e-4)
    sim.add_body("b", MESH, MAT)
    sim.add_rigid_body("r", ["b"])
    with pytest.raises(InputError, match="rigid bodies run with"):
        sim.step()
