"""Discrete springs between vertices (energies/node_springs.py, FEBio's discrete elements):
energy, gradient and Hessian against central finite differences for each law, the force
curve's exact integral, and a spring's force in a simulation against its closed form."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.energies.accumulator import Accumulator
from tissuesim.energies.node_springs import (
    ExpressionForce,
    ForceCurve,
    NodeSprings,
    SpringLaw,
    spring_stencil,
)


def _smooth(s: np.ndarray) -> np.ndarray:
    """The quadratic through (-1, -1), (0, 0), (1, 2), constant beyond (FEBio's SMOOTH curve
    of three points)."""
    t = np.clip(s, -1.0, 1.0)
    return 1.5 * t + 0.5 * t**2


CURVE = ForceCurve.from_function(_smooth, [-1.0, 1.0])
LAWS = {
    "linear": SpringLaw("linear", stiffness=3.0),
    "tension_only": SpringLaw("tension_only", stiffness=3.0),
    "elongation": SpringLaw("curve", curve=CURVE, measure="elongation", scale=2.0),
    "strain": SpringLaw("curve", curve=CURVE, measure="strain", scale=2.0),
    "stretch": SpringLaw("curve", curve=CURVE, measure="stretch", scale=2.0),
    # FEBio's math force (op05's law) and a non-analytic one (central differences for F')
    "expression": SpringLaw(
        "curve", curve=ExpressionForce("0.5 * (exp(3 * x) - 1)"), measure="elongation", scale=2.0
    ),  # fmt: skip
    "expression_kinked": SpringLaw(
        "curve", curve=ExpressionForce("where(x > 0, x**3, x)"), measure="strain"
    ),  # fmt: skip
}


def _springs(law: SpringLaw, stretch: float = 1.0):
    rng = np.random.default_rng(3)
    X = rng.normal(size=(5, 3))
    pairs = np.array([[0, 3], [1, 4], [2, -1]])
    anchors = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.3, -0.2, 0.5]])
    ends = np.where(pairs[:, 1:] >= 0, X[np.maximum(pairs[:, 1], 0)], anchors)
    rest = np.linalg.norm(ends - X[pairs[:, 0]], axis=1)
    springs = NodeSprings(pairs, rest, law, anchors, "s", 3)
    pattern = SparsityPattern.from_stencils(15, [spring_stencil(pairs[:2], 3)])
    x = (stretch * X + 0.3 * rng.normal(size=X.shape)).ravel()
    return springs, pattern, x


def _evaluate(springs, pattern, x, order):
    acc = Accumulator(pattern, order)
    springs.accumulate(x, acc)
    return acc


@pytest.mark.parametrize("name", sorted(LAWS))
def test_gradient_and_hessian_match_finite_differences(name):
    springs, pattern, x = _springs(LAWS[name], 1.6 if name == "tension_only" else 1.0)
    acc = _evaluate(springs, pattern, x, 2)
    h = 1e-6
    g = np.zeros_like(x)
    H = np.zeros((x.size, x.size))
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        g[i] = (_evaluate(springs, pattern, x + e, 0).value
                - _evaluate(springs, pattern, x - e, 0).value) / (2 * h)  # fmt: skip
        H[:, i] = (_evaluate(springs, pattern, x + e, 1).gradient
                   - _evaluate(springs, pattern, x - e, 1).gradient) / (2 * h)  # fmt: skip
    assert np.abs(acc.gradient).max() > 0.1
    np.testing.assert_allclose(acc.gradient, g, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(pattern.matrix(acc.hessian).toarray(), H, rtol=1e-5, atol=1e-6)


def test_projected_hessian_is_positive_semidefinite():
    springs, pattern, x = _springs(LAWS["linear"])
    x = 0.3 * x  # shortened: compressed springs, f / l < 0
    acc = Accumulator(pattern, 2, project=True)
    springs.accumulate(x, acc)
    assert np.linalg.eigvalsh(pattern.matrix(acc.hessian).toarray()).min() > -1e-12


def test_force_curve_is_exact_for_polynomial_pieces():
    s = np.linspace(-2.0, 2.0, 41)
    np.testing.assert_allclose(CURVE.value(s), _smooth(s), atol=1e-12)
    inside = np.abs(s) < 1
    ends = np.abs(s) <= 1  # at an end the end piece's slope
    np.testing.assert_allclose(CURVE.derivative(s), np.where(ends, 1.5 + s, 0.0), atol=1e-10)
    # int_0^s of 1.5 t + t^2 / 2 = 0.75 s^2 + s^3 / 6 inside; the end values beyond
    exact = np.where(inside, 0.75 * s**2 + s**3 / 6, 0.0)
    exact = np.where(s >= 1, 0.75 + 1 / 6 + 2.0 * (s - 1), exact)
    exact = np.where(s <= -1, 0.75 - 1 / 6 - 1.0 * (s + 1), exact)
    np.testing.assert_allclose(CURVE.integral(np.zeros_like(s), s), exact, atol=1e-12)


def test_spring_in_a_simulation_balances_the_support():
    """A bar clamped at x = 0 and pushed by a force P at its far corner, which a spring ties
    to a fixed point 0.5 further along x: at equilibrium the spring's tension is E (l - L0)
    (its closed form) and the clamp's reaction balances P and the spring's pull."""
    import tissuesim as ts
    from tissuesim import select

    mesh = ts.box(lower=(0, 0, 0), upper=(1, 0.2, 0.2), divisions=(4, 1, 1))
    sim = ts.Simulation(mesh, ts.make_material("neo_hookean", youngs_modulus=1e3,
                        poisson_ratio=0.3), integrator="quasistatic", time_step=1.0)  # fmt: skip
    wall = sim.fix(select.vertices_on_plane(mesh, 0, 0.0), name="wall")
    far = int(np.flatnonzero(np.all(np.isclose(mesh.points, [1, 0, 0]), axis=1))[0])
    P = np.array([2.0, 0.5, 0.0])
    sim.add_nodal_forces([far], P)
    springs = sim.add_springs([[far, -1]], 20.0, anchors=[[1.5, 0.0, 0.0]], name="tie")
    sim.step()
    x = sim.positions
    f, e = springs.tensions(x.ravel())
    length = np.linalg.norm(np.array([1.5, 0.0, 0.0]) - x[far])
    assert f[0] == pytest.approx(20.0 * (length - 0.5), rel=1e-12)
    assert f[0] < -0.05  # pushed towards the anchor: compressed
    reaction = np.asarray(sim.forces()[wall])
    np.testing.assert_allclose(reaction, -(P + f[0] * e[0]), rtol=1e-6, atol=1e-8)
    assert sim.energies()["tie"] == pytest.approx(0.5 * 20.0 * (length - 0.5) ** 2)


def test_linear_constraint_energy_matches_finite_differences():
    """k/2 g^2 of g = sum c_i (x_i - X_i) - offset (constraints/linear.py), a coefficient a
    function of t: gradient and Hessian against central differences."""
    from tissuesim.constraints.linear import LinearConstraint

    rng = np.random.default_rng(5)
    rest = rng.normal(size=(4, 3))
    c = LinearConstraint(np.array([0, 2, 3]), np.array([1, 0, 2]), (1.0, lambda t: -0.5 * t, 2.0),
                         0.1, 7.0, rest[[0, 2, 3], [1, 0, 2]], 3, "c")  # fmt: skip
    pairs = np.array([[0, 2], [0, 3], [2, 3]])
    pattern = SparsityPattern.from_stencils(12, [spring_stencil(pairs, 3)])
    x = (rest + 0.2 * rng.normal(size=rest.shape)).ravel()
    energy = c.energy(0.8)

    def value(y, order=0):
        acc = Accumulator(pattern, order)
        energy.accumulate(y, acc)
        return acc

    acc = value(x, 2)
    g = c.residual(x, 0.8)
    assert acc.value == pytest.approx(0.5 * 7.0 * g * g, rel=1e-14) and abs(g) > 1e-3
    h = 1e-6
    eye = np.eye(x.size) * h
    fd_g = np.array([(value(x + e).value - value(x - e).value) / (2 * h) for e in eye])
    fd_H = np.array([(value(x + e, 1).gradient - value(x - e, 1).gradient) / (2 * h) for e in eye])
    np.testing.assert_allclose(acc.gradient, fd_g, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(pattern.matrix(acc.hessian).toarray(), fd_H.T, atol=1e-6)


def test_a_scaled_spring_set_scales_energy_gradient_and_hessian():
    """NodeSprings.at(t): the law times scale(t) (FEBio's node distance penalty on a curve)."""
    from dataclasses import replace

    springs, pattern, x = _springs(LAWS["elongation"])
    scaled = replace(springs, scale=lambda t: 0.25 * t).at(2.0)
    one, half = _evaluate(springs, pattern, x, 2), _evaluate(scaled, pattern, x, 2)
    assert half.value == pytest.approx(0.5 * one.value, rel=1e-14)
    np.testing.assert_allclose(half.gradient, 0.5 * one.gradient, rtol=1e-14)
    np.testing.assert_allclose(half.hessian, 0.5 * one.hessian, rtol=1e-14, atol=1e-300)


def test_an_expression_force_is_its_closed_form():
    """F = a (exp(b x) - 1): the value, F' (a complex step: exact to round-off) and the
    energy's integral a (exp(b x) - 1) / b - a x (Gauss-Legendre) against the closed forms,
    over elongations where exp(b x) grows 150-fold; a kinked expression falls back to central
    differences."""
    a, b = 2.0, 50.0
    f = ExpressionForce(f"{a} * (exp({b} * x) - 1)")
    assert f.analytic and not ExpressionForce("abs(x)").analytic
    s = np.linspace(-0.05, 0.1, 7)
    np.testing.assert_allclose(f.value(s), a * (np.exp(b * s) - 1), rtol=1e-15)
    np.testing.assert_allclose(f.derivative(s), a * b * np.exp(b * s), rtol=1e-14)
    exact = a * (np.exp(b * s) - 1) / b - a * s
    np.testing.assert_allclose(f.integral(0 * s, s), exact, rtol=1e-13, atol=1e-16)
    kinked = ExpressionForce("where(x > 0, x**2, 0)")
    np.testing.assert_allclose(kinked.derivative(np.array([0.5, -0.5])), [1.0, 0.0], atol=1e-8)
