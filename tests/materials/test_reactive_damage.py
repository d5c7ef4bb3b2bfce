"""FEBio's elastic damage (materials/reactive/damage.py): finite differences of the step's
potential with a history (alone and in a solid mixture), the CDFs and criteria against their
formulas, the softening curve's closed form (verification/damage.py), a FEBio model of it,
a rejected attempt and a checkpoint that keep the history, and the one-line errors."""

from pathlib import Path

import numpy as np
import pytest
from scipy.special import erf
from stress_differences import pointwise_difference

import tissuesim as ts
from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.reactive.damage import ElasticDamage, UncoupledElasticDamage
from tissuesim.materials.reactive.damage_functions import DamageCDF, DamageCriterion
from tissuesim.materials.soft_tissue._hyperelastic import bulk_response
from tissuesim.scene.loader import load_febio
from tissuesim.verification import damage as closed

MODELS = Path(__file__).parents[1] / "febio" / "models"
WEIBULL = {"model": "weibull", "alpha": 2.0, "mu": 0.1, "Dmax": 0.9}


def coupled() -> ElasticDamage:
    neo = ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3)
    return ElasticDamage(neo, damage={"model": "weibull", "alpha": 2.0, "mu": 150.0},
                         criterion="von_mises_stress")  # fmt: skip


def uncoupled() -> UncoupledElasticDamage:
    mr = ts.MooneyRivlin(c1=200.0, c2=50.0, k=5e3)
    return UncoupledElasticDamage(mr, damage={"model": "log_normal", "mu": 0.2, "sigma": 0.5},
                                  criterion="DC max normal Lagrange strain", k=3e3)  # fmt: skip


def mixture():
    fibre = {"model": "fiber_pow_linear", "E": 500.0, "lam0": 1.05, "beta": 2.5,
             "fiber": [0.6, 0.8, 0.0]}  # fmt: skip
    return make_material("solid mixture", components=[
        {"model": "neo_hookean", "youngs_modulus": 1e3, "poisson_ratio": 0.3},
        {"model": "elastic damage", "elastic": fibre, "damage": WEIBULL,
         "criterion": "max_normal_lagrange_strain"}])  # fmt: skip


def fd_check(law, rng) -> None:
    F = np.eye(3) + 0.12 * rng.standard_normal((5, 3, 3))
    r = law.evaluate(F, 2)
    P_fd, A_fd = pointwise_difference(law, F)
    assert np.abs(P_fd - r.stress).max() < 1e-6 * np.abs(r.stress).max()
    assert np.abs(A_fd - r.tangent).max() < 1e-6 * np.abs(r.tangent).max()
    A = r.tangent.reshape(5, 9, 9)
    assert np.allclose(A, np.swapaxes(A, 1, 2), atol=1e-9 * np.abs(A).max())


@pytest.mark.parametrize("build", [coupled, uncoupled, mixture])
def test_step_potential_matches_finite_differences_with_a_history(build):
    rng = np.random.default_rng(4)
    law = build().bind(5, 3)
    for _ in range(2):  # some damage first
        law.begin_step(0.1)
        law.accept_step(np.eye(3) + 0.25 * rng.standard_normal((5, 3, 3)))
    states = law.state_arrays()
    assert any(np.all(v > 0.0) for v in states.values())  # the history is not trivial
    law.begin_step(0.1)
    fd_check(law, rng)


def test_the_step_is_the_undamaged_law_scaled_by_the_accepted_damage():
    law, base = coupled().bind(3, 3), coupled().elastic
    F = np.eye(3) + np.array([[0.3, 0.05, 0], [0, -0.1, 0], [0.02, 0, 0.1]])
    F = np.repeat(F[None], 3, axis=0)
    law.begin_step(0.1)
    np.testing.assert_array_equal(law.stress(F), base.stress(F))  # no damage yet
    law.accept_step(F)
    s = F[0] @ base.stress(F)[0].T / np.linalg.det(F[0])
    dev = s - np.trace(s) / 3 * np.eye(3)
    vm = np.sqrt(1.5 * np.sum(dev * dev))
    D = 1.0 - np.exp(-((vm / 150.0) ** 2))
    assert law.damage == pytest.approx(np.full(3, D), rel=1e-12) and 0.05 < D < 0.95
    law.begin_step(0.1)
    np.testing.assert_allclose(law.stress(F), (1 - D) * base.stress(F), rtol=1e-12)
    law.accept_step(np.repeat(np.eye(3)[None], 3, axis=0))  # unloaded: D stays
    assert law.damage == pytest.approx(np.full(3, D), rel=1e-12)
    # uncoupled: the wrapper's own bulk term is not damaged, the elastic law's k unused
    u = uncoupled().bind(3, 3)
    u.accept_step(F)
    mr = ts.MooneyRivlin(c1=200.0, c2=50.0, k=5e3)
    bulk = [bulk_response("t", "log", k, F, 1).stress for k in (5e3, 3e3)]
    assert 0.05 < u.damage[0] < 0.95
    expect = (1 - u.damage[0]) * (mr.stress(F) - bulk[0]) + bulk[1]
    np.testing.assert_allclose(u.stress(F), expect, rtol=1e-12, atol=1e-9)


def test_cdfs_and_criteria_are_febios_formulas():
    X = np.array([-0.1, 0.0, 0.05, 0.3, 0.6, 2.0])
    ln = DamageCDF("t", {"model": "CDF log-normal", "mu": 0.3, "sigma": 0.4, "Dmax": 0.5})
    with np.errstate(divide="ignore"):
        ref = 0.25 * (1 + erf(np.log(np.where(X > 0, X, 1e-300) / 0.3) / (0.4 * np.sqrt(2))))
    np.testing.assert_allclose(ln(X), np.where(X > 0, ref, 0.0), rtol=1e-10, atol=1e-300)
    simo = DamageCDF("t", {"model": "simo", "a": 0.2, "b": 0.3})
    small = simo(np.array([1e-13, 2e-12]))  # both branches meet: (1 - b) X / (2a) near 0
    assert small[0] == pytest.approx(0.7 * 1e-13 / 0.4)
    assert small[1] == pytest.approx(0.7 * 2e-12 / 0.4, rel=1e-3)
    assert simo(np.array([0.5]))[0] == pytest.approx(0.7 - 0.7 * (1 - np.exp(-2.5)) * 0.4)
    q = DamageCDF("t", {"model": "quintic", "mumin": 0.1, "mumax": 0.3})
    np.testing.assert_allclose(q(np.array([0.05, 0.2, 0.35])), [0.0, 0.5, 1.0])
    st = DamageCDF("t", {"model": "step", "mu": 0.3})
    np.testing.assert_array_equal(st(X), (X > 0.3).astype(float))
    g1 = DamageCDF("t", {"model": "gamma", "alpha": 1.0, "mu": 0.5})  # gamma(1): exponential
    np.testing.assert_allclose(g1(X), np.where(X > 0, 1 - np.exp(-np.maximum(X, 0) / 0.5), 0))
    w = DamageCDF("t", {"model": "weibull", "alpha": 3.0, "mu": 0.2, "ploc": 0.1})
    np.testing.assert_allclose(w(X), np.where(X > 0.1, 1 - np.exp(-(((X - 0.1) / 0.2) ** 3)), 0))
    # criteria at F = diag(l1, l2, l3) with a known Cauchy stress
    F = np.diag([1.3, 0.9, 1.1])[None]
    P = np.diag([5.0, -2.0, 1.0])[None] @ np.linalg.inv(F[0]).T * np.linalg.det(F)  # sigma diag
    crit = {name: DamageCriterion("t", name)(F, np.array([0.8]), P, 2.0)[0]
            for name in ("max_normal_lagrange_strain", "von_mises_stress", "max_shear_stress",
                         "max_normal_stress", "simo", "specific_strain_energy",
                         "octahedral_shear_strain", "octahedral_natural_strain")}  # fmt: skip
    E = 0.5 * (np.array([1.3, 0.9, 1.1]) ** 2 - 1)
    h = np.log([1.3, 0.9, 1.1])
    assert crit["max_normal_lagrange_strain"] == pytest.approx(E.max())
    assert crit["von_mises_stress"] == pytest.approx(np.sqrt(((7) ** 2 + 3**2 + 4**2) / 2))
    assert crit["max_shear_stress"] == pytest.approx(3.5)
    assert crit["max_normal_stress"] == pytest.approx(5.0)
    assert crit["simo"] == pytest.approx(np.sqrt(1.6))
    assert crit["specific_strain_energy"] == pytest.approx(0.4)
    assert crit["octahedral_shear_strain"] == pytest.approx(
        np.sqrt(2 / 3 * np.sum((E - E.mean()) ** 2))
    )
    assert crit["octahedral_natural_strain"] == pytest.approx(
        np.sqrt(2 / 3 * np.sum((h - h.mean()) ** 2))
    )


def test_softening_curve_is_the_closed_form():
    """Load, unload, reload: the force is (1 - D(max X before the step)) P11(l) to round-off
    (D frozen over a step), FEBio's (1 - D(max X up to the step)) P11(l) after a held step;
    the one-step lag costs up to 9% of the force on the steep branch at 0.01 per step."""
    path, got = closed.softening()
    lagged, febio = closed.closed_form(path, True), closed.closed_form(path, False)
    np.testing.assert_allclose(got, lagged, rtol=1e-9)
    assert got[-1] == pytest.approx(febio[-1], rel=1e-9)
    gap = np.abs(got - febio).max() / np.abs(febio).max()
    assert 0.01 < gap < 0.1  # the lag is real, and O(h)
    unloading = slice(30, 50)  # damage does not heal: the unloading branch is elastic x (1 - D)
    Dpeak = closed.damage(np.array([0.5 * (1.3**2 - 1)]))[0]
    l = path[unloading]
    np.testing.assert_allclose(got[unloading], (1 - Dpeak) * closed.MU * (l - 1 / l), rtol=1e-9)
    assert all(c.passed for c in closed.checks())


def test_febio_model_follows_the_closed_form():
    scene = load_febio(MODELS / "elastic_damage_softening.feb")
    sim = scene.simulation
    u = np.concatenate([np.linspace(0.03, 0.3, 10), np.linspace(0.28, 0.1, 10), [0.1]])
    forces = np.array([abs(sim.step().extra["forces"]["pull"][0]) for _ in u])
    lagged = closed.closed_form(1.0 + u, True) * 200.0 / 2 / closed.MU  # mu = E / 2 (v = 0)
    np.testing.assert_allclose(forces, lagged, rtol=1e-8)
    febio = closed.closed_form(1.0 + u, False) * 200.0 / 2 / closed.MU
    assert forces[-1] == pytest.approx(febio[-1], rel=1e-8)
    assert forces[5] > 1.2 * febio[5]  # on the loading branch D lags a step behind FEBio's


def uniaxial(law, h=0.1):
    mesh = ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="hex")
    sim = ts.Simulation(mesh, law, integrator="quasistatic", time_step=h)
    for axis in range(3):
        sim.add_dirichlet(ts.select.vertices_on_plane(mesh, axis=axis, value=0.0),
                          components=(axis,), name=f"sym{axis}")  # fmt: skip
    right = ts.select.vertices_on_plane(mesh, axis=0, value=1.0)
    sim.add_dirichlet(right, lambda X, t: np.outer(np.ones(len(X)), [0.4 * t, 0, 0]),
                      components=(0,), name="pull")  # fmt: skip
    return sim


def test_checkpoint_and_rejected_attempts_keep_the_history(tmp_path, monkeypatch):
    whole = uniaxial(mixture())
    for _ in range(6):
        whole.step()
    first = uniaxial(mixture())
    for _ in range(3):
        first.step()
    first.save(tmp_path / "c.npz")
    second = uniaxial(mixture()).load(tmp_path / "c.npz")
    for _ in range(3):
        second.step()
    a, b = (s.bodies["body"].model.material for s in (whole, second))
    assert np.all(a.state_arrays()["c1_xmax"] > 0.05)
    np.testing.assert_array_equal(a.state_arrays()["c1_xmax"], b.state_arrays()["c1_xmax"])
    np.testing.assert_array_equal(whole.state.x, second.state.x)

    import tissuesim.time.steps as steps

    real, calls = steps.implicit_step, {"n": 0}

    def flaky(system, state, dt, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 1:  # converged, then rejected: the history must not move
            real(system, state, dt, *args, **kwargs)
            return steps.StepOutcome(None, False, [], "rejected by the test")
        return real(system, state, dt, *args, **kwargs)

    monkeypatch.setattr(steps, "implicit_step", flaky)
    halved = uniaxial(mixture(), h=0.2)
    halved.step()
    monkeypatch.setattr(steps, "implicit_step", real)
    small = uniaxial(mixture(), h=0.1)
    small.step()
    small.step()
    assert halved.history[0].substeps == 2
    c, d = (s.bodies["body"].model.material for s in (halved, small))
    np.testing.assert_allclose(c.state_arrays()["c1_xmax"], d.state_arrays()["c1_xmax"],
                               rtol=1e-10)  # fmt: skip


def test_by_name_and_one_line_errors():
    law = make_material("elastic damage", elastic={"model": "neo_hookean", "youngs_modulus": 1e3,
                        "poisson_ratio": 0.3}, damage=WEIBULL)  # fmt: skip
    assert isinstance(law, ElasticDamage) and law.criterion.kind == "max_normal_lagrange_strain"
    bad = [
        ({"damage": {"model": "cauchy"}}, "not a damage CDF"),
        ({"damage": {**WEIBULL, "Dmax": 1.5}}, "Dmax must be in"),
        ({"damage": {**WEIBULL, "nu": 1.0}}, "damage weibull takes"),
        ({"damage": WEIBULL, "criterion": "tresca"}, "not a damage criterion"),
        ({"damage": None}, "needs damage as a table"),
        ({"damage": {"model": "simo", "b": 0.2}}, "damage simo needs a"),
    ]
    neo = ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3)
    for kwargs, message in bad:
        with pytest.raises(MaterialError, match=message):
            ElasticDamage(neo, **kwargs)
    with pytest.raises(MaterialError, match="needs an uncoupled elastic law"):
        UncoupledElasticDamage(neo, damage=WEIBULL)
    with pytest.raises(MaterialError, match="needs an elastic law"):
        ElasticDamage(coupled(), damage=WEIBULL)
