"""Newmark's method (time/integrators/newmark.py): exact for a constant acceleration from
FEBio's initial acceleration, energy-conserving where Backward Euler damps, quadratic Newton,
its state carried through checkpoints and phases, and one-line refusals."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.time.phases import Phase

MATERIAL = ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3)


def test_a_free_body_falls_exactly_from_the_initial_acceleration():
    """No supports, gravity only: the first step starts from a_0 = M^-1 f = g (FEBio's
    initial acceleration), and Newmark is exact for a constant acceleration: x = X + g t^2 / 2,
    v = g t, to round-off. Backward Euler is first-order off (v lags by g h / 2... h g)."""
    mesh = ts.box((0, 0, 0), (0.2, 0.2, 0.2), (2, 2, 2))
    g = np.array([0.0, 0.0, -9.81])
    sim = ts.Simulation(mesh, MATERIAL, density=1000.0, integrator="newmark", time_step=0.01,
                        gravity=g)  # fmt: skip
    for _ in range(10):
        sim.step()
    t = 0.1
    assert np.allclose(sim.positions - mesh.points, 0.5 * g * t * t, rtol=0, atol=1e-12)
    v = sim.state.v.reshape(-1, 3)
    assert np.allclose(v, g * t, rtol=0, atol=1e-12)
    euler = ts.Simulation(mesh, MATERIAL, density=1000.0, time_step=0.01, gravity=g)
    for _ in range(10):
        euler.step()
    drop = (euler.positions - mesh.points)[:, 2].mean()
    assert drop < 0.5 * g[2] * t * t - 1e-3  # Backward Euler falls h g t / 2 further


def _swinging_bar(integrator: str, h: float = 0.01, speed: float = 0.5) -> ts.Simulation:
    mesh = ts.box((0, 0, 0), (1, 0.2, 0.2), (6, 1, 1))
    sim = ts.Simulation(mesh, MATERIAL, density=1000.0, integrator=integrator, time_step=h)
    sim.fix(ts.select.vertices_on_plane(mesh, axis=0, value=0.0))
    v = np.zeros((mesh.n_points, 3))
    v[:, 2] = speed * mesh.points[:, 0]
    sim.set_velocity(v)
    return sim


def _total(record) -> float:
    return record.energies["elastic"] + record.energies["kinetic"]


def test_the_trapezoidal_rule_keeps_the_energy_backward_euler_damps():
    """A cantilever swung by an initial velocity (kinetic energy 1/6 J): over 100 steps the
    trapezoidal rule keeps the total energy to 1e-4 of itself, Backward Euler loses more than
    1 % (its numerical damping)."""
    out = {}
    for integrator in ("newmark", "backward_euler"):
        sim = _swinging_bar(integrator)
        records = [sim.step() for _ in range(100)]
        out[integrator] = [_total(r) for r in records]
    start = 1000.0 * 0.04 * 0.25 / 3 / 2  # 1/2 rho A int (v' x)^2 dx over the bar
    newmark = np.array(out["newmark"])
    assert abs(newmark[0] - start) < 1e-3 * start
    assert np.max(np.abs(newmark - newmark[0])) < 1e-4 * newmark[0]
    assert out["backward_euler"][-1] < 0.99 * out["backward_euler"][0]


def test_newmark_steps_converge_quadratically():
    sim = _swinging_bar("newmark", h=0.1, speed=5.0)  # large steps, large rotations
    sim.newton = ts.NewtonOptions(hessian_projection="never", gradient_tolerance=1e-13,
                                  absolute_tolerance=1e-14)  # fmt: skip
    for _ in range(3):
        record = sim.step()
    g = np.array(record.residual_norms[-1])
    assert len(g) >= 4  # a nonlinear step
    # from the first residual below 1 % of the start, each next one above round-off (1e-10 of
    # the start) is below a^2 / (1 % of the start): quadratic, whichever linear solver and
    # assembly backend the machine has (their iterates differ in the last digits)
    scale = 1e-2 * g[0]
    tail = [(a, b) for a, b in zip(g, g[1:], strict=False) if a < scale and b > 1e-10 * g[0]]
    assert tail and all(b <= a * a / scale for a, b in tail)
    assert any(b < 1e-2 * a for a, b in tail)  # far faster than a linear rate


def test_a_checkpoint_carries_the_accelerations(tmp_path):
    sim = _swinging_bar("newmark")
    for _ in range(5):
        sim.step()
    sim.save(tmp_path / "state.npz")
    for _ in range(5):
        sim.step()
    again = _swinging_bar("newmark").load(tmp_path / "state.npz")
    for _ in range(5):
        again.step()
    assert np.array_equal(again.state.x, sim.state.x)
    assert np.array_equal(again.state.a, sim.state.a)


def test_a_newmark_phase_after_a_quasistatic_one_starts_from_rest():
    """Gravity loaded quasistatically, then Newmark: the bar starts at rest in equilibrium
    (a = 0, as FEBio after a static step) and stays there."""
    mesh = ts.box((0, 0, 0), (1, 0.2, 0.2), (6, 1, 1))
    phases = [Phase(2, 0.5, "quasistatic"), Phase(5, 0.01, "newmark")]
    sim = ts.Simulation(mesh, MATERIAL, density=100.0, gravity=(0, 0, -9.81), phases=phases)
    sim.fix(ts.select.vertices_on_plane(mesh, axis=0, value=0.0))
    for _ in range(2):
        sim.step()
    rest = sim.positions.copy()
    for _ in range(5):
        sim.step()
    assert sim.integrator == "newmark"
    assert np.allclose(sim.positions, rest, atol=1e-9 * np.ptp(rest))


def test_newmark_refuses_what_it_cannot_run():
    with pytest.raises(InputError, match=r"1/2 <= gamma <= 2 beta"):
        ts.Simulation(integrator="newmark", newmark=(0.1, 0.5))
    with pytest.raises(InputError, match="newmark must be"):
        ts.Simulation(integrator="newmark", newmark=0.25)
    sim = _swinging_bar("newmark")
    sim.set_damping(mass=1.0)
    with pytest.raises(InputError, match="Rayleigh damping"):
        sim.step()
