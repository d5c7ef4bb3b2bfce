"""The generalised-alpha method (time/integrators/generalized_alpha.py): FEBio's weights from
rho_inf, the spectral radius of its amplification matrix, a mass-spring under gravity against
the closed-form recurrence of the method and against the exact motion (second order), and
its step's potential (value, gradient, Hessian) against finite differences."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.time.integrators.generalized_alpha import (
    check_generalized_alpha,
    febio_weights,
    midpoint_correction,
)

MATERIAL = ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3)
G = 9.81
K = 800.0  # N/m
MASS = 1000.0 * 0.2**3  # kg, the box below


def _step_matrix(omega_h: float, weights) -> tuple[np.ndarray, np.ndarray]:
    """(A, b): the method's step of m x'' + k x = f on (x, h v, h^2 a) is z1 = A z0 + b f h^2/m,
    from alpha_m a1 + (1 - alpha_m) a0 + w^2 (alpha_f x1 + (1 - alpha_f) x0) = f / m and
    Newmark's two updates (the implicit system solved as it stands)."""
    af, am, beta, gamma = weights
    w2 = omega_h**2
    # unknowns (x1, v1 h, a1 h^2); rows: the equation of motion, Newmark's x and v updates
    lhs = np.array([[af * w2, 0.0, am], [1.0, 0.0, -beta], [0.0, 1.0, -gamma]])
    rhs = np.array(
        [[-(1 - af) * w2, 0.0, -(1 - am)], [1.0, 1.0, 0.5 - beta], [0.0, 1.0, 1.0 - gamma]]
    )
    A = np.linalg.solve(lhs, rhs)
    b = np.linalg.solve(lhs, np.array([1.0, 0.0, 0.0]))
    return A, b


@pytest.mark.parametrize("rho", [0.0, 0.25, 0.5, 0.8, 1.0])
def test_febio_weights_give_the_spectral_radius_rho_at_infinite_step(rho):
    """FEBio's rhoi: the amplification matrix's spectral radius tends to rho as omega h grows
    (the method's definition), never exceeds 1 (unconditional stability), and the weights
    are second-order (gamma = 1/2 + alpha_m - alpha_f)."""
    weights = febio_weights(rho)
    af, am, beta, gamma = weights
    assert gamma == pytest.approx(0.5 + am - af)
    radius = max(abs(np.linalg.eigvals(_step_matrix(1e9, weights)[0])))
    assert radius == pytest.approx(rho, abs=1e-4)
    for omega_h in np.geomspace(1e-2, 1e3, 40):
        assert max(abs(np.linalg.eigvals(_step_matrix(omega_h, weights)[0]))) <= 1 + 1e-9


def test_rho_inf_one_is_the_midpoint_rule_and_check_refuses_the_unstable():
    assert febio_weights(1.0) == (0.5, 0.5, 0.25, 0.5)
    assert febio_weights(0.0) == (1.0, 2.0, 1.0, 1.5)
    assert check_generalized_alpha((1.0, 1.0, 0.25, 0.5)) == (1.0, 1.0, 0.25, 0.5)
    for bad in (1.5, -0.5, (0.4, 0.4, 0.25, 0.5), (1.0, 0.5, 0.25, 0.5), (1, 1, 0.1, 0.5), "x"):
        with pytest.raises(InputError, match="generalized_alpha"):
            check_generalized_alpha(bad)
    with pytest.raises(InputError, match="generalized_alpha rho_inf"):
        ts.Simulation(integrator="generalized_alpha", generalized_alpha=2.0)


def _mass_spring(h: float, rho: float) -> ts.Simulation:
    """A rigid box (8 kg) on a vertical spring of 800 N/m from a fixed ground, under gravity,
    released at rest with the spring at its free length: one DOF, z (the spring acts at
    x_{n+alpha_f}, as FEBio's rigid connectors do)."""
    mesh = ts.box((-0.1, -0.1, -0.1), (0.1, 0.1, 0.1), (1, 1, 1))
    sim = ts.Simulation(mesh, MATERIAL, density=1000.0, integrator="generalized_alpha",
                        time_step=h, gravity=(0, 0, -G), generalized_alpha=rho)  # fmt: skip
    sim.add_rigid_body("box", ["body"], fixed=("x", "y", "rx", "ry", "rz"))
    sim.add_rigid_body("ground", center=(0, 0, 1.0), fixed=("x", "y", "z", "rx", "ry", "rz"))
    sim.add_rigid_spring("ground", "box", (0, 0, 1.0), (0, 0, 0), K)
    return sim


def _heights(sim: ts.Simulation, steps: int) -> np.ndarray:
    out = []
    for _ in range(steps):
        sim.step()
        out.append(sim.state.x[-24 + 2])  # the box's centre z (the first rigid block)
    return np.array(out)


@pytest.mark.parametrize("rho", [0.0, 0.5, 1.0])
def test_a_mass_spring_follows_the_methods_closed_form_recurrence(rho):
    """The box's height step by step equals the recurrence z_{n+1} = A z_n + b g h^2 of the
    method's amplification matrix from FEBio's a_0 = -g (Newton's tolerance aside), for
    omega h = 0.2 and 2 (where the numerical damping of rho < 1 shows)."""
    for h in (0.02, 0.2):
        steps = 12
        sim = _mass_spring(h, rho)
        got = _heights(sim, steps)
        A, b = _step_matrix(np.sqrt(K / MASS) * h, febio_weights(rho))
        z = np.array([0.0, 0.0, -G * h * h])
        expected = []
        for _ in range(steps):
            z = A @ z + b * (-G) * h * h
            expected.append(z[0])
        amplitude = G * MASS / K
        assert np.max(np.abs(got - expected)) < 1e-7 * amplitude, (h, got, expected)


def test_a_mass_spring_converges_at_second_order():
    """Against the exact motion z = -(g / w^2) (1 - cos w t) at t = 0.4 s: the error of rho =
    0.5 falls by about 4 when h halves (second-order accuracy, with its numerical damping)."""
    omega = np.sqrt(K / MASS)
    errors = []
    for h in (0.04, 0.02, 0.01):
        z = _heights(_mass_spring(h, 0.5), round(0.4 / h))[-1]
        errors.append(abs(z + G / omega**2 * (1 - np.cos(omega * 0.4))))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 3.5) & (ratios < 4.5)), (errors, ratios)


def test_rho_inf_one_damps_nothing_and_rho_zero_damps_the_high_mode():
    """With omega h = 2: rho = 1 keeps the oscillation's amplitude; rho = 0 damps it, as the
    recurrence says (its eigenvalues' modulus below 0.7 there)."""
    h = 0.2
    amplitude = G * MASS / K
    kept = _heights(_mass_spring(h, 1.0), 60)
    damped = _heights(_mass_spring(h, 0.0), 60)
    # about the equilibrium -amplitude: the swing at the end
    assert np.max(np.abs(kept[-10:] + amplitude)) > 0.9 * amplitude
    assert np.max(np.abs(damped[-10:] + amplitude)) < 1e-3 * amplitude


def _cantilever(rho: float, h: float = 0.05) -> ts.Simulation:
    mesh = ts.box((0, 0, 0), (1, 0.2, 0.2), (3, 1, 1))
    sim = ts.Simulation(mesh, MATERIAL, density=1000.0, integrator="generalized_alpha",
                        time_step=h, generalized_alpha=rho, gravity=(0, 0, -G))  # fmt: skip
    sim.fix(ts.select.vertices_on_plane(mesh, axis=0, value=0.0))
    return sim


@pytest.mark.parametrize("rho", [0.0, 0.3, 1.0])
def test_a_step_solves_febios_generalised_alpha_equation(rho):
    """A sagging cantilever (large rotations): after each step the state satisfies FEBio's
    equation itself, M (alpha_m a_{n+1} + (1 - alpha_m) a_n) + f_int(x_{n+alpha_f}) =
    f(t_{n+1}) on the free DOFs, with Newmark's a_{n+1} and v_{n+1} from x_{n+1}: the
    minimisation over y (Backward Euler's with h_e and y_pred) is that equation (rho = 1:
    with FEBio's stress correction of the midpoint rule)."""
    h = 0.05
    af, am, beta, gamma = febio_weights(rho)
    sim = _cantilever(rho, h)
    model = sim.body().model
    M = model.mass.matrix().tocsr()
    free = np.ones(sim.state.x.size, dtype=bool)
    free[model.prescribed_dofs] = False
    sim.step()  # the first step from FEBio's a_0
    for _ in range(3):
        x0, v0, a0 = sim.state.x, sim.state.v, sim.state.a
        sim.step()
        x1, v1, a1 = sim.state.x, sim.state.v, sim.state.a
        assert np.allclose(a1, (x1 - x0 - h * v0 - h * h * (0.5 - beta) * a0) / (beta * h * h))
        assert np.allclose(v1, v0 + h * ((1 - gamma) * a0 + gamma * a1))
        y = af * x1 + (1 - af) * x0
        static = sim.step_energies(sim.time, None, h)  # elastic energy and the loads at t_{n+1}
        grad = sim.system.evaluate(y, 1, False, static).gradient
        if af == 0.5:  # FEBio's energy-conserving correction of the midpoint rule
            grad = grad + midpoint_correction(model, x0, x1, h)
        residual = (M @ (am * a1 + (1 - am) * a0) + grad)[free]
        scale = np.abs(M @ a1).max() + np.abs(grad[free]).max()
        assert np.abs(residual).max() < 1e-6 * scale


def test_the_steps_potential_has_its_gradient_and_hessian():
    """The step's Phi over the intermediate configuration y (Backward Euler's potential with
    h_e about y_pred, time/steps.py): its value's slope and its Hessian's product with a
    direction against central differences at a deformed y of the cantilever."""
    h = 0.05
    af, am, beta, _ = febio_weights(0.3)
    sim = _cantilever(0.3, h)
    sim.step()
    s, x = sim.system, sim.state.x
    h_e = h * np.sqrt(beta * af / am)
    rng = np.random.default_rng(0)
    energies = sim.step_energies(sim.time + h, x + 0.01 * rng.standard_normal(x.size), h_e)
    y = x + 0.02 * rng.standard_normal(x.size)
    d = rng.standard_normal(x.size)
    eps = 1e-6
    acc = s.evaluate(y, 2, False, energies)
    phi_p, phi_m = (s.evaluate(y + e * d, 0, False, energies).value for e in (eps, -eps))
    assert (phi_p - phi_m) / (2 * eps) == pytest.approx(acc.gradient @ d, rel=1e-6)
    g_p, g_m = (s.evaluate(y + e * d, 1, False, energies).gradient for e in (eps, -eps))
    H = s.pattern.matrix(acc.hessian)
    assert np.allclose(H @ d, (g_p - g_m) / (2 * eps), rtol=0, atol=1e-6 * np.abs(H @ d).max())


@pytest.mark.parametrize("rho", [0.0, 0.5, 1.0])
def test_a_free_rigid_body_spins_at_its_angular_velocity(rho):
    """A free rigid box (0.4 x 0.2 x 0.1 m) spinning at 2 rad/s about its longest principal
    axis of inertia, no torque: after 1 s it has turned 2 rad about that axis, its centre
    still (y and x_{n+1} go through the retraction: nothing spurious), for every rho."""
    from dataclasses import replace

    from tissuesim.frames.rotations import log_map

    mesh = ts.box((-0.2, -0.1, -0.05), (0.2, 0.1, 0.05), (2, 1, 1))
    sim = ts.Simulation(mesh, MATERIAL, density=1000.0, integrator="generalized_alpha",
                        time_step=0.05, generalized_alpha=rho)  # fmt: skip
    sim.add_rigid_body("box", ["body"])
    v = sim.state.v.copy()
    v[sim.system.rigid_tangent_slices[0].start + 5] = 2.0  # about z (rigid/body.py DOFs)
    sim.state = replace(sim.state, v=v)
    for _ in range(20):
        sim.step()
    centre, R = sim.rigid_state("box")
    assert log_map(R)[0] == pytest.approx([0.0, 0.0, 2.0], abs=1e-10)
    assert centre == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)


def test_prescribed_values_hold_at_the_step_end_and_at_t_n_plus_alpha_f():
    """The cantilever's tip pushed up at 0.5 m/s (a prescribed displacement linear in t):
    after each step x_{n+1} holds it at t_{n+1} exactly, the solve's y held it at t_n +
    alpha_f h (= alpha_f x_{n+1} + (1 - alpha_f) x_n there), and FEBio's equation holds on
    the free DOFs."""
    h, rho = 0.05, 0.4
    af, am, _, _ = febio_weights(rho)
    sim = _cantilever(rho, h)
    mesh = sim.body().mesh
    tip = ts.select.vertices_on_plane(mesh, axis=0, value=1.0)
    sim.add_dirichlet(
        tip, lambda X, t: np.stack([0 * X[:, 0], 0 * X[:, 1], 0.5 * t + 0 * X[:, 2]], axis=1)
    )
    model = sim.body().model
    M = model.mass.matrix().tocsr()
    free = np.ones(sim.state.x.size, dtype=bool)
    free[model.prescribed_dofs] = False
    sim.step()
    for _ in range(3):
        x0, a0 = sim.state.x, sim.state.a
        sim.step()
        x1, a1 = sim.state.x, sim.state.a
        lifted = (x1 - mesh.points.ravel()).reshape(-1, 3)[tip, 2]
        assert lifted == pytest.approx(0.5 * sim.time, abs=1e-14)
        y = af * x1 + (1 - af) * x0
        static = sim.step_energies(sim.time, None, h)
        grad = sim.system.evaluate(y, 1, False, static).gradient
        residual = (M @ (am * a1 + (1 - am) * a0) + grad)[free]
        assert np.abs(residual).max() < 1e-6 * (np.abs(M @ a1).max() + np.abs(grad[free]).max())


def test_a_pulled_rigid_motion_under_contact_is_refused_in_one_line():
    """With contact, a rigid body's prescribed DOFs are pulled by springs to their values at
    the step's end: with alpha_f < 1 that would pull y there; refused in one line (rho_inf =
    0, alpha_f = 1, runs)."""
    mesh = ts.box((0, 0, 0), (0.2, 0.2, 0.2), (1, 1, 1))
    for rho, refused in ((0.5, True), (0.0, False)):
        sim = ts.Simulation(mesh, MATERIAL, density=1000.0, integrator="generalized_alpha",
                            time_step=0.01, generalized_alpha=rho)  # fmt: skip
        platen = ts.box((0, 0, 0.3), (0.2, 0.2, 0.4), (1, 1, 1))
        sim.add_body("platen", platen, MATERIAL, density=1000.0)
        sim.fix(ts.select.vertices_on_plane(mesh, axis=2, value=0.0), body="body")
        sim.add_rigid_body("press", ["platen"], prescribed={"z": lambda t: -0.1 * t})
        sim.set_contact(dhat=0.01)
        if refused:
            with pytest.raises(InputError, match="rigid body's prescribed") as info:
                sim.step()
            assert "\n" not in str(info.value)
        else:
            sim.step()


def test_the_midpoint_rule_conserves_the_energy_with_febios_correction(monkeypatch):
    """rho_inf = 1 (alpha_f = 1/2): with FEBio's stress correction (UpdateElementStress) the
    total energy of a cantilever swung through large rotations stays constant to 1e-8 over 40
    steps (the discrete gradient: the step's internal work is the change of strain energy);
    without it (no update of the correction) the plain midpoint rule drifts by more than
    1e-3."""
    import tissuesim.time.integrators.generalized_alpha as ga

    def drift(updates: int) -> float:
        monkeypatch.setattr(ga, "MIDPOINT_UPDATES", updates)
        mesh = ts.box((0, 0, 0), (1, 0.2, 0.2), (6, 1, 1))
        sim = ts.Simulation(mesh, MATERIAL, density=1000.0, integrator="generalized_alpha",
                            time_step=0.05, generalized_alpha=1.0)  # fmt: skip
        sim.fix(ts.select.vertices_on_plane(mesh, axis=0, value=0.0))
        v = np.zeros((mesh.n_points, 3))
        v[:, 2] = 2.0 * mesh.points[:, 0]
        sim.set_velocity(v)
        energy = np.array([_total(sim.step()) for _ in range(40)])
        assert energy[0] == pytest.approx(1000.0 * 0.04 * 4.0 / 6.0, rel=1e-3)  # the start's
        return float(np.abs(energy - energy[0]).max() / energy[0])

    assert drift(ga.MIDPOINT_UPDATES) < 1e-8
    assert drift(0) > 1e-3


def _total(record) -> float:
    return record.energies["elastic"] + record.energies["kinetic"]


def test_the_midpoint_correction_makes_the_internal_work_the_change_of_energy():
    """FEBio's correction at alpha_f = 1/2 (derived in generalized_alpha.py): between two
    random deformed configurations of a neo-Hookean block, (x1 - x0) . (f_int(x_1/2) + f_c)
    equals W(x1) - W(x0) to round-off (the plain midpoint force misses by far more)."""
    mesh = ts.box((0, 0, 0), (1, 0.5, 0.5), (3, 2, 2))
    model = ts.Simulation(mesh, MATERIAL, density=1000.0).body().model
    rng = np.random.default_rng(3)
    x0 = mesh.points.ravel() + 0.02 * rng.standard_normal(mesh.points.size)
    x1 = x0 + 0.03 * rng.standard_normal(mesh.points.size)
    h = 0.01
    f_int = model.evaluate(0.5 * (x0 + x1), 1, False).gradient
    dW = model.evaluate(x1, 0, False).value - model.evaluate(x0, 0, False).value
    f_c = midpoint_correction(model, x0, x1, h)
    assert (x1 - x0) @ (f_int + f_c) == pytest.approx(dW, rel=1e-10)
    assert abs((x1 - x0) @ f_int - dW) > 1e-4 * abs(dW)


SCENE = """
[mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [1.0, 0.2, 0.2]
divisions = [3, 1, 1]

[material]
model = "neo_hookean"
youngs_modulus = 1e4
poisson_ratio = 0.3

[simulation]
density = 1000.0
integrator = "generalized_alpha"
generalized_alpha = 0.5
time_step = 0.05

[gravity]
acceleration = [0.0, 0.0, -9.81]

[[dirichlet]]
vertices = { on_plane = { axis = 0, value = 0.0 } }

[run]
steps = 3
"""


def test_a_scene_selects_generalized_alpha_as_the_api_does(tmp_path):
    """[simulation] integrator = "generalized_alpha" with generalized_alpha = rho_inf: the same
    steps as Simulation(integrator="generalized_alpha", generalized_alpha=0.5)."""
    from tissuesim.scene.loader import load_scene

    path = tmp_path / "s.toml"
    path.write_text(SCENE)
    scene = load_scene(path)
    sim = scene.simulation
    assert sim.integrator == "generalized_alpha"
    assert sim.generalized_alpha == febio_weights(0.5)
    api = _cantilever(0.5)
    for _ in range(3):
        sim.step()
        api.step()
    assert np.allclose(sim.state.x, api.state.x, rtol=0, atol=1e-12)
