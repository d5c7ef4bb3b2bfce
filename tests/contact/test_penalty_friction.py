"""Coulomb friction of the penalty contact (contact/penalty/friction.py, FEBio's return map):
its energy's derivatives against finite differences in stick and in slip, and blocks pulled
over a table against Coulomb's law."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.penalty import friction as coulomb
from tissuesim.contact.penalty.faces import Facets
from tissuesim.contact.penalty.friction import return_map
from tissuesim.contact.penalty.pair import PenaltyContact, PenaltySide
from tissuesim.materials import NeoHookean
from tissuesim.mesh import box

RNG = np.random.default_rng(11)


def _blocks(dz: float = 0.02):
    lower = box((0, 0, 0), (1, 1, 0.5), (3, 3, 2), element="hex")
    upper = box((0.2, 0.15, 0.5 - dz), (0.8, 0.75, 1.0), (2, 2, 2), element="hex")
    return lower, upper


def test_the_return_map_keeps_stick_inside_the_cone_and_scales_slip_onto_it():
    tau = np.array([[3.0, 4.0, 0.0], [0.3, 0.4, 0.0], [0.0, 0.0, 0.0]])
    t, stick = return_map(tau, np.array([2.0, 2.0, 1.0]))
    np.testing.assert_allclose(t, [[1.2, 1.6, 0.0], [0.3, 0.4, 0.0], [0.0, 0.0, 0.0]])
    assert stick.tolist() == [False, True, True]


@pytest.mark.parametrize(
    "slide, options",
    [
        (0.001, {"rule": "gauss"}),  # small: most points stick
        (0.05, {"rule": "gauss"}),  # large: they slip
        (0.02, {"rule": "nodal", "two_pass": True, "friction_penalty": 30.0}),
        (0.02, {"rule": "gauss", "augmented": True}),
    ],
)
def test_friction_energy_gradient_and_hessian_match_finite_differences(slide, options):
    """Upper block's bottom overlapping the lower's top by 2 %, anchored, then slid by
    ``slide`` and perturbed: the pair's gradient and Hessian (normal and friction) against
    central differences, with both stick and slip points where the slide is moderate."""
    lower, upper = _blocks()
    rest = [lower.points, upper.points]
    sides = (
        PenaltySide(1, Facets.of(upper.facet_sets["zmin"], "u"), np.ones(4)),
        PenaltySide(0, Facets.of(lower.facet_sets["zmax"], "l"), np.full(9, 2.0)),
    )
    augmented = options.pop("augmented", False)
    pair = PenaltyContact("p", *sides, penalty=50.0, friction=0.4, **options)
    pair.setup(rest)
    if augmented:
        for p in pair.passes:
            p.friction.traction = RNG.uniform(-0.3, 0.3, p.friction.traction.shape)
    pair.begin_step(rest)
    assert all(p.friction.pressure.max() > 0 for p in pair.passes)
    moved = [rest[0].copy(), rest[1] + np.array([slide, 0.5 * slide, 0.0])]
    positions = [r + 0.003 * RNG.standard_normal(r.shape) for r in moved]
    n0 = lower.n_points * 3
    dofs = [np.arange(n0).reshape(-1, 3), n0 + np.arange(upper.n_points * 3).reshape(-1, 3)]
    n = n0 + upper.n_points * 3
    flat = np.concatenate([p.ravel() for p in positions])

    def split(v):
        return [v[:n0].reshape(-1, 3), v[n0:].reshape(-1, 3)]

    value, grad, hess = pair.evaluate(positions, dofs, n, 2)
    frictionless = PenaltyContact("q", *sides, penalty=50.0, **options)
    frictionless.setup(rest)
    v0, g0, _ = frictionless.evaluate(positions, dofs, n, 1)
    assert value > v0 and np.abs(grad - g0).max() > 1e-3  # the friction is there
    e = 1e-7
    active = np.flatnonzero(np.abs(grad) > 0)
    for i in active[:: max(1, len(active) // 14)]:
        d = np.zeros(n)
        d[i] = e
        vp, gp, _ = pair.evaluate(split(flat + d), dofs, n, 1)
        vm, gm, _ = pair.evaluate(split(flat - d), dofs, n, 1)
        assert grad[i] == pytest.approx((vp - vm) / (2 * e), rel=1e-5, abs=1e-9)
        np.testing.assert_allclose(hess[:, i].toarray().ravel(), (gp - gm) / (2 * e), atol=2e-5)


@pytest.mark.parametrize("slide", [0.001, 0.05])
def test_node_on_facet_friction_measures_slip_as_febio_and_its_derivatives_hold(slide):
    """FEBio's node-on-facet slip ("contact" anchors: natural coordinates on the anchor's
    facet in its reference metric, friction.py): the energy's gradient against central
    differences on every DOF (the lower block deformed, so its facets are no longer
    parallelograms), and its Hessian exactly on the upper block's DOFs while the lower
    block stays at rest (flat square facets: r is linear in the point there); stick at the
    small slide, slip at the large one."""
    lower, upper = _blocks()
    rest = [lower.points, upper.points]
    sides = (
        PenaltySide(1, Facets.of(upper.facet_sets["zmin"], "u"), np.ones(4)),
        PenaltySide(0, Facets.of(lower.facet_sets["zmax"], "l"), np.ones(9)),
    )
    options = {"rule": "nodal", "friction_penalty": 30.0, "friction_anchor": "contact"}
    pair = PenaltyContact("p", *sides, penalty=50.0, friction=0.4, **options)
    pair.setup(rest)
    pair.begin_step(rest)
    (p,) = pair.passes
    assert p.friction.rest is not None and p.friction.pressure.max() > 0
    n0 = lower.n_points * 3
    dofs = [np.arange(n0).reshape(-1, 3), n0 + np.arange(upper.n_points * 3).reshape(-1, 3)]
    n = n0 + upper.n_points * 3

    def split(v):
        return [v[:n0].reshape(-1, 3), v[n0:].reshape(-1, 3)]

    moved = rest[1] + np.array([slide, 0.5 * slide, 0.0])
    deformed = lower.points + 0.003 * RNG.standard_normal(lower.points.shape)
    for lower_at, exact_hessian in ((deformed, False), (lower.points, True)):
        positions = [lower_at, moved + 0.002 * RNG.standard_normal(moved.shape)]
        flat = np.concatenate([q.ravel() for q in positions])
        value, grad, hess = pair.evaluate(positions, dofs, n, 2)
        frictionless = PenaltyContact("q", *sides, penalty=50.0, rule="nodal")
        frictionless.setup(rest)
        v0, g0, _ = frictionless.evaluate(positions, dofs, n, 1)
        assert value > v0 and np.abs(grad - g0).max() > 1e-3  # the friction is there
        _, _, _, _, _, _, stick = coulomb._natural(p.friction, p, positions,
                                                   pair._eps_t(p), pair.friction)[:7]  # fmt: skip
        assert stick.all() if slide < 0.01 else not stick.any()
        e = 1e-7
        active = np.flatnonzero(np.abs(grad - g0) > 0)
        assert active.min() < n0 < active.max()  # both blocks' DOFs
        for i in active[:: max(1, len(active) // 16)]:
            d = np.zeros(n)
            d[i] = e
            vp, gp, _ = pair.evaluate(split(flat + d), dofs, n, 1)
            vm, gm, _ = pair.evaluate(split(flat - d), dofs, n, 1)
            assert grad[i] == pytest.approx((vp - vm) / (2 * e), rel=1e-5, abs=1e-9)
            if exact_hessian and i >= n0:
                column = hess[:, i].toarray().ravel()
                np.testing.assert_allclose(column[n0:], ((gp - gm) / (2 * e))[n0:], atol=2e-5)


def _pulled(mu: float, pull: float, steps: int = 4, augmented: bool = False, **extra):
    """A block (0.6 x 0.6 x 0.5) on a fixed table block, pressed down 0.01 by its top, then
    its top dragged along x by ``pull`` per step (held in z): Coulomb friction mu."""
    lower, upper = _blocks(dz=0.0)
    soft = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.0)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0)
    sim.add_body("lower", lower, NeoHookean(youngs_modulus=1e6, poisson_ratio=0.0))
    sim.add_body("upper", upper, soft)
    sim.fix(np.arange(lower.n_points), body="lower", name="table")  # it does not move
    top = np.flatnonzero(upper.points[:, 2] > 1 - 1e-9)

    def motion(t):
        return np.array([pull * max(t - 1.0, 0.0), 0.0, -0.01 * min(t, 1.0)])

    sim.grasp(top, motion, body="upper", name="drag")
    sim.add_penalty_contact(
        "upper", "lower", primary_facets="zmin", secondary_facets="zmax", penalty=1e6,
        friction=mu, augmented=augmented, tolerance=1e-8, max_augmentations=40,
        name="contact", **extra,
    )  # fmt: skip
    for _ in range(steps):
        record = sim.step()
        assert record.converged
    return sim


@pytest.mark.parametrize(
    "extra",
    [{}, {"integration": "nodes", "friction_anchor": "contact", "friction_penalty": 1e6}],
)
def test_a_sliding_block_feels_mu_times_the_normal_force(extra):
    """Dragged far enough to slide: the contact's tangential force is mu times its normal
    force (Coulomb) and opposes the drag; the grasp's reaction balances it. Also with
    FEBio's node-on-facet slip (natural coordinates in the reference metric)."""
    sim = _pulled(mu=0.3, pull=0.05, **extra)
    f = np.asarray(sim.forces()["contact"])
    assert f[2] > 1.0  # pressed
    assert f[0] == pytest.approx(-0.3 * f[2], rel=1e-3)
    assert abs(f[1]) < 1e-4 * f[2]  # the block sits off the table's mesh symmetry
    drag = np.asarray(sim.forces()["drag"])
    np.testing.assert_allclose(drag + f, 0.0, atol=1e-6 * f[2])


def test_a_gently_dragged_block_sticks_below_the_cone():
    """A drag too small to slide at mu = 0.8: the tangential force stays inside the cone
    and the augmented Lagrangian holds the bottom where it was (no slip)."""
    sim = _pulled(mu=0.8, pull=0.0005, steps=3, augmented=True)
    f = np.asarray(sim.forces()["contact"])
    assert 0 < -f[0] < 0.8 * f[2]
    bottom = np.flatnonzero(sim.bodies["upper"].mesh.points[:, 2] < 0.5 + 1e-9)
    u = sim.body_displacement(body="upper")[bottom]
    assert np.max(np.abs(u[:, 0])) < 1e-6 * 0.0005 * 2


@pytest.mark.parametrize(
    "options, message",
    [
        ({"friction": -0.1}, "friction = -0.1: give a non-negative number"),
        ({"friction": 0.2, "friction_penalty": -1.0}, "friction_penalty = -1.0"),
        ({"friction": 0.2, "friction_anchor": "first"}, "friction_anchor 'first': give one of"),
        ({"friction": 0.2, "tied": True}, "friction on a tied or sticky pair"),
    ],
)
def test_bad_friction_settings_give_one_line(options, message):
    from tissuesim.errors import InputError

    lower, upper = _blocks()
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0)
    law = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.0)
    sim.add_body("lower", lower, law)
    sim.add_body("upper", upper, law)
    with pytest.raises(InputError, match=message) as error:
        sim.add_penalty_contact("upper", "lower", penalty=1e4, **options)
    assert "\n" not in str(error.value)
