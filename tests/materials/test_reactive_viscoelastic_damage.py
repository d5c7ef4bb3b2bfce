"""FEBio's viscoelastic damage (materials/reactive/viscoelastic_damage.py) and reactive
viscoelastic damage (read as a reactive viscoelastic law on an elastic damage): finite
differences with a history, the damaged Prony relaxation's closed form through a FEBio model,
its checkpoint state, and FEBio's two damaged reactive forms read alike."""

from pathlib import Path

import numpy as np
import pytest
from stress_differences import pointwise_difference

import tissuesim as ts
from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.reactive.damage import ElasticDamage
from tissuesim.materials.reactive.viscoelastic_damage import ViscoelasticDamage
from tissuesim.scene.loader import load_febio

MODELS = Path(__file__).parents[1] / "febio" / "models"
QUINTIC = {"model": "quintic", "mumin": 0.1, "mumax": 0.4, "Dmax": 0.6}


def law() -> ViscoelasticDamage:
    damaged = ElasticDamage(ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
                            damage=QUINTIC, criterion="max_normal_lagrange_strain")  # fmt: skip
    return ViscoelasticDamage(damaged, g=[0.5, 0.25], tau=[0.2, 1.5])


def test_step_potential_matches_finite_differences_with_a_history():
    rng = np.random.default_rng(2)
    m = law().bind(5, 3)
    for h in (0.05, 0.1):
        m.begin_step(h)
        m.accept_step(np.eye(3) + 0.3 * rng.standard_normal((5, 3, 3)))
    assert np.all(m.state_arrays()["damage_xmax"] > 0.1)
    m.begin_step(0.04)
    F = np.eye(3) + 0.12 * rng.standard_normal((5, 3, 3))
    r = m.evaluate(F, 2)
    P_fd, A_fd = pointwise_difference(m, F)
    assert np.abs(P_fd - r.stress).max() < 1e-6 * np.abs(r.stress).max()
    assert np.abs(A_fd - r.tangent).max() < 1e-6 * np.abs(r.tangent).max()
    undamaged = ts.Viscoelastic(ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
                                g=[0.5, 0.25], tau=[0.2, 1.5]).bind(5, 3)  # fmt: skip
    undamaged.set_state_arrays({k: m.state_arrays()[k] for k in ("H", "Se")})
    undamaged.begin_step(0.04)
    D = m.damaged.damage
    np.testing.assert_allclose(r.stress, (1 - D)[:, None, None] * undamaged.stress(F), rtol=1e-12)


def test_febio_model_is_the_damaged_prony_closed_form():
    """A unit cube (E = 1000, v = 0) stretched to 1.2 in the first step and held: FEBio's
    Prony pull lambda mu (1 - lambda^-2) (1 + sum g_i gamma_i e_i^(n-1)) times 1 - D, D of the
    quintic CDF at E11 = 0.22 from the second step (frozen over the first, as tissuesim's)."""
    sim = load_febio(MODELS / "viscoelastic_damage_relaxation.feb").simulation
    stretch, mu, h = 1.2, 500.0, 0.1
    g, tau = np.array([0.5, 0.25]), np.array([0.2, 1.5])
    e = np.exp(-h / tau)
    gamma = (1 - e) / (h / tau)
    x = (0.5 * (stretch**2 - 1) - 0.1) / 0.3
    D = 0.6 * x**3 * (10 - 15 * x + 6 * x * x)
    for n in range(1, 6):
        force = abs(sim.step().extra["forces"]["pull"][0])
        prony = stretch * mu * (1 - stretch**-2) * (1.0 + np.sum(g * gamma * e ** (n - 1)))
        assert force == pytest.approx(prony * (1.0 if n == 1 else 1 - D), rel=1e-9)
    material = sim.bodies["body"].model.material
    assert set(material.state_arrays()) == {"H", "Se", "damage_xmax"}


def test_febios_reactive_viscoelastic_damage_reads_as_a_damaged_strong_bond(tmp_path):
    """FEBio's "reactive viscoelastic damage" ((1 - D) on the whole law) and a "reactive
    viscoelastic" whose <elastic> is an "elastic damage" ((1 - D) on the strong bonds and, by
    FEBio's Damage(), on the weak ones) are one law (FEBio's ma67 and ma68 share their norm)."""
    base = (MODELS / "reactive_viscoelastic_relaxation.feb").read_text()
    damage = ('<damage type="CDF Weibull"><alpha>2</alpha><mu>30</mu></damage>'
              '<criterion type="DC von Mises stress"/>')  # fmt: skip
    start, end = base.index("<elastic type"), base.index("</elastic>") + len("</elastic>")
    elastic = base[start:end]
    a = base.replace(elastic, f'<elastic type="elastic damage">{elastic}{damage}</elastic>')
    start, end = base.index('<material id="1"'), base.index("</material>")
    inner = base[start:end].replace('<material id="1" name="tissue"', "<viscoelastic")
    inner = inner.replace("<density>1000</density>", "")
    b = base[:start] + ('<material id="1" name="tissue" type="reactive viscoelastic damage">'
                        f"{inner}</viscoelastic>{damage}") + base[end:]  # fmt: skip
    forces = []
    for name, text in (("a", a), ("b", b)):
        (tmp_path / f"{name}.feb").write_text(text)
        sim = load_febio(tmp_path / f"{name}.feb").simulation
        forces.append([abs(sim.step().extra["forces"]["pull"][0]) for _ in range(6)])
    np.testing.assert_array_equal(forces[0], forces[1])
    plain = load_febio(MODELS / "reactive_viscoelastic_relaxation.feb").simulation
    undamaged = [abs(plain.step().extra["forces"]["pull"][0]) for _ in range(6)]
    assert forces[0][-1] < 0.9 * undamaged[-1]  # the damage is there


def test_by_name_and_errors():
    m = make_material("viscoelastic_damage", elastic={"model": "elastic_damage", "elastic": {
        "model": "neo_hookean", "youngs_modulus": 1e3, "poisson_ratio": 0.3}, "damage": QUINTIC},
        g=[0.5], tau=[0.2])  # fmt: skip
    assert isinstance(m, ViscoelasticDamage) and isinstance(m.damaged, ElasticDamage)
    with pytest.raises(MaterialError, match="needs elastic = an elastic_damage law"):
        ViscoelasticDamage(ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), g=[0.5],
                           tau=[0.2])  # fmt: skip


def test_checkpoint_resumes_the_damaged_history(tmp_path):
    def build():
        return load_febio(MODELS / "viscoelastic_damage_relaxation.feb").simulation

    whole = build()
    for _ in range(5):
        whole.step()
    first = build()
    for _ in range(2):
        first.step()
    first.save(tmp_path / "c.npz")
    second = build().load(tmp_path / "c.npz")
    for _ in range(3):
        second.step()
    a, b = (s.bodies["body"].model.material.state_arrays() for s in (whole, second))
    assert np.all(a["damage_xmax"] > 0.2)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])
    np.testing.assert_array_equal(whole.state.x, second.state.x)
