"""FEBio's fibre laws (fiber-exp-pow, fiber-pow-linear, coupled and uncoupled) and solid
mixtures: finite differences of stress against energy and of the tangent against stress in 2D
and 3D, the fibre slack in compression, a mixture as the sum of its parts, closed forms of a
stretch along the fibre derived by hand, per-element fibres through a mixture, the registry's
tables and the parameter errors."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import (
    FiberExpLinear,
    FiberExpLinearUncoupled,
    FiberExpPow,
    FiberExpPowUncoupled,
    FiberPowLinear,
    FiberPowLinearUncoupled,
    MooneyRivlin,
    NeoHookean,
    SolidMixture,
    UncoupledSolidMixture,
    Viscoelastic,
    make_material,
)
from tissuesim.materials.volumetric import volumetric_part
from tissuesim.mesh import box
from tissuesim.model import Model

NH = dict(youngs_modulus=1000.0, poisson_ratio=0.3)
EXP = dict(ksi=50.0, alpha=2.0, beta=2.5)
LIN = dict(E=400.0, lam0=1.08, beta=3.0)
EXPLIN = dict(c3=20.0, c4=8.0, c5=600.0, lam_max=1.06)
FIBRE = [1.0, 0.4, 0.2]

LAWS = {
    "fiber_exp_pow": lambda: FiberExpPow(**EXP, lam0=1.02, fiber=FIBRE),
    "fiber_exp_pow_alpha0_beta2": lambda: FiberExpPow(ksi=50.0, alpha=0.0, beta=2.0, fiber=FIBRE),
    "fiber_exp_pow_uncoupled": lambda: FiberExpPowUncoupled(**EXP, fiber=FIBRE),
    "fiber_exp_pow_shear": lambda: FiberExpPow(**EXP, mu=30.0, lam0=1.02, fiber=FIBRE),
    "fiber_exp_pow_uncoupled_shear": lambda: FiberExpPowUncoupled(**EXP, mu=30.0, fiber=FIBRE),
    "fiber_pow_linear": lambda: FiberPowLinear(**LIN, fiber=FIBRE),
    "fiber_pow_linear_uncoupled": lambda: FiberPowLinearUncoupled(**LIN, fiber=FIBRE),
    "fiber_exp_linear": lambda: FiberExpLinear(**EXPLIN, fiber=FIBRE),
    "fiber_exp_linear_uncoupled": lambda: FiberExpLinearUncoupled(**EXPLIN, fiber=FIBRE),
    "solid_mixture": lambda: SolidMixture(
        [NeoHookean(**NH), FiberExpPow(**EXP, fiber=FIBRE), FiberPowLinear(**LIN, fiber=[0, 1, 0])]
    ),
    "uncoupled_solid_mixture": lambda: UncoupledSolidMixture(
        [
            MooneyRivlin(c1=100.0, c2=20.0, k=1.0),
            FiberExpPowUncoupled(**EXP, fiber=FIBRE),
            FiberPowLinearUncoupled(**LIN, fiber=[0, 1, 1]),
        ],
        k=5000.0,
        pressure_model="NIKE3D",
    ),
}


@pytest.mark.parametrize("name", sorted(LAWS))
@pytest.mark.parametrize("d", [2, 3])
def test_stress_and_tangent_match_finite_differences(name, d):
    law = LAWS[name]()
    F = random_deformations(np.random.default_rng(d + 7), 12, d, 0.2)
    res = law.evaluate(F)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-6
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-6
    At = np.transpose(res.tangent, (0, 3, 4, 1, 2))
    np.testing.assert_allclose(res.tangent, At, atol=1e-12 * np.abs(At).max())


@pytest.mark.parametrize("name", sorted(LAWS))
def test_rest_state_is_stress_free(name):
    res = LAWS[name]().evaluate(np.eye(3)[None])
    assert res.energy[0] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(res.stress[0], 0.0, atol=1e-10)


@pytest.mark.parametrize("name", [n for n in LAWS if n.startswith("fiber")])
def test_a_fibre_bears_nothing_in_compression(name):
    """Shortened along the fibre (and stretched across it): no energy, stress or tangent;
    the uncoupled laws measure the isochoric stretch, so the block keeps J = 1 there."""
    law = LAWS[name]()
    a = law.fiber
    lam = np.array([0.8, 0.95, 0.999])
    Q = np.linalg.qr(np.column_stack([a, [0, 1, 0], [0, 0, 1]]))[0]
    Q *= np.sign(Q[:, 0] @ a)
    F = np.array([Q @ np.diag([s, s**-0.5, s**-0.5]) @ Q.T for s in lam])
    res = law.evaluate(F)
    assert np.all(res.energy == 0.0)
    assert np.all(res.stress == 0.0) and np.all(res.tangent == 0.0)
    stretched = law.evaluate(np.array([Q @ np.diag([1.1, 1.1**-0.5, 1.1**-0.5]) @ Q.T]))
    assert stretched.energy[0] > 0.0 and np.abs(stretched.stress).max() > 0.0


def test_a_mixture_is_the_sum_of_its_parts():
    parts = [NeoHookean(**NH), FiberExpPow(**EXP, fiber=FIBRE), FiberPowLinear(**LIN)]
    mix = SolidMixture(parts)
    F = random_deformations(np.random.default_rng(1), 10, 3, 0.2)
    res, each = mix.evaluate(F), [p.evaluate(F) for p in parts]
    for key in ("energy", "stress", "tangent"):
        total = sum(getattr(r, key) for r in each)
        np.testing.assert_allclose(getattr(res, key), total, rtol=1e-13, atol=1e-10)
    assert mix.mu == parts[0].mu and mix.lam == parts[0].lam


def test_an_uncoupled_mixture_sums_deviatoric_parts_and_its_own_bulk_term():
    """The components' k is ignored (FEBio's rule): the mixture's k gives U(J), so Mooney-Rivlin
    with that k plus the fibre is the same law."""
    fibre = FiberExpPowUncoupled(**EXP, fiber=FIBRE)
    mix = UncoupledSolidMixture([MooneyRivlin(c1=100.0, k=7.0), fibre], k=3000.0)
    ref = [MooneyRivlin(c1=100.0, k=3000.0), fibre]
    F = random_deformations(np.random.default_rng(2), 10, 3, 0.2)
    res = mix.evaluate(F)
    for key in ("energy", "stress", "tangent"):
        total = sum(getattr(r.evaluate(F), key) for r in ref)
        np.testing.assert_allclose(getattr(res, key), total, rtol=1e-12, atol=1e-9)
    assert mix.mu == 200.0 and mix.lam == pytest.approx(3000.0 - 400.0 / 3.0)
    assert volumetric_part(mix) == volumetric_part(ref[0])


def test_uniaxial_stretch_along_the_fibre_by_hand():
    """F = diag(l, t, t), fibre e1: P11 = neo-Hookean's + 2 l W'(I4), I4 = l^2, with
    W' = ksi x^(beta-1) exp(alpha x^beta), x = l^2 - lam0^2 (fiber-exp-pow); the other
    components are the neo-Hookean's alone."""
    mu, lam = NeoHookean(**NH).mu, NeoHookean(**NH).lam
    ksi, alpha, beta, lam0 = 50.0, 2.0, 2.5, 1.03
    mix = SolidMixture([NeoHookean(**NH), FiberExpPow(ksi=ksi, alpha=alpha, beta=beta, lam0=lam0)])
    for l, t in [(1.2, 0.93), (1.1, 1.0), (1.02, 0.98)]:
        P = mix.stress(np.diag([l, t, t])[None])[0]
        J = l * t * t
        x = max(l**2 - lam0**2, 0.0)
        fibre = 2.0 * l * ksi * x ** (beta - 1) * np.exp(alpha * x**beta)
        assert P[0, 0] == pytest.approx(mu * (l - 1 / l) + lam * np.log(J) / l + fibre, rel=1e-12)
        assert P[1, 1] == pytest.approx(mu * (t - 1 / t) + lam * np.log(J) / t, rel=1e-12)
        np.testing.assert_allclose(P[[0, 0, 1], [1, 2, 2]], 0.0, atol=1e-12)


def test_fiber_pow_linear_toe_and_linear_range_by_hand():
    """The fibre's nominal stress 2 l W'(l^2): 2 ksi l (l^2 - 1)^(beta - 1) in the toe and
    2 b l - E past lam0 (linear), with FEBio's ksi and b; continuous at lam0."""
    E, lam0, beta = LIN["E"], LIN["lam0"], LIN["beta"]
    law = FiberPowLinear(**LIN)
    I0 = lam0**2
    ksi = E / (4 * (beta - 1)) * I0**-1.5 * (I0 - 1) ** (2 - beta)
    b = ksi * (I0 - 1) ** (beta - 1) + E / (2 * lam0)
    for l in (1.01, 1.05, lam0 - 1e-9, lam0 + 1e-9, 1.2, 1.5):
        P = law.stress(np.diag([l, 1.0, 1.0])[None])[0, 0, 0]
        hand = 2 * ksi * l * (l**2 - 1) ** (beta - 1) if l < lam0 else 2 * b * l - E
        assert P == pytest.approx(hand, rel=1e-9)
    # the uncoupled law at J = 1 is the coupled one's I4b = I4 plus the deviatoric projection
    unc = FiberPowLinearUncoupled(**LIN)
    l = 1.2
    F = np.diag([l, l**-0.5, l**-0.5])[None]
    Wp = b - E / (2 * l)
    P = unc.stress(F)[0]
    assert P[0, 0] == pytest.approx(4.0 / 3.0 * Wp * l, rel=1e-12)
    assert P[1, 1] == pytest.approx(-2.0 / 3.0 * Wp * l**2.5, rel=1e-12)


def test_fiber_exp_linear_by_hand():
    """FEBio's l dW/dl = c3 (exp(c4 (l - 1)) - 1) up to lam_max, c5 l + c6 past it, so the
    nominal stress along the fibre, 2 l dW/dI4 = (l dW/dl) / l; with c3 = 0 FEBio's
    c3 = c5 / c4 exp(-c4 (lam_max - 1)) (a continuous slope). Energy: the integral of it."""
    from scipy.integrate import quad

    c3, c4, c5, lm = EXPLIN["c3"], EXPLIN["c4"], EXPLIN["c5"], EXPLIN["lam_max"]
    c6 = c3 * (np.exp(c4 * (lm - 1)) - 1) - c5 * lm
    law = FiberExpLinear(**EXPLIN)
    for l in (1.02, 1.05, 1.1, 1.3):
        s = c3 * (np.exp(c4 * (l - 1)) - 1) if l < lm else c5 * l + c6
        F = np.diag([l, 1.0, 1.0])[None]
        assert law.stress(F)[0, 0, 0] == pytest.approx(s / l, rel=1e-12)
        energy = quad(lambda t: (c3 * np.expm1(c4 * (t - 1)) if t < lm else c5 * t + c6) / t,
                      1.0, l, points=[lm] if l > lm else None)[0]  # fmt: skip
        assert law.energy_density(F)[0] == pytest.approx(energy, rel=1e-9)
    slope = FiberExpLinear(c4=c4, c5=c5, lam_max=lm)
    h = 1e-6
    l = lm + h * np.array([-2.0, -1.0, 1.0, 2.0])
    s = slope.stress(np.stack([np.diag([x, 1.0, 1.0]) for x in l]))[:, 0, 0] * l  # l dW/dl
    below, above = (s[1] - s[0]) / h, (s[3] - s[2]) / h
    assert below == pytest.approx(c5, rel=1e-4) and above == pytest.approx(c5, rel=1e-9)


def test_fiber_exp_pow_uncoupled_at_constant_volume_by_hand():
    """J = 1, F = diag(l, l^-1/2, l^-1/2): P = W' (2 F a (x) a - 2/3 I4 F^-T), so
    P11 = 4/3 l W' and P22 = -2/3 l^(5/2) W' with W' at x = l^2 - 1."""
    ksi, alpha, beta = EXP["ksi"], EXP["alpha"], EXP["beta"]
    law = FiberExpPowUncoupled(**EXP)
    for l in (1.05, 1.2):
        x = l**2 - 1
        Wp = ksi * x ** (beta - 1) * np.exp(alpha * x**beta)
        P = law.stress(np.diag([l, l**-0.5, l**-0.5])[None])[0]
        assert P[0, 0] == pytest.approx(4 / 3 * l * Wp, rel=1e-12)
        assert P[2, 2] == pytest.approx(-2 / 3 * l**2.5 * Wp, rel=1e-12)


@pytest.mark.parametrize("uncoupled", [False, True])
def test_fiber_exp_pow_cauchy_stress_is_febios(uncoupled):
    """FEBio's FiberStress: sigma = 2 Wl / J N + mu / J sym(N (B - I)), N = (F a) (x) (F a),
    Wl = ksi x^(beta-1) exp(alpha x^beta); the uncoupled law's is the deviatoric part of the
    same on F~ = J^(-1/3) F (FEBio's DevFiberStress). Where the fibre is taut."""
    ksi, alpha, beta, mu = 50.0, 2.0, 2.5, 30.0
    a = np.array(FIBRE) / np.linalg.norm(FIBRE)
    cls = FiberExpPowUncoupled if uncoupled else FiberExpPow
    law = cls(ksi=ksi, alpha=alpha, beta=beta, mu=mu, fiber=FIBRE)
    F = random_deformations(np.random.default_rng(5), 40, 3, 0.2)
    P = law.stress(F)
    checked = 0
    for Fq, Pq in zip(F, P, strict=True):
        J = np.linalg.det(Fq)
        Fm = Fq * J ** (-1 / 3) if uncoupled else Fq
        n = Fm @ a
        x = n @ n - 1.0
        if x <= 0:
            assert np.all(Pq == 0.0)
            continue
        N = np.outer(n, n)
        NB = N @ (Fm @ Fm.T - np.eye(3))
        s = 2 * ksi * x ** (beta - 1) * np.exp(alpha * x**beta) / J * N + mu / J * (NB + NB.T) / 2
        if uncoupled:
            s = s - np.trace(s) / 3 * np.eye(3)
        np.testing.assert_allclose(Pq @ Fq.T / J, s, atol=1e-10 * np.abs(s).max())
        checked += 1
    assert checked > 10


def test_per_element_fibres_through_a_mixture_are_bound_and_assembled():
    mesh = box(divisions=(2, 1, 1))
    m = mesh.n_cells
    rng = np.random.default_rng(0)
    fibres = rng.standard_normal((m, 3))
    mix = SolidMixture([NeoHookean(**NH), FiberExpPow(**EXP, fiber=fibres)])
    bound = mix.bind(2 * m, 3)
    assert bound.components[1].fibres.shape == (2 * m, 1, 3)
    assert mix.components[1].fibres.shape == (m, 1, 3)
    assert SolidMixture([NeoHookean(**NH)]).bind(10, 3).components[0] is not None
    model = Model(mesh, mix, np.ones(m), backend="numpy")
    x = mesh.points.ravel() * np.repeat([1.15, 0.95, 0.95], mesh.n_points) + 0.02 * (
        rng.standard_normal(mesh.points.size)
    )
    F = model.kinematics.deformation_gradients(x)
    laws = [SolidMixture([NeoHookean(**NH), FiberExpPow(**EXP, fiber=f)]) for f in fibres]
    per_element = np.array([law.energy_density(F[e : e + 1])[0] for e, law in enumerate(laws)])
    acc = model.evaluate(x, 1, False)
    assert acc.value == pytest.approx(per_element @ model.kinematics.weights, rel=1e-12)


def test_registry_tables_and_names():
    mix = make_material(
        "solid mixture",
        components=[
            {"model": "neo-Hookean", **NH},
            {"model": "fiber-exp-pow", **EXP, "fiber": [0, 1, 0]},
            FiberPowLinear(**LIN),
        ],
    )
    assert isinstance(mix, SolidMixture) and isinstance(mix.components[1], FiberExpPow)
    unc = make_material(
        "uncoupled_solid_mixture",
        k=1e4,
        components=[
            {"model": "Mooney-Rivlin", "c1": 100.0},
            {"model": "fibre_exp_pow_uncoupled", **EXP},
        ],
    )
    assert unc.components[0].k == 0.0 and unc.k == 1e4
    assert "FiberExpPowUncoupled" in repr(unc) and "k=10000.0" in repr(unc)
    assert volumetric_part(mix).lam == pytest.approx(NeoHookean(**NH).lam)


@pytest.mark.parametrize(
    "model, params, message",
    [
        ("solid_mixture", {}, "needs components"),
        ("solid_mixture", {"components": []}, "at least one component"),
        ("solid_mixture", {"components": [{"c1": 1.0}]}, r"components\[0\] needs its model"),
        ("solid_mixture", {"components": [{"model": "fiber_exp_pow", **EXP}]}, "must be > 0"),
        ("solid_mixture", {"components": [{"model": "neo_hookean", **NH}], "k": 1.0}, "unknown"),
        (
            "solid_mixture",
            {"components": [SolidMixture([NeoHookean(**NH)])]},
            "is a mixture",
        ),
        (
            "solid_mixture",
            {"components": [Viscoelastic(NeoHookean(**NH), g=[0.5], tau=[1.0])]},
            "visco-elastic",
        ),
        (
            "uncoupled_solid_mixture",
            {"k": 1e3, "components": [{"model": "neo_hookean", **NH}]},
            "not an uncoupled law",
        ),
        ("uncoupled_solid_mixture", {"components": [{"model": "yeoh", "c1": 1.0}]}, "needs k"),
        ("fiber_exp_pow", {**EXP, "mu": -1.0}, r"mu \(the fibre's shear modulus\) must be >= 0"),
        ("fiber_exp_pow", {**EXP, "beta": 1.5}, "beta must be >= 2"),
        ("fiber_exp_pow", {**EXP, "lam0": 0.9}, "lam0 must be >= 1"),
        ("fiber_exp_pow", {"alpha": 1.0}, "needs ksi"),
        ("fiber_exp_pow", {**EXP, "fiber": [0, 0, 0]}, "non-zero"),
        ("fiber_pow_linear", {**LIN, "lam0": 1.0}, "lam0 .* must be > 1"),
        ("fiber_pow_linear", {**LIN, "tension_only": 0}, "tension_only"),
        ("fiber_pow_linear", {"lam0": 1.1}, "needs E"),
        ("fiber_exp_linear", {**EXPLIN, "c4": 0.0}, "c4 must be > 0"),
        ("fiber_exp_linear", {**EXPLIN, "lam_max": 0.9}, "lam_max >= 1"),
        (
            "solid_mixture",
            {"components": [{"model": "neo_hookean", **NH}, {"model": "fiber_pow_linear"}]},
            r"components\[1\]: fiber_pow_linear needs E",
        ),
    ],
)
def test_parameter_errors(model, params, message):
    with pytest.raises(MaterialError, match=message):
        make_material(model, **params)


@pytest.mark.parametrize("name", ["solid_mixture", "uncoupled_solid_mixture"])
def test_mean_dilatation_of_a_mixture_under_homogeneous_stretch(name):
    """The mixture's volumetric part (the components' summed, or the uncoupled mixture's own
    bulk term) averaged over patches: a homogeneous stretch has the same energy and gradient
    as in the displacement form."""
    mesh = box(divisions=(2, 2, 1))
    x = (mesh.points * [1.12, 0.96, 0.97]).ravel()
    law = LAWS[name]()
    out = [
        Model(mesh, law, np.ones(mesh.n_cells), backend="numpy", formulation=f).evaluate(
            x, 1, False
        )
        for f in ("displacement", "mean_dilatation")
    ]
    assert out[1].value == pytest.approx(out[0].value, rel=1e-12)
    np.testing.assert_allclose(
        out[1].gradient, out[0].gradient, atol=1e-9 * abs(out[0].gradient).max()
    )


def test_an_uncoupled_mixture_in_uncoupled_viscoelastic():
    """FEBio's uncoupled viscoelastic wraps an uncoupled mixture: its bulk term stays elastic."""
    law = make_material(
        "uncoupled_viscoelastic",
        elastic={
            "model": "uncoupled_solid_mixture",
            "k": 1e4,
            "components": [
                {"model": "mooney_rivlin", "c1": 100.0},
                {"model": "fiber_exp_pow_uncoupled", **EXP},
            ],
        },
        g=[0.5],
        tau=[1.0],
    )
    bound = law.bind(4, 3)
    res = bound.evaluate(np.eye(3)[None].repeat(4, axis=0))
    np.testing.assert_allclose(res.stress, 0.0, atol=1e-10)
