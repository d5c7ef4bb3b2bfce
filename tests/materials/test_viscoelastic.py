"""Visco-elasticity as a Prony series (materials/viscoelastic.py): relaxation under a held
stretch and a constant-rate stretch against the series' closed form, the stored energy through
relaxation, finite differences of the step's incremental potential, halved steps, checkpoints,
and the parameters' one-line errors."""

import numpy as np
import pytest
from scipy.optimize import brentq
from stress_differences import pointwise_difference

import tissuesim as ts
from tissuesim.errors import InputError, MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.viscoelastic import UncoupledViscoelastic, Viscoelastic
from tissuesim.model import Model

G, TAU = [0.6, 0.3], [0.05, 0.4]
MU, LAM = 400.0, 600.0
PRONY = list(zip(G, TAU, strict=True))


def neo(mu=MU, lam=LAM):
    return ts.NeoHookean(shear_modulus=mu, lame_lambda=lam)


def uniaxial_block(material, stretch, h, integrator="quasistatic"):
    """A unit Q1 cube on three symmetry planes, its x = 1 face pulled to ``stretch(t)``: a
    homogeneous uniaxial stress state; returns the simulation and the pulled set's name."""
    mesh = ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="hex")
    sim = ts.Simulation(mesh, material, integrator=integrator, time_step=h)
    for axis in range(3):
        sim.add_dirichlet(ts.select.vertices_on_plane(mesh, axis=axis, value=0.0),
                          components=(axis,), name=f"sym{axis}")  # fmt: skip
    right = ts.select.vertices_on_plane(mesh, axis=0, value=1.0)

    def pull(X, t):
        u = np.zeros_like(X)
        u[:, 0] = stretch(t) - 1.0
        return u

    sim.add_dirichlet(right, pull, components=(0,), name="pull")
    return sim


def neo_uniaxial_pk2(lam1, mu=MU, lam=LAM):
    """S_11 of the compressible neo-Hookean (mu/2 (I1 - 3) - mu ln J + lam/2 ln^2 J) in
    uniaxial stress: P = mu F + (lam ln J - mu) F^-T, the lateral stretch l from P_22 = 0:
    mu l + (lam ln(lam1 l^2) - mu) / l = 0; S_11 = P_11 / lam1."""
    l2 = brentq(lambda l: mu * l + (lam * np.log(lam1 * l * l) - mu) / l, 0.2, 2.0, xtol=1e-15)
    J = lam1 * l2 * l2
    return (mu * lam1 + (lam * np.log(J) - mu) / lam1) / lam1


def test_relaxation_under_a_held_stretch_is_the_prony_closed_form():
    h, lam1, steps = 0.01, 1.2, 60
    sim = uniaxial_block(Viscoelastic(neo(), g=G, tau=TAU), lambda t: lam1, h)
    S_inf = neo_uniaxial_pk2(lam1)
    worst, stored = 0.0, []
    for n in range(1, steps + 1):
        record = sim.step()
        t = n * h
        # Se ramps linearly over the first step (t_r = h) and is held: the convolution gives
        # S(t) = Se [g0 + sum g_i tau_i/t_r (1 - exp(-t_r/tau_i)) exp(-(t - t_r)/tau_i)]
        ref = S_inf * (1.0 + sum(g * tau / h * (1 - np.exp(-h / tau)) * np.exp(-(t - h) / tau)
                                 for g, tau in PRONY))  # fmt: skip
        S11 = record.extra["forces"]["pull"][0] / lam1  # P_11 A0 / lam1, A0 = 1
        worst = max(worst, abs(S11 - ref) / abs(ref))
        stored.append(record.energies["elastic"])
    assert worst < 1e-4
    # the stored energy decreases through the relaxation, towards the elastic law's
    assert np.all(np.diff(stored) < 0)
    x = sim.state.x.reshape(-1, 3)
    psi_inf = neo().energy_density(sim.bodies["body"].model.kinematics.deformation_gradients(
        x.ravel()))  # fmt: skip
    assert stored[-1] > psi_inf.mean() and stored[-1] < stored[0]


def test_constant_rate_stretch_is_the_prony_closed_form():
    """St Venant-Kirchhoff in uniaxial stress: S_11 = Y E_11 with Y = mu (3 lam + 2 mu) /
    (lam + mu); at a constant Green-strain rate r the series gives
    S_11(t) = Y r [g0 t + sum_i g_i tau_i (1 - exp(-t/tau_i))] exactly."""
    h, r, steps = 0.01, 0.5, 40
    law = ts.StVenantKirchhoff(shear_modulus=MU, lame_lambda=LAM)
    sim = uniaxial_block(Viscoelastic(law, g=G, tau=TAU), lambda t: np.sqrt(1 + 2 * r * t), h)
    Y = MU * (3 * LAM + 2 * MU) / (LAM + MU)
    worst = 0.0
    for n in range(1, steps + 1):
        record = sim.step()
        t = n * h
        ref = Y * r * (t + sum(g * tau * (1 - np.exp(-t / tau)) for g, tau in PRONY))
        S11 = record.extra["forces"]["pull"][0] / np.sqrt(1 + 2 * r * t)
        worst = max(worst, abs(S11 - ref) / abs(ref))
    assert worst < 1e-4


@pytest.mark.parametrize("kind", ["coupled", "uncoupled"])
def test_incremental_potential_matches_finite_differences(kind):
    rng = np.random.default_rng(3)
    if kind == "coupled":
        law = Viscoelastic(neo(), g=G, tau=TAU, g0=0.8)
    else:
        law = UncoupledViscoelastic(ts.MooneyRivlin(c1=200.0, c2=50.0, k=5e3), g=G, tau=TAU)
    law = law.bind(5, 3)
    for h in (0.02, 0.07):  # some history first
        law.begin_step(h)
        law.accept_step(np.eye(3) + 0.15 * rng.standard_normal((5, 3, 3)))
    law.begin_step(0.03)
    F = np.eye(3) + 0.15 * rng.standard_normal((5, 3, 3))
    r = law.evaluate(F, 2)
    P_fd, A_fd = pointwise_difference(law, F)
    assert np.abs(P_fd - r.stress).max() < 1e-6 * np.abs(r.stress).max()
    assert np.abs(A_fd - r.tangent).max() < 1e-6 * np.abs(r.tangent).max()
    # the step's stress is FEBio's: (g0 + sum g gamma) Se + sum g (e H - gamma Se_n) pushed on
    A = r.tangent.reshape(5, 9, 9)
    assert np.allclose(A, np.swapaxes(A, 1, 2), atol=1e-9 * np.abs(A).max())


def test_uncoupled_relaxes_the_deviatoric_part_only():
    """A held F: S - S_bulk(F) = S_dev(F) G_ramp(t) and the bulk part never relaxes."""
    base = ts.MooneyRivlin(c1=200.0, c2=50.0, k=5e3)
    law = UncoupledViscoelastic(base, g=G, tau=TAU).bind(1, 3)
    F = np.array([[[1.2, 0.1, 0.0], [0.0, 0.9, 0.05], [0.0, 0.0, 0.95]]])
    J = np.linalg.det(F[0])
    bulk = np.linalg.solve(F[0], 5e3 * np.log(J) * np.linalg.inv(F[0]).T)  # k ln J C^-1
    S_dev = np.linalg.solve(F[0], base.stress(F)[0]) - bulk
    h = 0.01
    for n in range(1, 30):
        law.begin_step(h)
        law.accept_step(F)
        t = n * h
        S = np.linalg.solve(F[0], law.stress(F)[0])  # between steps: the current stress
        ramp = 1.0 + sum(g * tau / h * (1 - np.exp(-h / tau)) * np.exp(-(t - h) / tau)
                         for g, tau in PRONY)  # fmt: skip
        assert np.allclose(S - bulk, S_dev * ramp, rtol=1e-10, atol=1e-9)
    with pytest.raises(MaterialError, match="needs an uncoupled elastic law"):
        UncoupledViscoelastic(neo(), g=G, tau=TAU)


def test_halved_steps_do_not_corrupt_the_history(monkeypatch):
    """A step rejected once and redone as two halves gives the state of two steps of h/2."""
    import tissuesim.time.steps as steps

    def run(h, n, reject_first):
        sim = uniaxial_block(Viscoelastic(neo(), g=G, tau=TAU), lambda t: 1 + 2 * t, h)
        real, calls = steps.implicit_step, {"n": 0}

        def flaky(system, state, dt, *a, **k):
            calls["n"] += 1
            if reject_first and calls["n"] == 1:
                real(system, state, dt, *a, **k)  # it ran (and converged), then is rejected
                return steps.StepOutcome(None, False, [], "rejected by the test")
            return real(system, state, dt, *a, **k)

        monkeypatch.setattr(steps, "implicit_step", flaky)
        for _ in range(n):
            sim.step()
        return sim

    halved, small = run(0.04, 1, True), run(0.02, 2, False)
    a, b = (s.bodies["body"].model.material for s in (halved, small))
    assert halved.history[0].substeps == 2
    np.testing.assert_allclose(a.history, b.history, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(halved.state.x, small.state.x, rtol=1e-12, atol=1e-12)


def test_checkpoint_carries_the_history(tmp_path):
    def build():
        return uniaxial_block(Viscoelastic(neo(), g=G, tau=TAU), lambda t: 1 + 2 * t, 0.02)

    whole = build()
    for _ in range(6):
        whole.step()
    first = build()
    for _ in range(3):
        first.step()
    first.save(tmp_path / "c.npz")
    second = build().load(tmp_path / "c.npz")
    for _ in range(3):
        second.step()
    a, b = (s.bodies["body"].model.material for s in (whole, second))
    np.testing.assert_array_equal(a.history, b.history)
    np.testing.assert_array_equal(whole.state.x, second.state.x)


def test_by_name_and_one_line_errors():
    law = make_material(
        "Viscoelastic", elastic={"model": "neo_hookean", "youngs_modulus": 1e3,
                                 "poisson_ratio": 0.3}, g=[0.5], tau=[0.1])  # fmt: skip
    assert isinstance(law, Viscoelastic) and law.g == [0.5] and law.tau == [0.1]
    law = make_material("uncoupled viscoelastic", elastic={"model": "ogden", "c": [1e3],
                        "m": [4.0], "k": 1e5}, g=0.3, tau=2.0)  # fmt: skip
    assert isinstance(law, UncoupledViscoelastic)
    bad = [
        ({"g": [0.5], "tau": [0.1, 0.2]}, "same length"),
        ({"g": [-0.5], "tau": [0.1]}, r"g\[0\] must be >= 0"),
        ({"g": [0.5], "tau": [0.0]}, r"tau\[0\] must be > 0"),
        ({"g": [0.5]}, "needs g .* and tau"),
        ({"g": [0.5], "tau": [1.0], "beta": 1}, "unknown parameter 'beta'"),
        ({"g": [0.5], "tau": [1.0], "g0": 0}, "g0 must be > 0"),
    ]
    for params, message in bad:
        with pytest.raises(MaterialError, match=message) as info:
            make_material("viscoelastic", elastic={"model": "neo_hookean", "youngs_modulus": 1e3,
                          "poisson_ratio": 0.3}, **params)  # fmt: skip
        assert "\n" not in str(info.value)
    with pytest.raises(MaterialError, match="elastic needs its model"):
        make_material("viscoelastic", elastic={"c1": 1}, g=[0.5], tau=[1.0])
    with pytest.raises(MaterialError, match="elastic: unknown material model"):
        make_material("viscoelastic", elastic={"model": "rubber"}, g=[0.5], tau=[1.0])
    with pytest.raises(MaterialError, match="needs an elastic law"):
        Viscoelastic(None, g=[0.5], tau=[1.0])
    with pytest.raises(InputError, match="mean_dilatation"):
        Model(ts.box(divisions=(1, 1, 1)), Viscoelastic(neo(), g=G, tau=TAU), np.ones(6),
                 formulation="mean_dilatation")  # fmt: skip


def test_a_scene_takes_it_by_name(tmp_path):
    from tissuesim.scene.loader import load_scene

    scene = tmp_path / "v.toml"
    scene.write_text(
        """
[mesh]
generator = "box"
divisions = [1, 1, 1]
element = "hex"

[material]
model = "viscoelastic"
g = [0.6, 0.3]
tau = [0.05, 0.4]
elastic = { model = "neo_hookean", shear_modulus = 400.0, lame_lambda = 600.0 }

[simulation]
integrator = "quasistatic"
time_step = 0.01
"""
    )
    sim = load_scene(scene).simulation
    assert isinstance(sim.bodies["body"].model.material, Viscoelastic)
    assert sim.bodies["body"].model.material.bound
