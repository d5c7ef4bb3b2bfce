"""Rayleigh damping (energies/damping.py): a free vibration in one mode of a linear elastic
body decays as Backward Euler with the dissipation term predicts, mode by mode."""

import numpy as np
import pytest
import scipy.linalg as sla

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.time.state import State


def _mode_and_simulation(alpha, beta, h):
    mesh = ts.rectangle((0, 0), (2.0, 0.4), (6, 2))
    sim = ts.Simulation(mesh, ts.LinearElastic(youngs_modulus=1e4, poisson_ratio=0.3),
                        density=10.0, time_step=h)  # fmt: skip
    sim.fix(ts.select.vertices_on_plane(mesh, axis=0, value=0.0))
    sim.set_damping(mass=alpha, stiffness=beta)
    model = sim.bodies["body"].model
    X = mesh.points.ravel()
    acc = model.evaluate(X, 2, False)
    K = model.pattern.matrix(acc.hessian).toarray()
    M = model.mass.matrix().toarray()
    free = np.setdiff1d(np.arange(X.size), model.prescribed_dofs)
    w2, V = sla.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)])
    phi = np.zeros(X.size)
    phi[free] = V[:, 0]  # the first bending mode, M-normalised
    return sim, X, M, phi, float(np.sqrt(w2[0]))


@pytest.mark.parametrize("alpha, beta", [(0.0, 0.0), (2.0, 0.0), (0.0, 2e-3), (1.0, 1e-3)])
def test_a_free_vibration_decays_at_the_predicted_rate(alpha, beta):
    h, eps, steps = 2e-3, 1e-4, 150
    sim, X, M, phi, omega = _mode_and_simulation(alpha, beta, h)
    sim.state = State(0.0, X + eps * phi, np.zeros_like(X))
    q = [eps]
    for _ in range(steps):
        sim.step()
        q.append(float(phi @ M @ (sim.state.x - X)))
    # Backward Euler with the damping potential, in the mode's coordinate (c = alpha +
    # beta omega^2): (q+ - 2 q + q-)/h^2 + c (q+ - q)/h + omega^2 q+ = 0, q_-1 = q_0
    c = alpha + beta * omega**2
    ref, prev = [eps], eps
    for _ in range(steps):
        new = (ref[-1] * (2 + c * h) - prev) / (1 + c * h + (omega * h) ** 2)
        prev = ref[-1]
        ref.append(new)
    assert np.abs(np.array(q) - ref).max() < 1e-6 * eps
    # the predicted rate: the roots z of (1 + c h + w^2 h^2) z^2 - (2 + c h) z + 1 = 0
    z = np.roots([1 + c * h + (omega * h) ** 2, -(2 + c * h), 1.0])
    rate = -np.log(np.abs(z[0])) / h  # 1/s; -> c/2 + omega^2 h/2 for small h
    assert rate == pytest.approx(0.5 * c + 0.5 * omega**2 * h, rel=0.1)
    # and the simulated amplitude follows it: q_n = a z0^n + b z1^n (a + b = q_0 and
    # a / z0 + b / z1 = q_-1 = q_0), so |q_n| <= (|a| + |b|) |z|^n
    a, b = np.linalg.solve([[1, 1], [1 / z[0], 1 / z[1]]], [eps, eps])
    A = abs(a) + abs(b)
    n = np.arange(steps + 1)
    assert np.all(np.abs(q) <= A * np.abs(z[0]) ** n * (1 + 1e-6) + 1e-9 * eps)


def test_damping_needs_an_implicit_integrator_and_a_scene_takes_it(tmp_path):
    sim = ts.Simulation(ts.rectangle(), ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
                        integrator="explicit", time_step=1e-4)  # fmt: skip
    with pytest.raises(InputError, match="needs an implicit integrator"):
        sim.set_damping(mass=1.0)
    from tissuesim.scene.loader import load_scene

    scene = tmp_path / "d.toml"
    scene.write_text(
        '[mesh]\ngenerator = "rectangle"\n[material]\nmodel = "neo_hookean"\n'
        "youngs_modulus = 1e3\npoisson_ratio = 0.3\n"
        "[simulation]\ndamping = { mass = 0.5, stiffness = 1e-3 }\n"
    )
    model = load_scene(scene).simulation.bodies["body"].model
    assert model.damping == (0.5, 1e-3)
    scene.write_text(scene.read_text().replace("stiffness", "stifness"))
    with pytest.raises(ts.errors.SceneError, match="did you mean 'stiffness'"):
        load_scene(scene)
