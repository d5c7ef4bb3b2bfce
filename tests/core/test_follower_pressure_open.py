"""A follower pressure on an open surface (energies/pressure_lag.py): the lagged load against
finite differences and hand-computed facet loads, a block compressed through its top face at
the neo-Hookean closed form (and not at the dead load's), a cantilever bending under its top
face with the load normal to the deformed face, the inner solves still quadratic, re-lags
counted, an unsettled load failing the step in one line, and friction lagged alongside."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import tissuesim as ts
from tissuesim.energies import pressure_lag
from tissuesim.energies.accumulator import Accumulator
from tissuesim.energies.pressure import FollowerPressure, PressureEnergy
from tissuesim.energies.pressure_lag import LaggedPressureEnergy, facet_loads, facet_stiffness
from tissuesim.errors import ConvergenceError
from tissuesim.mesh import select
from tissuesim.model import Model

E, NU = 1e4, 0.3
MU, LAM = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))


def _assembled(facets: np.ndarray, per_node: np.ndarray, n: int) -> np.ndarray:
    return np.bincount(
        (facets[:, :, None] * 3 + np.arange(3)).ravel(), per_node.ravel(), minlength=3 * n
    )


def _gauss_loads(X: np.ndarray, p: float) -> np.ndarray:
    """p int N_a (x_xi x x_eta) on bilinear quads by a 5 x 5 Gauss rule (independent of the
    library's 2 x 2 one, which is exact)."""
    r, w = np.polynomial.legendre.leggauss(5)
    s = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    out = np.zeros_like(X)
    for xi, wi in zip(r, w, strict=True):
        for eta, wj in zip(r, w, strict=True):
            N = (1 + s[:, 0] * xi) * (1 + s[:, 1] * eta) / 4
            a = np.einsum("a,kai->ki", s[:, 0] * (1 + s[:, 1] * eta) / 4, X)
            b = np.einsum("a,kai->ki", s[:, 1] * (1 + s[:, 0] * xi) / 4, X)
            out += wi * wj * p * N[None, :, None] * np.cross(a, b)[:, None, :]
    return out


@pytest.mark.parametrize("element", ["tet", "hex"])
def test_the_lagged_load_matches_finite_differences_and_hand_computed_facet_loads(element):
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.5, 0.5), (2, 1, 1), element=element)
    model = Model(mesh, ts.make_material("neo_hookean", youngs_modulus=1.0, poisson_ratio=0.3),
                  np.ones(mesh.n_cells), backend="numpy")  # fmt: skip
    facets = mesh.facet_sets["zmax"]
    rng = np.random.default_rng(1)
    x = mesh.points.ravel() + 0.05 * rng.standard_normal(mesh.points.size)
    X = x.reshape(-1, 3)[facets]
    # the loads by hand: a third of p times each triangle's area vector, or 5 x 5 Gauss
    if element == "tet":
        hand = np.repeat(3.0 / 6 * np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])[:, None], 3, 1)
    else:
        hand = _gauss_loads(X, 3.0)
    np.testing.assert_allclose(facet_loads(X, 3.0), hand, rtol=1e-12, atol=1e-14)
    # K = dG/dx (unsymmetric) against central differences of G
    h, K = 1e-6, facet_stiffness(X, 3.0)
    for b in range(X.shape[1]):
        for j in range(3):
            dX = np.zeros_like(X)
            dX[:, b, j] = h
            fd = (facet_loads(X + dX, 3.0) - facet_loads(X - dX, 3.0)) / (2 * h)
            np.testing.assert_allclose(K[:, :, :, b, j], fd, atol=1e-8)
    assert np.abs(K - np.swapaxes(np.swapaxes(K, 1, 3), 2, 4)).max() > 1e-3  # not symmetric
    # W_lag at a fixed lag, with and without S: value, gradient and Hessian by differences
    load = FollowerPressure(facets, lambda t: 3.0, closed=False)
    lag = x + 0.02 * rng.standard_normal(x.size)
    for stiffness in (False, True):
        energy = LaggedPressureEnergy(load, 3.0, stiffness=stiffness)
        energy.set_lag(lag)

        def evaluate(y, order, energy=energy):
            acc = Accumulator(model.pattern, order)
            energy.accumulate(y, acc)
            return acc

        acc = evaluate(x, 2)
        H = model.pattern.matrix(acc.hessian).toarray()
        assert np.allclose(H, H.T, atol=1e-12) and (np.abs(H).max() > 0) == stiffness
        d = rng.standard_normal(x.size)
        hi, lo = evaluate(x + h * d, 1), evaluate(x - h * d, 1)
        assert (hi.value - lo.value) / (2 * h) == pytest.approx(acc.gradient @ d, rel=1e-8)
        np.testing.assert_allclose((hi.gradient - lo.gradient) / (2 * h), H @ d, atol=1e-7)
        # at x = lag the applied load is the follower load exactly
        applied, follower = energy.nodal(lag)
        np.testing.assert_allclose(applied, follower, rtol=1e-13, atol=1e-13)


def test_on_a_closed_surface_the_facet_loads_sum_to_the_energys_gradient():
    """The closed surface's energy p V and the lagged follower load agree node by node."""
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.5, 0.5), (2, 1, 1))
    facets = select.all_boundary_facets(mesh)
    model = Model(mesh, ts.make_material("neo_hookean", youngs_modulus=1.0, poisson_ratio=0.3),
                  np.ones(mesh.n_cells), backend="numpy")  # fmt: skip
    x = mesh.points.ravel() + 0.05 * np.random.default_rng(2).standard_normal(mesh.points.size)
    acc = Accumulator(model.pattern, 1)
    PressureEnergy(FollowerPressure(facets, lambda t: 5.0), 5.0).accumulate(x, acc)
    lagged = _assembled(facets, facet_loads(x.reshape(-1, 3)[facets], 5.0), mesh.n_points)
    np.testing.assert_allclose(lagged, acc.gradient, atol=1e-12)


def uniaxial_stretch(p: float, follower: bool) -> tuple[float, float]:
    """(axial stretch s, lateral stretch a) of a neo-Hookean block under p on its top face.

    F = diag(a, a, s), J = a^2 s, Cauchy stress sigma = (mu (B - I) + lam ln J I) / J. The free
    sides: mu (a^2 - 1) + lam ln J = 0. The top: a follower p is a Cauchy traction, sigma_zz =
    -p, so mu (s^2 - 1) + lam ln J = -p a^2 s; a dead p is a nominal one, P_zz = J sigma_zz / s
    = -p, so mu (s^2 - 1) + lam ln J = -p s."""

    def lateral(s):
        return brentq(lambda a: MU * (a * a - 1) + LAM * np.log(a * a * s), 0.5, 2.0)

    def top(s):
        a = lateral(s)
        return MU * (s * s - 1) + LAM * np.log(a * a * s) + p * s * (a * a if follower else 1)

    s = brentq(top, 0.3, 1.0, xtol=1e-15)
    return s, lateral(s)


def pressed_block(element: str, follower: bool, p: float = 2e3) -> ts.Simulation:
    """A unit block on rollers (z = 0, x = 0 and y = 0 each held normal to itself) pressed by
    p on its top face, ramped over 2 quasistatic steps."""
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2, 2, 2), element=element)
    sim = ts.Simulation(mesh, ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=NU),
                        integrator="quasistatic", time_step=0.5)  # fmt: skip
    P = mesh.points
    for axis, name in enumerate(("x0", "y0", "bottom")):
        sim.add_dirichlet(np.flatnonzero(P[:, axis] == 0), None, (axis,), name=name)
    if follower:
        sim.add_follower_pressure(mesh.facet_sets["zmax"], lambda t: p * t, name="top")
    else:
        sim.add_traction(mesh.facet_sets["zmax"], lambda X, t: np.tile([0, 0, -p * t], (len(X), 1)))
    return sim


def _lagged(sim: ts.Simulation) -> list[LaggedPressureEnergy]:
    return [e for es in sim.system.last_step_energies for e in es
            if isinstance(e, LaggedPressureEnergy)]  # fmt: skip


@pytest.mark.parametrize("element", ["tet", "hex"])
def test_a_block_pressed_through_its_top_face_takes_the_follower_closed_form(element):
    """Follower: s = 0.809486, a = 1.063764 at p = 0.2 E; dead: s = 0.828311 (the load per
    deformed area is p there, p / a^2 per deformed area for the dead load)."""
    p = 2e3
    (s, a), (s_dead, _) = uniaxial_stretch(p, True), uniaxial_stretch(p, False)
    assert s == pytest.approx(0.8094864, abs=1e-7) and s_dead == pytest.approx(0.8283110, abs=1e-7)
    sim, relags = pressed_block(element, True, p), []
    for _ in range(2):
        sim.step()
        relags += [e.relags for e in _lagged(sim)]
    assert relags == [6, 8]  # re-lags per step to the tolerance 1e-8
    x = sim.body_positions("body")
    P = sim.mesh.points
    np.testing.assert_allclose(x[:, 2], s * P[:, 2], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(x[:, :2], a * P[:, :2], rtol=1e-8, atol=1e-12)
    # the converged load is p times the deformed facets' area vectors, node by node
    (energy,) = _lagged(sim)
    applied, _ = energy.nodal(x.ravel())
    facets = sim.mesh.facet_sets["zmax"]
    X = x[facets]
    if element == "tet":
        share = np.repeat(p / 6 * np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])[:, None], 3, 1)
    else:  # the faces stay rectangles: a quarter of p times the area vector on each corner
        share = np.repeat(p / 8 * np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])[:, None], 4, 1)
    hand = _assembled(facets, share, sim.mesh.n_points)
    assert np.linalg.norm(applied - hand) <= 1e-8 * np.linalg.norm(hand)
    # the report: the support holds the block up with p times the deformed top area, and the
    # pressure's term is the frozen load's potential -f . x = p a^2 s
    assert sim.forces()["bottom"][2] == pytest.approx(p * a * a, rel=1e-8)
    assert sim.energies()["top"] == pytest.approx(p * a * a * s, rel=1e-8)
    dead = pressed_block(element, False, p)
    for _ in range(2):
        dead.step()
    assert dead.body_positions("body")[:, 2].max() == pytest.approx(s_dead, rel=1e-8)
    assert s_dead - s > 0.018


def cantilever(follower: bool, steps: int = 2, p: float = 10.0) -> ts.Simulation:
    """A 4 x 1 x 0.5 hexahedral cantilever clamped at x = 0, p on its top face."""
    mesh = ts.box((0.0, 0.0, 0.0), (4.0, 1.0, 0.5), (8, 2, 2), element="hex")
    sim = ts.Simulation(mesh, ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=NU),
                        integrator="quasistatic", time_step=1.0 / steps)  # fmt: skip
    sim.fix(np.flatnonzero(mesh.points[:, 0] == 0), name="wall")
    top = mesh.facet_sets["zmax"]
    if follower:
        sim.add_follower_pressure(top, lambda t: p * t)
    else:
        sim.add_traction(top, lambda X, t: np.tile([0, 0, -p * t], (len(X), 1)))
    return sim


def test_a_cantilever_bends_under_a_load_normal_to_its_deformed_top_face():
    """Tip displacement: follower (-0.5953, -1.9601), dead (-0.5445, -1.9006); 6 and 10
    re-lags in the two steps; the inner solves converge quadratically at a fixed lag."""
    sim, relags = cantilever(True), []
    for _ in range(2):
        sim.step()
        relags += [e.relags for e in _lagged(sim)]
    dead = cantilever(False)
    for _ in range(2):
        dead.step()
    P = sim.mesh.points
    tip = P[:, 0] == 4
    u = (sim.body_positions("body") - P)[tip].mean(axis=0)
    u_dead = (dead.body_positions("body") - P)[tip].mean(axis=0)
    np.testing.assert_allclose(u[[0, 2]], [-0.5953, -1.9601], atol=1e-4)
    np.testing.assert_allclose(u_dead[[0, 2]], [-0.5445, -1.9006], atol=1e-4)
    assert relags == [6, 10]
    # the load on each deformed face: its resultant is p times the face's area vector (half the
    # cross product of its diagonals), and node by node the 5 x 5 Gauss integral
    x = sim.body_positions("body")
    (energy,) = _lagged(sim)
    facets = sim.mesh.facet_sets["zmax"]
    X = x[facets]
    applied, _ = energy.nodal(x.ravel())
    hand = _assembled(facets, _gauss_loads(X, 10.0), sim.mesh.n_points)
    assert np.linalg.norm(applied - hand) <= 1e-8 * np.linalg.norm(hand)
    resultant = facet_loads(X, 10.0).sum(axis=1)
    area = 0.5 * np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
    np.testing.assert_allclose(resultant, 10.0 * area, rtol=1e-12, atol=1e-12)
    normal = area / np.linalg.norm(area, axis=1, keepdims=True)
    assert normal[:, 0].max() > 0.6  # the faces near the tip turned by 40 degrees
    total = applied.reshape(-1, 3).sum(axis=0)  # the follower load turned with them: -x
    assert total[0] > 0.2 * abs(total[2])
    # the second step's first inner solve, lagged at its start, converges quadratically
    from tissuesim.solve.newton import NewtonOptions, minimize

    sim = cantilever(True)
    sim.step()
    energies = sim.step_energies(1.0, None, 0.5)
    c0 = sim.system.apply_prescribed(sim.state.x.copy(), 1.0)
    (lagged,) = [e for es in energies for e in es if isinstance(e, LaggedPressureEnergy)]
    lagged.set_lag(c0)
    _, record = minimize(
        lambda c, order, project: sim.system.evaluate(c, order, project, energies),
        c0, sim.system.elimination, sim._linear_solver(), NewtonOptions(),
        force_scale=sim.system.force_scale, length_scale=sim.system.length_scale,
    )  # fmt: skip
    g = np.array(record.gradient_norms) / record.gradient_norms[0]  # 7e-4, 4e-6, 3e-12
    assert record.converged and not any(record.projected) and g[-1] < 1e-10
    assert g[-1] <= g[-2] ** 1.8 and g[-2] <= g[-3] ** 1.5


def test_a_load_that_does_not_settle_fails_the_step_in_one_line(monkeypatch):
    monkeypatch.setattr(pressure_lag, "MAX_RELAGS", 1)
    sim = cantilever(True)
    with pytest.raises(ConvergenceError, match=r"'pressure' did not settle in 1 re-lags") as e:
        sim.step()
    assert "\n" not in str(e.value)


def test_friction_and_a_follower_pressure_are_lagged_together():
    """A block sliding down a frictional incline, pressed onto it by p on its top face: it
    accelerates at g (sin theta - mu cos theta) - mu p A / m, friction still lagged twice per
    step while the pressure re-lags until it settles."""
    pytest.importorskip("ipctk")
    from tissuesim.contact.obstacles import plane

    tan_theta, mu, p, g, h = 0.8, 0.5, 100.0, 9.81, 0.01
    theta = np.arctan(tan_theta)
    mesh = ts.box((0, 0, 5e-5), (0.1, 0.1, 0.05 + 5e-5), (3, 3, 2))
    sim = ts.Simulation(mesh, ts.make_material("neo_hookean", youngs_modulus=1e5,
                        poisson_ratio=0.3), density=1000.0, integrator="backward_euler",
                        time_step=h)  # fmt: skip
    sim.add_gravity([g * np.sin(theta), 0.0, -g * np.cos(theta)])
    sim.add_obstacle("ramp", plane((0.05, 0.05, 0.0), (0, 0, 1), 8.0))
    sim.set_contact(dhat=1e-4, friction=mu)
    sim.add_follower_pressure(mesh.facet_sets["zmax"], p)
    v, relags = [], []
    for _ in range(40):
        record = sim.step()
        assert record.extra["contact"]["friction_solves"] == 2
        relags += [e.relags for e in _lagged(sim)]
        v.append(sim.state.v.reshape(-1, 3)[:, 0].mean())
    t = h * np.arange(1, 41)
    a = np.polyfit(t[20:], v[20:], 1)[0]
    mass = 1000.0 * 0.1 * 0.1 * 0.05
    assert a == pytest.approx(g * (np.sin(theta) - mu * np.cos(theta)) - mu * p * 0.01 / mass,
                              rel=0.02)  # fmt: skip
    assert max(relags) >= 1
