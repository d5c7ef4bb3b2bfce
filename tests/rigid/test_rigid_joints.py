"""Joints and springs between rigid bodies (rigid/joints.py): their energies against finite
differences (multipliers and prescribed motions included), a revolute joint turned by its
prescribed rotation, a prismatic joint with a spring under a force off its axis, against
closed forms; the augmented Lagrangian holds each joint to its tolerance."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from tissuesim.errors import InputError
from tissuesim.materials import make_material
from tissuesim.mesh import box
from tissuesim.rigid.joints import TOLERANCE
from tissuesim.simulation import Simulation

MAT = make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
GROUND = box((-0.5, -0.5, -1.0), (0.5, 0.5, 0.0), (1, 1, 1))
ARM = box((0.0, -0.1, 0.0), (2.0, 0.1, 0.2), (2, 1, 1))


def _pair(**kw) -> Simulation:
    sim = Simulation(integrator="quasistatic", time_step=0.5, **kw)
    sim.add_body("ground", GROUND, MAT)
    sim.add_body("arm", ARM, MAT)
    sim.add_rigid_body("G", ["ground"], fixed=("x", "y", "z", "rx", "ry", "rz"))
    return sim


@pytest.mark.parametrize("kind", ["spherical", "revolute", "prismatic", "cylindrical", "planar"])
def test_joint_energies_against_finite_differences(kind):
    """Phi of a system with the joint (and a spring) at a moved, turned state, with
    multipliers and the prescribed motion the kind takes: the first difference along random
    retractions against the gradient, the second against the Hessian's quadratic form."""
    sim = _pair()
    sim.add_rigid_body("A", ["arm"], force=(1.0, -2.0, 0.5))
    extra = {}
    if kind in ("revolute", "cylindrical"):
        extra["rotation"] = lambda t: 0.3 + t
    if kind in ("prismatic", "cylindrical"):
        extra["translation"] = lambda t: 0.1 * t
    joint = sim.add_rigid_joint(kind, "G", "A", (0.2, 0.1, 0.05), axis=(0.2, 0.1, 1.0),
                                transverse=(1.0, 0.3, 0.0), **extra)  # fmt: skip
    sim.add_rigid_spring("G", "A", (0.0, 0.3, 0.0), (1.5, 0.0, 0.1), 50.0, free_length=0.7)
    s = sim.system
    s.load_time = 0.4
    rng = np.random.default_rng(7)
    free = np.ones(s.n_dofs, dtype=bool)
    free[s.elimination.dofs] = False
    c = s.apply_prescribed(
        s.retract(s.rest_config(), np.where(free, rng.normal(scale=0.1, size=s.n_dofs), 0)), 0.0
    )
    (j,) = [j for j in s.joints if j.name == joint]
    g = s.joint_terms(c, 0)[0][3]
    j.multipliers = rng.normal(size=g.size)
    acc = s.evaluate(c, 2)
    H = sp.csr_matrix((acc.hessian, s.pattern.indices, s.pattern.indptr), shape=(s.n_dofs,) * 2)
    for _ in range(3):
        d = np.where(free, rng.normal(size=s.n_dofs), 0.0)
        e = 1e-6
        plus = s.evaluate(s.retract(c, e * d), 0).value
        minus = s.evaluate(s.retract(c, -e * d), 0).value
        assert (plus - minus) / (2 * e) == pytest.approx(acc.gradient @ d, rel=1e-6)
        e = 1e-4
        plus = s.evaluate(s.retract(c, e * d), 0).value
        minus = s.evaluate(s.retract(c, -e * d), 0).value
        second = (plus + minus - 2 * acc.value) / e**2
        assert second == pytest.approx(d @ (H @ d), rel=1e-4)


def test_a_revolute_joint_turns_the_arm_by_its_prescribed_rotation():
    """The arm (centre (1, 0, 0.1)) turned 0.6 rad about z through the origin: its centre at
    Rz(0.6) (1, 0, 0.1), its rotation Rz(0.6); the joint holds to its tolerance and carries no
    load (nothing else acts)."""
    sim = _pair()
    sim.add_rigid_body("A", ["arm"])
    name = sim.add_rigid_joint("revolute", "G", "A", (0, 0, 0), axis=(0, 0, 1),
                               transverse=(1, 0, 0), rotation=lambda t: 0.6 * t)  # fmt: skip
    for _ in range(2):
        sim.step()
    c, R = sim.rigid_state("A")
    phi = 0.6
    Rz = np.array([[np.cos(phi), -np.sin(phi), 0], [np.sin(phi), np.cos(phi), 0], [0, 0, 1]])
    assert c == pytest.approx(Rz @ [1.0, 0.0, 0.1], abs=1e-8)
    assert R == pytest.approx(Rz, abs=1e-8)
    residual = sim.system.joint_terms(sim.state.x, 0)[0][3]
    assert np.abs(residual).max() <= TOLERANCE * sim.system.length_scale
    assert np.allclose(sim.forces()[name], 0.0, atol=1e-9)


def test_a_prismatic_joint_with_a_spring_slides_as_far_as_the_force_pulls():
    """The arm on a prismatic joint along x, a spring k = 200 N/m from the ground along x,
    a force (10, 4, -3) N and a moment on it: it slides 10 / 200 = 0.05 m along x and not at
    all across or turning; the joint takes the force's other components and the moment."""
    sim = _pair()
    sim.add_rigid_body("A", ["arm"], force=(10.0, 4.0, -3.0), moment=(0.5, 0.2, -0.1))
    joint = sim.add_rigid_joint("prismatic", "G", "A", (0.0, 0.0, 0.1), axis=(1, 0, 0))
    spring = sim.add_rigid_spring("G", "A", (-1.0, 0.0, 0.1), (0.0, 0.0, 0.1), 200.0)
    sim.step()
    sim.step()
    c, R = sim.rigid_state("A")
    assert c == pytest.approx([1.05, 0.0, 0.1], abs=1e-8)
    assert R == pytest.approx(np.eye(3), abs=1e-8)
    f = sim.forces()
    assert f[spring] == pytest.approx([-10.0, 0.0, 0.0], abs=1e-6)
    assert f[joint] == pytest.approx([0.0, -4.0, 3.0], abs=1e-6)


def test_joint_refusals_name_what_is_wrong():
    sim = _pair()
    sim.add_rigid_body("A", ["arm"])
    with pytest.raises(InputError, match="the kinds are"):
        sim.add_rigid_joint("hinge", "G", "A", (0, 0, 0), axis=(0, 0, 1))
        sim.build()
    with pytest.raises(InputError, match="is not a rigid body"):
        sim.add_rigid_joint("spherical", "G", "arm", (0, 0, 0))
    with pytest.raises(InputError, match="needs its axis"):
        sim.add_rigid_joint("revolute", "G", "A", (0, 0, 0))
    with pytest.raises(InputError, match="no prescribed rotation"):
        sim.add_rigid_joint("prismatic", "G", "A", (0, 0, 0), axis=(1, 0, 0), rotation=0.1)


def _features(joint, z, centres0):
    """The joint's features at the two bodies' configurations z (2, 12), as system.py's."""
    rest = joint.rest_features(centres0)
    c = [zk[:3] for zk in z]
    R = [zk[3:12].reshape(3, 3) for zk in z]
    y = [c[0] + R[0] @ rest[0], c[1] + R[1] @ rest[1]]
    y += [R[0] @ rest[i] for i in (2, 3, 4)] + [R[1] @ rest[i] for i in (5, 6)]
    return np.array(y), np.array(c)


@pytest.mark.parametrize("kind", ["revolute", "prismatic", "cylindrical", "planar"])
def test_a_joint_alone_against_finite_differences(kind):
    """joint_energy with unit penalties and random multipliers (so that the multipliers'
    bilinear and curvature terms weigh as much as the penalty's), on random rigid states."""
    from tissuesim.rigid.body import RigidModel
    from tissuesim.rigid.joints import RigidJoint, joint_energy

    rng = np.random.default_rng(3)
    extra = {}
    if kind in ("revolute", "cylindrical"):
        extra["rotation"] = lambda t: 0.4
    if kind in ("prismatic", "cylindrical"):
        extra["translation"] = lambda t: 0.2
    joint = RigidJoint("j", kind, "a", "b", rng.normal(size=3), rng.normal(size=3),
                       rng.normal(size=3), **extra)  # fmt: skip
    centres0 = (rng.normal(size=3), rng.normal(size=3))
    z = [RigidModel.retract(np.concatenate([c, np.eye(3).ravel()]), rng.normal(size=6))
         for c in centres0]  # fmt: skip
    y, c = _features(joint, z, centres0)
    g = joint.residuals(y, 0.0)[0]
    joint.multipliers = 5.0 * rng.normal(size=g.size)
    k = np.ones(g.size)

    def energy(dq):
        zz = [RigidModel.retract(z[0], dq[:6]), RigidModel.retract(z[1], dq[6:])]
        yy, cc = _features(joint, zz, centres0)
        return joint_energy(joint, yy, cc, 0.0, k)[0]

    value, grad, hess, _ = joint_energy(joint, y, c, 0.0, k)
    for _ in range(4):
        d = rng.normal(size=12)
        e = 1e-6
        assert (energy(e * d) - energy(-e * d)) / (2 * e) == pytest.approx(grad @ d, rel=1e-6)
        e = 1e-4
        second = (energy(e * d) + energy(-e * d) - 2 * value) / e**2
        assert second == pytest.approx(d @ hess @ d, rel=1e-5, abs=1e-6)


def _slider(F: float, ks: float, k: float, **enforcement) -> tuple[Simulation, str]:
    """The arm free along x only, a spring ks along x and a spherical joint of penalty k at its
    centre (1, 0, 0.1), pulled by F along x."""
    sim = _pair()
    sim.add_rigid_body("A", ["arm"], force=(F, 0.0, 0.0), fixed=("y", "z", "rx", "ry", "rz"))
    sim.add_rigid_spring("G", "A", (-1.0, 0.0, 0.1), (1.0, 0.0, 0.1), ks)
    rule = {"penalty": k, **enforcement}
    return sim, sim.add_rigid_joint("spherical", "G", "A", (1.0, 0.0, 0.1), enforcement=rule)


@pytest.mark.parametrize(
    "rule, solves",
    [
        ({"tolerance": 0.1}, 4),  # changes 1, 1/3, 1/7, 1/15 < 0.1: the 4th solve stands
        ({"tolerance": 0.05}, 5),  # 1/31 < 0.05
        ({"tolerance": 0.1, "max_augmentations": 2}, 3),
        ({"tolerance": 0.1, "min_augmentations": 5}, 6),
        ({"gap_tolerance": 1.5 * 0.3 / 2**5}, 6),  # u_n = 0.3 / 2^n: the first below, n = 5
        ({"augmented": False, "tolerance": 0.1}, 1),  # FEBio's penalty method
    ],
)
def test_febios_augmentation_rule_stops_where_its_tolerance_says(rule, solves):
    """F = 12 N, spring ks = penalty k = 20 N/m in parallel: each solve gives u_n =
    (F + lambda_n) / (ks + k) and FEBio's update lambda <- lambda - k u_n halves F + lambda,
    so u_n = F / (ks + k) / 2^n and lambda_n = -F (1 - 2^-n); the multipliers' relative change
    after solve n is | |lambda_(n+1)| - |lambda_n| | / |lambda_(n+1)| = 1 / (2^(n+1) - 1):
    1, 1/3, 1/7, 1/15, 1/31, 1/63 (n = 0, 1, ...). The arm ends where the last solve left it
    (``solves`` of them)."""
    sim, name = _slider(12.0, 20.0, 20.0, **rule)
    x0 = sim.rigid_state("A")[0][0]
    sim.step()
    u = sim.rigid_state("A")[0][0] - x0
    n = solves - 1
    assert u == pytest.approx(12.0 / 40.0 / 2**n, rel=1e-7)
    (joint,) = [j for j in sim.system.joints if j.name == name]
    assert joint.multipliers[0] == pytest.approx(-12.0 * (1 - 2.0**-n), rel=1e-7, abs=1e-9)


def test_without_an_enforcement_a_joint_holds_to_tissuesims_tolerance():
    sim, _ = _slider(12.0, 20.0, 20.0)
    sim.system.joints[-1].enforcement = None
    x0 = sim.rigid_state("A")[0][0]
    sim.step()
    assert abs(sim.rigid_state("A")[0][0] - x0) <= TOLERANCE * sim.system.length_scale


@pytest.mark.parametrize(
    "rule, message",
    [
        ({"tolerance": 0.1}, "needs its penalty"),
        ({"penalty": 0.0}, "penalty must be a number > 0"),
        ({"penalty": 1.0, "tolerance": -1}, "tolerance must be a number >= 0"),
        ({"penalty": 1.0, "maxaug": 3}, "not 'maxaug'"),
        ({"penalty": 1.0, "max_augmentations": 1.5}, "must be a count"),
        ({"penalty": 1.0, "augmented": 1}, "true or false"),
    ],
)
def test_enforcement_refusals_are_one_line(rule, message):
    sim = _pair()
    sim.add_rigid_body("A", ["arm"])
    with pytest.raises(InputError, match=message) as info:
        sim.add_rigid_joint("spherical", "G", "A", (0, 0, 0), enforcement=rule)
    assert "\n" not in str(info.value)


def test_a_joint_stops_updating_where_solves_no_longer_close_its_residual():
    """Two solves in a row that move the bodies but leave a joint's residual where it was
    (by less than STALLED of it) end its updates: redundant constraints that do not quite
    agree (FEBio's rj13, a closed loop of four revolute joints given to six digits) took the
    30 updates in every step, and FEBio's stepper shrank its steps to dtmin. A solve that did
    not move (Newton staying put while the multipliers' change is below its tolerance) does
    not count, and a residual that shrinks goes on being updated."""
    from tissuesim.rigid.joints import STALLED, RigidJoint, augment

    def joint():
        return RigidJoint("j", "spherical", "a", "b", np.zeros(3))

    k, rows, tight = np.full(3, 10.0), np.ones(3, dtype=bool), 1e-9
    g = np.array([3e-8, 0.0, -1e-8])
    stuck = joint()
    drift = g * (1 + STALLED / 2)
    assert augment(stuck, g, k, rows, tight)  # the first update
    assert augment(stuck, drift, k, rows, tight)  # one stalled solve: updated again
    assert not augment(stuck, g, k, rows, tight)  # two in a row: it holds as it is
    assert stuck.multipliers == pytest.approx(-2 * k * g, rel=STALLED)
    idle = joint()  # solves that did not move the bodies (or tissuesim's Newton) say nothing
    assert all(augment(idle, g, k, rows, tight, moved=n == 0) for n in range(5))
    closing = joint()  # a residual halved by each solve is updated until below tight
    updates = [augment(closing, g / 2**n, k, rows, tight) for n in range(5)]
    assert all(updates) and not augment(closing, g / 2**5, k, rows, tight)
