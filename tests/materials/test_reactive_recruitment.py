"""FEBio's bond recruitment in the reactive viscoelastic laws (materials/reactive/
recruitment.py, reactive_viscoelastic.py): the functions against FEBio's formulas, each
generation weighed by brf of the strain it formed at, the step's potential with the forming
bonds' weight lagged against finite differences, FEBio's fixed point reached by re-lagging (a
pulled cube whose traction balances the stress of the accepted state), and the errors."""

import math

import numpy as np
import pytest
from scipy.special import erfc, gammainc
from stress_differences import pointwise_difference

import tissuesim as ts
from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.reactive import generations as gen
from tissuesim.materials.reactive.reactive_viscoelastic import (
    ReactiveViscoelastic,
    UncoupledReactiveViscoelastic,
)
from tissuesim.materials.reactive.recruitment import Recruitment

EXP = {"model": "exponential", "tau": 0.2}
X = np.array([-0.1, 0.0, 0.05, 0.3, 1.2])


def febio(kind, x, p):
    """FEBio's brf (FEBondRecruitment.cpp), one value at a time."""
    if kind == "power":
        return p["mu0"] + p["mu1"] * (x / p["scale"]) ** p["alpha"] if x > 0 else 0.0
    if kind == "exponential":
        return p["mu0"] * math.exp(p["mu1"] * (x / p["scale"]) ** p["alpha"]) if x > 0 else 0.0
    if kind == "polynomial":
        return p["mu0"] + p["mu1"] * x + p["mu2"] * x * x if x > 0 else 0.0
    if kind == "log-normal":
        if x < 0:
            return 0.0
        z = -math.log(x / p["mu"]) / p["sigma"] / math.sqrt(2) if x > 0 else math.inf
        return 1.0 + p["max"] * 0.5 * erfc(z)
    if kind == "Weibull":
        if x <= p["ploc"]:
            return 0.0
        return 1 + p["max"] * (1 - math.exp(-(((x - p["ploc"]) / p["mu"]) ** p["alpha"])))
    if kind == "quintic":
        if x <= p["mumin"]:
            return 1.0
        if x >= p["mumax"]:
            return 1.0 + p["max"]
        s = (x - p["mumin"]) / (p["mumax"] - p["mumin"])
        return 1 + p["max"] * s**3 * (10 - 15 * s + 6 * s * s)
    if kind == "gamma":
        return 1 + p["max"] * gammainc(p["alpha"], x / p["mu"]) if x > 0 else 1.0
    raise AssertionError(kind)


@pytest.mark.parametrize(
    ("kind", "params"),
    [
        ("power", {"alpha": 1.5, "mu0": 0.8, "mu1": 3.0, "scale": 0.5}),
        ("exponential", {"alpha": 2.0, "mu0": 1.1, "mu1": 0.7, "scale": 0.4}),
        ("polynomial", {"mu0": 1.0, "mu1": 2.0, "mu2": -0.5}),
        ("log-normal", {"mu": 0.2, "sigma": 0.6, "max": 1.5}),
        ("Weibull", {"alpha": 1.7, "mu": 0.3, "ploc": 0.02, "max": 2.0}),
        ("quintic", {"mumin": 0.04, "mumax": 0.5, "max": 0.9}),
        ("gamma", {"alpha": 2.5, "mu": 0.1, "max": 1.2}),
    ],
)
def test_the_recruitment_functions_are_febios(kind, params):
    got = Recruitment("t", {"model": f"recruitment {kind}", **params})(X)
    np.testing.assert_allclose(got, [febio(kind, x, params) for x in X], rtol=1e-13)
    assert len(set(np.round(got, 12))) >= 3  # the points tell the laws' shapes apart


def test_a_user_function_and_febios_defaults():
    user = Recruitment("t", {"model": "user", "function": "1 + 10*X**2"})
    np.testing.assert_allclose(user(X), 1 + 10 * X**2, rtol=1e-14)
    np.testing.assert_allclose(Recruitment("t", {"model": "power"})(X), np.where(X > 0, 1.0, 0.0))
    assert Recruitment("t", {"model": "gamma"})(X) == pytest.approx(np.ones(5))


def law(recruitment, cls=ReactiveViscoelastic, **kw):
    neo = ts.NeoHookean
    if cls is UncoupledReactiveViscoelastic:
        bond = ts.MooneyRivlin(c1=100.0, c2=20.0, k=1e3)
        return cls(ts.MooneyRivlin(c1=200.0, c2=50.0, k=5e3), bond=bond, relaxation=EXP,
                   k=3e3, recruitment=recruitment, **kw)  # fmt: skip
    return cls(neo(youngs_modulus=1e3, poisson_ratio=0.3),
               bond=neo(youngs_modulus=500.0, poisson_ratio=0.2), relaxation=EXP,
               recruitment=recruitment, **kw)  # fmt: skip


@pytest.mark.parametrize("trigger", [0, 1, 2])
def test_each_generation_carries_brf_of_the_strain_it_formed_at(trigger):
    """wv of every new generation is brf(X(F)) of the F it formed at (X: |E|, |dev ln V|,
    |ln J| by the trigger), kept as later ones form; a constant brf c scales every breaking
    generation's stress by c, but not the original bonds' before any forms (FEBio's)."""
    rng = np.random.default_rng(3)
    rec = {"model": "user", "function": "1 + 4*X"}
    m = law(rec, trigger=trigger).bind(4, 3)
    Fs = [np.eye(3) + 0.08 * (k + 1) * rng.standard_normal((4, 3, 3)) for k in range(3)]
    for k, F in enumerate(Fs):
        m.begin_step(0.1)
        m.accept_step(F)
        assert np.all(m.generations == k + 1)
        for j, G in enumerate(Fs[: k + 1]):
            C = np.swapaxes(G, 1, 2) @ G
            if trigger == 0:
                x = np.linalg.norm(0.5 * (C - np.eye(3)), axis=(1, 2))
            elif trigger == 1:
                h = 0.5 * np.log(np.linalg.eigvalsh(C))
                x = np.linalg.norm(h - h.mean(axis=1, keepdims=True), axis=1)
            else:
                x = np.abs(np.log(np.linalg.det(G)))
            np.testing.assert_allclose(m.state_arrays()["wv"][:, j], 1 + 4 * x, rtol=1e-12)
    plain = law(None, trigger=trigger, emin=1e-3).bind(4, 3)
    double = law({"model": "user", "function": "2"}, trigger=trigger, emin=1e-3).bind(4, 3)
    strong = ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3)
    for a in (plain, double):
        a.begin_step(0.1)
    small = np.broadcast_to(np.diag([1.0004, 1.0, 1.0]), (4, 3, 3))  # below the trigger
    np.testing.assert_allclose(double.stress(small), plain.stress(small), rtol=1e-13)
    F = Fs[0]
    weak = plain.stress(F) - strong.stress(F)  # the first generation forms: brf on it
    np.testing.assert_allclose(double.stress(F) - strong.stress(F), 2 * weak, rtol=1e-10)
    for a in (plain, double):
        a.accept_step(F)
        a.begin_step(0.05)
    weak = plain.stress(F) - strong.stress(F)  # it breaks, still weighed by its brf
    np.testing.assert_allclose(double.stress(F) - strong.stress(F), 2 * weak, rtol=1e-10)
    assert np.abs(weak).max() > 1.0


@pytest.mark.parametrize("cls", [ReactiveViscoelastic, UncoupledReactiveViscoelastic])
def test_the_step_potential_with_recruitment_matches_finite_differences(cls):
    """In a step the forming bonds' brf is held at the lagged strain, so the step is a
    potential: its stress and tangent against central differences of the energy and stress,
    with generations of different weights."""
    rng = np.random.default_rng(5)
    m = law({"model": "power", "mu0": 1.0, "mu1": 6.0, "alpha": 1.0}, cls).bind(5, 3)
    for h in (0.05, 0.1):
        m.begin_step(h)
        m.accept_step(np.eye(3) + 0.1 * rng.standard_normal((5, 3, 3)))
    wv = m.state_arrays()["wv"]
    assert np.ptp(wv) > 0.1
    m.begin_step(0.04)
    m.relag(np.eye(3) + 0.1 * rng.standard_normal((5, 3, 3)), 0.0)  # a lag of its own
    F = np.eye(3) + 0.12 * rng.standard_normal((5, 3, 3))
    r = m.evaluate(F, 2)
    P_fd, A_fd = pointwise_difference(m, F)
    assert np.abs(P_fd - r.stress).max() < 1e-6 * np.abs(r.stress).max()
    assert np.abs(A_fd - r.tangent).max() < 1e-6 * np.abs(r.tangent).max()


def _pulled_cube(monkeypatch=None, relags=None):
    """A unit hex cube, symmetry planes held, its +x face pulled by a traction ramped over 4
    steps, with a steep recruitment: (traction per step, the stress P_xx of the accepted
    state at each step)."""
    if relags is not None:
        import tissuesim.time.lags as lags

        monkeypatch.setattr(lags, "MATERIAL_RELAGS", relags)
    rec = {"model": "user", "function": "1 + 30*X"}
    m = law(rec, trigger=0)
    mesh = ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="hex")
    sim = ts.Simulation(mesh, m, integrator="quasistatic", time_step=0.1)
    for axis in range(3):
        sim.add_dirichlet(ts.select.vertices_on_plane(mesh, axis=axis, value=0.0),
                          components=(axis,), name=f"sym{axis}")  # fmt: skip
    right = mesh.facet_sets["xmax"]
    sim.add_traction(right, lambda X, t: np.outer(np.ones(len(X)), [1500.0 * t, 0.0, 0.0]))
    traction, stress = [], []
    for _ in range(4):
        sim.step()
        body = sim.bodies["body"].model
        F = body.kinematics.deformation_gradients(sim.state.x[sim.system.config_slices[0]])
        stress.append(body.material.evaluate(F, 1).stress[:, 0, 0])
        traction.append(1500.0 * sim.time)
    return np.array(traction), np.array(stress)


def test_a_step_settles_at_febios_fixed_point(monkeypatch):
    """FEBio sets the forming bonds' brf at each iterate, so its converged state balances the
    load with brf(X) of that state. Re-lagged to its fixed point, every step's traction is the
    accepted state's stress (the new generation then weighs brf(X) of it) to 1e-7; held at the
    last step's strain (no re-lag) the step is refused (off by 1.1 there)."""
    traction, stress = _pulled_cube()
    assert np.ptp(stress, axis=1).max() < 1e-8 * traction.max()  # one homogeneous state
    np.testing.assert_allclose(stress[:, 0], traction, rtol=1e-7)
    # with no re-lag the solve at the last step's strain is not FEBio's: refused, not taken
    from tissuesim.errors import ConvergenceError

    with pytest.raises(ConvergenceError, match="lagged weight did not settle"):
        _pulled_cube(monkeypatch, relags=0)


def test_the_state_and_errors():
    m = law({"model": "power", "mu1": 2.0}).bind(2, 3)
    m.begin_step(0.1)
    m.accept_step(np.broadcast_to(np.diag([1.1, 1.0, 1.0]), (2, 3, 3)).copy())
    old = {k: v for k, v in m.state_arrays().items() if k not in gen.RECRUITMENT_KEYS}
    m.set_state_arrays(old)  # a checkpoint from before recruitment: every weight 1
    assert np.all(m.state_arrays()["wv"][:, 0] == 1.0)
    built = make_material("reactive_viscoelastic", elastic={"model": "neo_hookean",
                          "youngs_modulus": 1e3, "poisson_ratio": 0.3},
                          bond={"model": "neo_hookean", "youngs_modulus": 500.0,
                                "poisson_ratio": 0.2}, relaxation=EXP,
                          recruitment={"model": "exponential", "mu1": 0.5})  # fmt: skip
    assert built.recruitment.kind == "exponential"
    for bad, message in [
        ({"model": "sigmoid"}, "is not one tissuesim has"),
        ({"model": "power", "beta": 1}, "takes alpha"),
        ({"model": "quintic", "mumin": 0.5, "mumax": 0.2}, "mumax > mumin"),
        ({"model": "user"}, "needs function"),
        ({"model": "user", "function": "1 + t"}, "its variable is X"),
        ({"model": "gamma", "alpha": 0}, "alpha must be > 0"),
        ("power", "as a table"),
    ]:
        with pytest.raises(MaterialError, match=message):
            law(bad)


def _febio_model(tmp_path, recruitment: str):
    from pathlib import Path

    from tissuesim.scene.loader import load_febio

    source = Path(__file__).parents[1] / "febio" / "models" / "reactive_viscoelastic_relaxation.feb"
    text = source.read_text().replace("</relaxation>", "</relaxation>" + recruitment)
    (tmp_path / "m.feb").write_text(text)
    return load_febio(tmp_path / "m.feb").simulation


def test_febios_recruitment_is_read(tmp_path):
    """FEBio's <recruitment type="recruitment user"> with a point curve of X (LINEAR, the
    curve held constant beyond its ends) and a named law; the run pulls harder with it."""
    curve = ('<recruitment type="recruitment user"><function type="point"><interpolate>LINEAR'
             "</interpolate><points><point>0,1</point><point>0.1,2</point></points></function>"
             "</recruitment>")  # fmt: skip
    sim = _febio_model(tmp_path, curve)
    rec = next(iter(sim.bodies.values())).model.material.recruitment
    np.testing.assert_allclose(rec(np.array([0.0, 0.05, 0.1, 0.4])), [1.0, 1.5, 2.0, 2.0])
    pulled = [abs(sim.step().extra["forces"]["pull"][0]) for _ in range(3)]
    plain = _febio_model(tmp_path, "")
    assert next(iter(plain.bodies.values())).model.material.recruitment is None
    base = [abs(plain.step().extra["forces"]["pull"][0]) for _ in range(3)]
    assert pulled[-1] > base[-1] * 1.01
    power = _febio_model(tmp_path, '<recruitment type="recruitment power"><mu1>2</mu1>'
                                   "<alpha>1</alpha></recruitment>")  # fmt: skip
    rec = next(iter(power.bodies.values())).model.material.recruitment
    assert rec.kind == "power" and rec(np.array([0.5]))[0] == pytest.approx(2.0)
