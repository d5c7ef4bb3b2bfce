"""A law from its energy (``EnergyLaw``): the derived P and dP/dF against finite differences and
against the hand-written laws, the checks every built-in law passes (rest, objectivity, tangent
symmetry, plane strain), and one clear error line for every bad psi."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

pytest.importorskip("sympy")

import sympy as sp  # noqa: E402

from tissuesim.errors import InvertedElementError, MaterialError, SceneError  # noqa: E402
from tissuesim.materials import (  # noqa: E402
    CoupledMooneyRivlin,
    EnergyLaw,
    MooneyRivlin,
    NeoHookean,
    Yeoh,
    from_energy,
    make_material,
)

MU, LAM = 400.0, 600.0
NH = "mu/2*(I1 - 3) - mu*log(J) + lam/2*log(J)**2"
#: (id, psi, parameters): invariant and component forms, isotropic and anisotropic
LAWS = [
    ("neo_hookean", NH, {"mu": MU, "lam": LAM}),
    ("neo_hookean_C", "mu/2*(C11 + C22 + C33 - 3) - mu*ln(J) + lam/2*ln(J)**2",
     {"mu": MU, "lam": LAM}),
    ("mooney_rivlin", "c1*(I1b - 3) + c2*(I2b - 3) + k/2*log(J)**2",
     {"c1": 300.0, "c2": 100.0, "k": 1e4}),
    ("exp_I3", "c*(exp(b*(I1 - 3)) - 1)/b - c*log(I3) + k/4*(I3 - 1 - log(I3))",
     {"c": 200.0, "b": 0.8, "k": 5e3}),
    ("fibre_x", NH + " + k1/(2*k2)*(exp(k2*(C11 - 1)**2) - 1)",
     {"mu": MU, "lam": LAM, "k1": 500.0, "k2": 3.0}),
    ("stvk_F", "mu*((F11**2 + F21**2 + F31**2 - 1)**2/4 + (F12**2 + F22**2 + F32**2 - 1)**2/4"
     " + (F13**2 + F23**2 + F33**2 - 1)**2/4 + (F11*F12 + F21*F22 + F31*F32)**2/2"
     " + (F11*F13 + F21*F23 + F31*F33)**2/2 + (F12*F13 + F22*F23 + F32*F33)**2/2)"
     " + lam/8*(I1 - 3)**2", {"mu": MU, "lam": LAM}),
]  # fmt: skip


def _random_F(rng, q, d, spread, jmin=0.3):
    out = []
    while len(out) < q:
        F = np.eye(d) + spread * rng.standard_normal((d, d))
        if np.linalg.det(F) > jmin:
            out.append(F)
    return np.array(out)


def _rotations(rng, q, d):
    Q, _ = np.linalg.qr(rng.standard_normal((q, d, d)))
    Q[np.linalg.det(Q) < 0, :, 0] *= -1.0
    return Q


def _central_diff(fun, F, h):
    q, d = F.shape[:2]
    basis = np.eye(d * d).reshape(d * d, d, d) * h
    Fp = (F[:, None] + basis[None]).reshape(-1, d, d)
    Fm = (F[:, None] - basis[None]).reshape(-1, d, d)
    diff = ((fun(Fp) - fun(Fm)) / (2 * h)).reshape((q, d, d) + fun(F[:1]).shape[1:])
    return np.moveaxis(diff, (1, 2), (-2, -1))


def _rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.fixture(scope="module", params=LAWS, ids=[law[0] for law in LAWS])
def law(request):
    _, psi, params = request.param
    return EnergyLaw(psi, **params)


@pytest.mark.parametrize("d", (2, 3))
def test_derived_stress_and_tangent_match_finite_differences(law, d):
    rng = np.random.default_rng(10 + d)
    F = _random_F(rng, 6, d, 0.25)
    res = law.evaluate(F, 2)
    assert res.stress.shape == F.shape and res.tangent.shape == (6, d, d, d, d)
    assert _rel(res.stress, _central_diff(law.energy_density, F, 1e-5)) < 1e-7
    assert _rel(res.tangent, _central_diff(law.stress, F, 1e-6)) < 1e-6
    # a Hessian: major symmetry A_ijkl = A_klij
    assert _rel(res.tangent, np.transpose(res.tangent, (0, 3, 4, 1, 2))) < 1e-13
    low = law.evaluate(F, 0)
    assert low.stress is None and low.tangent is None
    np.testing.assert_allclose(low.energy, res.energy, rtol=1e-14)
    np.testing.assert_allclose(law.evaluate(F, 1).stress, res.stress, rtol=1e-14)


@pytest.mark.parametrize("d", (2, 3))
def test_rest_is_stress_free_and_objective(law, d):
    rest = law.evaluate(np.eye(d)[None], 2)
    np.testing.assert_allclose(rest.energy, 0.0, atol=1e-9)
    np.testing.assert_allclose(rest.stress, 0.0, atol=1e-9 * law.mu)
    rng = np.random.default_rng(7 + d)
    F, Q = _random_F(rng, 8, d, 0.3), _rotations(rng, 8, d)
    np.testing.assert_allclose(law.energy_density(Q @ F), law.energy_density(F), rtol=1e-10)
    np.testing.assert_allclose(law.stress(Q @ F), Q @ law.stress(F), rtol=1e-9, atol=1e-9 * MU)


def test_plane_strain_equals_3d_with_unit_out_of_plane_stretch(law):
    F2 = _random_F(np.random.default_rng(3), 5, 2, 0.3)
    F3 = np.zeros((5, 3, 3))
    F3[:, :2, :2], F3[:, 2, 2] = F2, 1.0
    r2, r3 = law.evaluate(F2), law.evaluate(F3)
    np.testing.assert_allclose(r2.energy, r3.energy, rtol=1e-12)
    np.testing.assert_allclose(r2.stress, r3.stress[:, :2, :2], rtol=1e-11, atol=1e-9)
    np.testing.assert_allclose(r2.tangent, r3.tangent[:, :2, :2, :2, :2], rtol=1e-11, atol=1e-8)


#: (psi, parameters, the hand-written law)
AGAINST = [
    (NH, {"mu": MU, "lam": LAM}, NeoHookean(shear_modulus=MU, lame_lambda=LAM)),
    ("mu/2*(C11 + C22 + C33 - 3) - mu*log(J) + lam/2*log(J)**2", {"mu": MU, "lam": LAM},
     NeoHookean(shear_modulus=MU, lame_lambda=LAM)),
    ("c1*(I1b - 3) + c2*(I2b - 3) + k/2*log(J)**2", {"c1": 300.0, "c2": 100.0, "k": 1e4},
     MooneyRivlin(c1=300.0, c2=100.0, k=1e4)),
    ("c1*(I1 - 3) + c2*(I2 - 3) - 2*(c1 + 2*c2)*log(J) + k/2*log(J)**2",
     {"c1": 300.0, "c2": 100.0, "k": 1e4}, CoupledMooneyRivlin(c1=300.0, c2=100.0, k=1e4)),
    ("c1*(I1b - 3) + c2*(I1b - 3)**2 + c3*(I1b - 3)**3 + k/2*log(J)**2",
     {"c1": 300.0, "c2": 50.0, "c3": 10.0, "k": 1e4}, Yeoh(c1=300.0, c2=50.0, c3=10.0, k=1e4)),
]  # fmt: skip


@pytest.mark.parametrize(
    "psi, params, builtin", AGAINST, ids=[f"{b.name}_{i}" for i, (_, _, b) in enumerate(AGAINST)]
)
@pytest.mark.parametrize("d", (2, 3))
def test_equals_the_hand_written_law(psi, params, builtin, d):
    law = EnergyLaw(psi, **params)
    assert law.mu == pytest.approx(builtin.mu, rel=1e-12)
    assert law.lam == pytest.approx(builtin.lam, rel=1e-12)
    F = _random_F(np.random.default_rng(d), 40, d, 0.35, jmin=0.2)
    ours, theirs = law.evaluate(F), builtin.evaluate(F)
    for a, b in zip(
        (ours.energy, ours.stress, ours.tangent),
        (theirs.energy, theirs.stress, theirs.tangent),
        strict=True,
    ):
        assert _rel(a, b) < 1e-12


def test_a_function_of_F_is_the_same_law():
    def psi(F, mu, lam):
        J = F.det()
        return mu / 2 * ((F.T * F).trace() - 3) - mu * sp.log(J) + lam / 2 * sp.log(J) ** 2

    law = from_energy(psi, mu=MU, lam=LAM)
    assert law.kind == "components" and "log" in repr(law)
    nh = NeoHookean(shear_modulus=MU, lame_lambda=LAM)
    for d in (2, 3):
        F = _random_F(np.random.default_rng(d), 10, d, 0.3)
        assert _rel(law.evaluate(F).tangent, nh.evaluate(F).tangent) < 1e-12
    invariant = EnergyLaw(lambda I1, J, mu: mu / 2 * (I1 - 3) - mu * sp.log(J) + mu * (J - 1) ** 2,
                          mu=MU)  # fmt: skip
    assert invariant.kind == "invariants" and invariant.lam == pytest.approx(2 * MU)


def test_undefined_where_J_is_not_positive():
    law = EnergyLaw(NH, mu=MU, lam=LAM)
    for d in (2, 3):
        F = np.array([np.eye(d)] * 4)
        F[1, 0, 0], F[3, 0, 0] = -1.0, 0.0
        with np.errstate(all="raise"):
            psi = law.energy_density(F)
        assert np.isinf(psi[[1, 3]]).all() and np.isfinite(psi[[0, 2]]).all()
        with pytest.raises(InvertedElementError, match="energy law is undefined") as info:
            law.evaluate(F, 1)
        np.testing.assert_array_equal(info.value.indices, [1, 3])


def test_registry_repr_and_pickle():
    law = make_material("energy", psi=NH, mu=MU, lam=LAM)
    assert isinstance(law, EnergyLaw)
    assert repr(law) == f"EnergyLaw(psi={NH!r}, mu={MU!r}, lam={LAM!r})"
    again = pickle.loads(pickle.dumps(law))
    F = _random_F(np.random.default_rng(0), 3, 3, 0.2)
    np.testing.assert_array_equal(again.evaluate(F).tangent, law.evaluate(F).tangent)
    assert again.parameters() == {"psi": NH, "mu": MU, "lam": LAM}


BAD = [
    ({"psi": "mu/2*(I1 - 3) - mu*log(J) + lamda/2*log(J)**2", "mu": MU, "lam": LAM},
     "psi uses 'lamda'.*give it"),
    ({"psi": "mu/2*(I1 - 3) +", "mu": MU}, "psi: cannot parse"),
    ({"psi": "(mu*(I1 - 3), J)", "mu": MU}, "Tuple is not allowed.*a scalar is needed"),
    ({"psi": "mu*gamma(I1)", "mu": MU}, "unknown function 'gamma'"),
    ({"psi": "__import__('os').system('true')"}, "unknown function"),
    ({"psi": "mu.real*(I1 - 3)", "mu": MU}, "Attribute is not allowed"),
    ({"psi": "mu/2*(I1 - 3) - mu*log(J)", "mu": MU, "lam": LAM},
     "parameter 'lam' is not used in psi"),
    ({"psi": "mu/2*(I1 - 3) + lam/2*log(J)**2", "mu": MU, "lam": LAM}, "not stress-free at rest"),
    ({"psi": "-mu/2*(I1 - 3) + mu*log(J) + lam/2*log(J)**2", "mu": MU, "lam": LAM},
     "shear modulus"),
    ({"psi": "mu*F12**2 + lam/2*log(J)**2 + mu*(F11 - 1)**2", "mu": MU, "lam": LAM},
     "not objective"),
    ({"psi": "mu*2", "mu": MU}, "does not depend on the deformation"),
    ({"psi": "mu/(I1 - 3)", "mu": MU}, "not finite at rest"),
    ({"psi": "(-1)**0.5*mu*(I1 - 3) - mu*log(J)", "mu": MU}, "imaginary or infinite constant"),
    ({"psi": NH, "mu": "soft", "lam": LAM}, "mu"),
    ({"psi": NH, "mu": MU, "I1": LAM}, "'I1' is a variable"),
    ({"psi": 42}, "expression string or a function"),
]  # fmt: skip


@pytest.mark.parametrize("params, message", BAD, ids=[m for _, m in BAD])
def test_bad_energy_is_one_clear_line(params, message):
    with pytest.raises(MaterialError, match=message) as info:
        make_material("energy", **params)
    text = str(info.value)
    assert "\n" not in text and text.startswith("energy")


def test_bad_energy_in_a_scene_names_the_table():
    from tissuesim.scene.loader import build_scene

    data = {
        "mesh": {"generator": "box", "divisions": [2, 2, 2]},
        "material": {"model": "energy", "psi": "mu/2*(I1 - 3) - mu*log(J) + k*", "mu": 1.0},
    }
    with pytest.raises(SceneError, match=r"scene.toml \[material\]: energy: psi: cannot parse"):
        build_scene(data, source="scene.toml")
    data["material"] = {"model": "energy", "mu": 1.0}
    with pytest.raises(SceneError, match="energy needs psi"):
        build_scene(data, source="scene.toml")


def test_a_function_that_returns_a_matrix_is_refused():
    with pytest.raises(MaterialError, match="scalar"):
        EnergyLaw(lambda F, mu: mu * F, mu=MU)
    with pytest.raises(MaterialError, match="raised ValueError"):
        EnergyLaw(lambda I1, mu: mu * (I1 - 3) * float("one"), mu=MU)
    with pytest.raises(MaterialError, match="argument 'k'"):
        EnergyLaw(lambda I1, J, mu, k: mu * (I1 - 3), mu=MU)


def test_the_guides_scene_block_runs():
    """The [material] block of docs/guide/materials.md's section runs as a scene."""
    import tomllib
    from pathlib import Path

    from tissuesim.scene.loader import build_scene

    page = (Path(__file__).resolve().parents[2] / "docs/guide/materials.md").read_text()
    blocks = [b.split("```")[0] for b in page.split("```toml\n")[1:]]
    material = tomllib.loads(next(b for b in blocks if '"energy"' in b))["material"]
    scene = {
        "mesh": {"generator": "box", "upper": [1.0, 0.3, 0.3], "divisions": [4, 1, 1]},
        "material": material,
        "simulation": {"density": 1.0, "integrator": "quasistatic", "time_step": 1.0},
        "gravity": {"acceleration": [0.0, 0.0, -9.81]},
        "dirichlet": [{"vertices": {"on_plane": {"axis": 0, "value": 0.0}}}],
    }
    sim = build_scene(scene, name="energy").simulation
    assert isinstance(sim.bodies["body"].model.material, EnergyLaw)
    sim.step()
    assert sim.displacement[:, 2].min() < -1e-3
    builtin = {
        "model": "neo_hookean",
        "shear_modulus": material["mu"],
        "lame_lambda": material["lam"],
    }
    ref = build_scene({**scene, "material": builtin}, name="nh").simulation
    ref.step()
    np.testing.assert_allclose(sim.displacement, ref.displacement, rtol=0, atol=1e-12)
