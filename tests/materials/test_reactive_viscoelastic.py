"""FEBio's reactive visco-elasticity (materials/reactive/reactive_viscoelastic.py): finite
differences of the step's potential with generations (types I and II, uncoupled), the
relaxation functions against their spectra, the generations' closed form under a ramp and
hold (verification/reactive_viscoelastic.py), FEBio's rule for new generations, a FEBio model,
checkpoint resume and a rejected attempt, and the one-line errors."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from stress_differences import pointwise_difference

import tissuesim as ts
from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.reactive.reactive_viscoelastic import (
    ReactiveViscoelastic,
    UncoupledReactiveViscoelastic,
)
from tissuesim.materials.reactive.relaxation import Relaxation
from tissuesim.scene.loader import load_febio
from tissuesim.verification import reactive_viscoelastic as closed

MODELS = Path(__file__).parents[1] / "febio" / "models"
EXP = {"model": "exponential", "tau": 0.2}


def neo(E=1e3, nu=0.3):
    return ts.NeoHookean(youngs_modulus=E, poisson_ratio=nu)


def coupled(kinetics=1):
    return ReactiveViscoelastic(neo(), bond=neo(500.0, 0.2), kinetics=kinetics, relaxation={
        "model": "exp_distortion", "tau0": 0.2, "tau1": 1.0, "alpha": 2.0})  # fmt: skip


def uncoupled():
    return UncoupledReactiveViscoelastic(
        ts.MooneyRivlin(c1=200.0, c2=50.0, k=5e3), bond=ts.MooneyRivlin(c1=100.0, c2=20.0, k=1e3),
        relaxation={"model": "power", "tau": 0.3, "beta": 1.5}, k=3e3)  # fmt: skip


@pytest.mark.parametrize("build", [coupled, lambda: coupled(2), uncoupled])
def test_step_potential_matches_finite_differences_with_generations(build):
    rng = np.random.default_rng(1)
    law = build().bind(5, 3)
    for h in (0.05, 0.1, 0.07):
        law.begin_step(h)
        law.accept_step(np.eye(3) + 0.1 * rng.standard_normal((5, 3, 3)))
    assert np.all(law.generations == 3)
    w, fr = law.weights()
    assert np.all(w > 0.05) and np.allclose(fr, 0.0)  # the newest took the reforming mass
    law.begin_step(0.04)
    F = np.eye(3) + 0.12 * rng.standard_normal((5, 3, 3))
    r = law.evaluate(F, 2)
    P_fd, A_fd = pointwise_difference(law, F)
    assert np.abs(P_fd - r.stress).max() < 1e-6 * np.abs(r.stress).max()
    assert np.abs(A_fd - r.tangent).max() < 1e-6 * np.abs(r.tangent).max()
    A = r.tangent.reshape(5, 9, 9)
    assert np.allclose(A, np.swapaxes(A, 1, 2), atol=1e-9 * np.abs(A).max())
    _, fr = law.weights()
    assert np.all(fr > 0.01)  # in the step the reforming bonds carry mass again


def test_relaxation_functions_are_their_spectra():
    """Fung: a uniform spectrum of exponentials in tau on [tau1, tau2]; Malkin: tau^-beta on
    [tau1, tau2]; CSexp: int_0^inf exp(-t/u - u/tau) du / tau = s K1(s); Prony normalised."""
    t = np.array([0.0, 0.05, 0.4, 3.0])
    zero = np.zeros_like(t)

    def spectrum(weight, a, b, ti):
        num = quad(lambda s: weight(s) * np.exp(-ti / s), a, b, epsabs=0, epsrel=1e-12)[0]
        return num / quad(weight, a, b, epsabs=0, epsrel=1e-12)[0]

    fung = Relaxation("t", {"model": "relaxation-Fung", "tau1": 0.1, "tau2": 2.0})
    ref = [spectrum(lambda s: 1.0, 0.1, 2.0, ti) for ti in t]
    np.testing.assert_allclose(fung(t, zero), ref, rtol=1e-9)
    for beta in (1.0, 1.25, 2.5, 0.25):  # beta < 1: the user form only (FEBio's range)
        kind = "Malkin" if beta >= 1 else "Malkin-dist-user"
        malkin = Relaxation("t", {"model": kind, "tau1": 0.1, "tau2": 2.0, "beta": beta})
        ref = [spectrum(lambda s, b=beta: s**-b, 0.1, 2.0, ti) for ti in t]
        np.testing.assert_allclose(malkin(t, zero), ref, rtol=1e-8)
    cs = Relaxation("t", {"model": "CSexp", "tau": 0.7})
    ref = [1.0] + [quad(lambda u, x=ti: np.exp(-x / u - u / 0.7), 0, np.inf, epsrel=1e-12)[0] / 0.7
                   for ti in t[1:]]  # fmt: skip
    np.testing.assert_allclose(cs(t, zero), ref, rtol=1e-8)
    prony = Relaxation("t", {"model": "prony", "g": [0.3, 0.1], "t": [0.1, 1.0]})
    np.testing.assert_allclose(prony(t, zero), (0.3 * np.exp(-t / 0.1) + 0.1 * np.exp(-t)) / 0.4)
    K2 = np.array([0.0, 0.1, 0.2, 0.3])
    user = Relaxation("t", {"model": "exp_dist_user", "tau": "1 + 10*K2**2"})
    dist = Relaxation("t", {"model": "exp_distortion", "tau0": 1.0, "tau1": 10.0, "alpha": 2.0})
    np.testing.assert_allclose(user(t, K2), np.exp(-t / (1 + 10 * K2**2)), rtol=1e-14)
    np.testing.assert_allclose(dist(t, K2), user(t, K2), rtol=1e-14)
    power = Relaxation("t", {"model": "power", "tau": 0.2, "beta": 1.5})
    park = Relaxation("t", {"model": "park", "tau": 0.2, "beta": 1.5})
    np.testing.assert_allclose(power(t, zero), (1 + t / 0.2) ** -1.5)
    np.testing.assert_allclose(park(t, zero), 1 / (1 + (t / 0.2) ** 1.5))


@pytest.mark.parametrize("kinetics", [1, 2])
def test_ramp_and_hold_is_the_generations_closed_form(kinetics):
    times, got = closed.generations(kinetics)
    ref = closed.closed_form(times, kinetics)
    np.testing.assert_allclose(got, ref, rtol=1e-10)
    assert got[-1] < 0.8 * got[1]  # it relaxed
    assert all(c.passed for c in closed.checks())


def test_new_generations_follow_febios_trigger():
    """A generation starts breaking only when the strain from the last one's stretch exceeds
    max(emin, 10 eps); a rigid rotation of the held stretch is no strain."""
    law = ReactiveViscoelastic(neo(), bond=neo(), relaxation=EXP, emin=1e-3).bind(1, 3)
    F = np.diag([1.1, 1.0, 1.0])[None]
    for step, (G, expected) in enumerate([(F, 1), (F, 1), (F * 1.0005, 1), (F * 1.002, 2)]):
        law.begin_step(0.1)
        law.accept_step(G)
        assert law.generations[0] == expected, step
    c, s = np.cos(0.3), np.sin(0.3)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    law.begin_step(0.1)
    law.accept_step(R @ F * 1.002)
    assert law.generations[0] == 2
    np.testing.assert_allclose(law.stress(R @ F * 1.002), R @ law.stress(F * 1.002), atol=1e-10)
    # the original bonds carry their full stress until a generation forms
    fresh = ReactiveViscoelastic(neo(), bond=neo(300.0), relaxation=EXP).bind(1, 3)
    fresh.begin_step(0.1)
    np.testing.assert_allclose(fresh.stress(F), neo().stress(F) + neo(300.0).stress(F))


def test_febio_model_follows_the_closed_form():
    sim = load_febio(MODELS / "reactive_viscoelastic_relaxation.feb").simulation
    forces = np.array([abs(sim.step().extra["forces"]["pull"][0]) for _ in range(20)])
    times = 0.1 * np.arange(1, 21)
    assert (closed.MU_S, closed.MU_B) == (100.0, 60.0)  # the model's E = 200, 120, v = 0
    assert closed.RELAXATION == {"model": "exp_distortion", "tau0": 0.3, "tau1": 2.0,
                                 "alpha": 1.0}  # fmt: skip
    np.testing.assert_allclose(forces, closed.closed_form(times, 1), rtol=1e-9)


def uniaxial(h=0.1):
    law = coupled()
    mesh = ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="hex")
    sim = ts.Simulation(mesh, law, integrator="quasistatic", time_step=h)
    for axis in range(3):
        sim.add_dirichlet(ts.select.vertices_on_plane(mesh, axis=axis, value=0.0),
                          components=(axis,), name=f"sym{axis}")  # fmt: skip
    right = ts.select.vertices_on_plane(mesh, axis=0, value=1.0)
    sim.add_dirichlet(right, lambda X, t: np.outer(np.ones(len(X)), [0.4 * t, 0, 0]),
                      components=(0,), name="pull")  # fmt: skip
    return sim


def test_checkpoint_and_rejected_attempts_keep_the_generations(tmp_path, monkeypatch):
    whole = uniaxial()
    for _ in range(6):
        whole.step()
    first = uniaxial()
    for _ in range(3):
        first.step()
    first.save(tmp_path / "c.npz")
    second = uniaxial().load(tmp_path / "c.npz")
    for _ in range(3):
        second.step()
    a, b = (s.bodies["body"].model.material.state_arrays() for s in (whole, second))
    assert np.all(a["count"] == 6)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])
    np.testing.assert_array_equal(whole.state.x, second.state.x)

    import tissuesim.time.steps as steps

    real, calls = steps.implicit_step, {"n": 0}

    def flaky(system, state, dt, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 1:  # converged, then rejected: the generations must not move
            real(system, state, dt, *args, **kwargs)
            return steps.StepOutcome(None, False, [], "rejected by the test")
        return real(system, state, dt, *args, **kwargs)

    monkeypatch.setattr(steps, "implicit_step", flaky)
    halved = uniaxial(h=0.2)
    halved.step()
    monkeypatch.setattr(steps, "implicit_step", real)
    small = uniaxial(h=0.1)
    small.step()
    small.step()
    assert halved.history[0].substeps == 2
    c, d = (s.bodies["body"].model.material.state_arrays() for s in (halved, small))
    for key in c:
        np.testing.assert_allclose(c[key], d[key], rtol=1e-10, atol=1e-14)


def test_by_name_and_one_line_errors():
    law = make_material("reactive viscoelastic", elastic={"model": "neo_hookean",
                        "youngs_modulus": 1e3, "poisson_ratio": 0.3}, bond={"model":
                        "neo_hookean", "youngs_modulus": 5e2, "poisson_ratio": 0.3},
                        relaxation={"model": "relaxation-exponential", "tau": 0.2})  # fmt: skip
    assert isinstance(law, ReactiveViscoelastic) and law.relaxation.kind == "exponential"
    law = make_material("uncoupled_reactive_viscoelastic", elastic={"model": "mooney_rivlin",
                        "c1": 1.0, "c2": 0.5}, bond={"model": "mooney_rivlin", "c1": 1.0,
                        "c2": 0.5}, relaxation=EXP, k=2e3)  # fmt: skip
    assert isinstance(law, UncoupledReactiveViscoelastic) and law.k == 2e3
    bad = [
        ({"relaxation": {"model": "carreau"}}, "not one tissuesim has"),
        ({"relaxation": {"model": "exponential"}}, "exponential needs tau"),
        ({"relaxation": {"model": "exponential", "tau": -1.0}}, "tau must be >"),
        ({"relaxation": {"model": "exp_dist_user", "tau": "1 + t"}}, "its variable is K2"),
        ({"relaxation": EXP, "kinetics": 3}, "kinetics must be one of"),
        ({"relaxation": EXP, "wmin": 1.5}, "wmin must be in"),
        ({"relaxation": EXP, "emin": -1.0}, "emin must be >= 0"),
    ]
    for kwargs, message in bad:
        with pytest.raises(MaterialError, match=message):
            ReactiveViscoelastic(neo(), bond=neo(), **kwargs)
    with pytest.raises(MaterialError, match="needs bond"):
        ReactiveViscoelastic(neo(), relaxation=EXP)
    with pytest.raises(MaterialError, match="needs an uncoupled bond law"):
        UncoupledReactiveViscoelastic(ts.MooneyRivlin(c1=1.0, c2=0.5, k=1e3), bond=neo(),
                                      relaxation=EXP)  # fmt: skip
