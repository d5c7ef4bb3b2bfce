"""The fibre-reinforced laws (Holzapfel-Gasser-Ogden, HGO unconstrained, trans iso
Mooney-Rivlin): finite differences in 2D and 3D, the rest state, objectivity (but not isotropy),
closed forms by hand from principal stretches, the fibre-free limit, per-element fibres bound
to integration points and assembled, and parameter errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.fibres.holzapfel_gasser_ogden import HGOUnconstrained, HolzapfelGasserOgden
from tissuesim.materials.fibres.trans_iso_mooney_rivlin import TransIsoMooneyRivlin
from tissuesim.mesh import box
from tissuesim.model import Model

HGO = dict(c=100.0, k1=300.0, k2=2.0, kappa=0.1, gamma=30.0, k=5000.0)
TIMR = dict(c1=100.0, c2=20.0, c3=10.0, c4=5.0, c5=400.0, lam_max=1.1, k=5000.0)
LAWS = {
    "hgo": lambda **kw: HolzapfelGasserOgden(**HGO, **kw),
    "hgo_dispersed_tilted": lambda **kw: HolzapfelGasserOgden(
        **{**HGO, "kappa": 0.25}, mat_axis_a=[1, 0.3, 0.2], mat_axis_d=[0, 1, 0.4], **kw
    ),
    "hgo_unconstrained": lambda **kw: HGOUnconstrained(**HGO, **kw),
    "trans_iso_mooney_rivlin": lambda **kw: TransIsoMooneyRivlin(**TIMR, fiber=[1, 1, 0], **kw),
}


@pytest.mark.parametrize("name", sorted(LAWS))
@pytest.mark.parametrize("d", [2, 3])
def test_stress_and_tangent_match_finite_differences(name, d):
    law = LAWS[name]()
    F = random_deformations(np.random.default_rng(d), 8, d, 0.25)
    res = law.evaluate(F)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7
    At = np.transpose(res.tangent, (0, 3, 4, 1, 2))
    np.testing.assert_allclose(res.tangent, At, atol=1e-12 * np.abs(At).max())


@pytest.mark.parametrize("name", sorted(LAWS))
def test_rest_state_objectivity_and_anisotropy(name):
    law = LAWS[name]()
    res = law.evaluate(np.eye(3)[None])
    assert abs(res.energy[0]) < 1e-12 * law.mu and np.abs(res.stress).max() < 1e-12 * law.mu
    rng = np.random.default_rng(4)
    F = random_deformations(rng, 6, 3, 0.3)
    Q, _ = np.linalg.qr(rng.standard_normal((6, 3, 3)))
    Q[np.linalg.det(Q) < 0, :, 0] *= -1
    psi = law.energy_density(F)
    np.testing.assert_allclose(law.energy_density(Q @ F), psi, rtol=1e-11)
    np.testing.assert_allclose(law.stress(Q @ F), Q @ law.stress(F), rtol=1e-9, atol=1e-9 * law.k)
    # not isotropic: rotating the reference changes the energy
    assert np.max(np.abs(law.energy_density(F @ Q) - psi) / np.abs(psi)) > 1e-3


def test_without_fibres_they_are_mooney_rivlin():
    F = random_deformations(np.random.default_rng(9), 6, 3, 0.3)
    hgo = HolzapfelGasserOgden(c=100.0, k1=0.0, k2=2.0, k=5000.0)
    mr = make_material("mooney_rivlin", c1=50.0, k=5000.0, pressure_model="Abaqus (GOH)")
    np.testing.assert_allclose(hgo.stress_derivative(F), mr.stress_derivative(F), rtol=1e-11)
    ti = TransIsoMooneyRivlin(c1=100.0, c2=20.0, k=5000.0)
    mr = make_material("mooney_rivlin", c1=100.0, c2=20.0, k=5000.0)
    np.testing.assert_allclose(ti.stress_derivative(F), mr.stress_derivative(F), rtol=1e-11)
    # and with isotropic dispersion kappa = 1/3 the fibres only act on I1: the law is isotropic
    iso = HolzapfelGasserOgden(**{**HGO, "kappa": 1 / 3})
    Q, _ = np.linalg.qr(np.random.default_rng(1).standard_normal((3, 3)))
    np.testing.assert_allclose(iso.energy_density(F @ Q), iso.energy_density(F), rtol=1e-11)


def _fibre_s(l):
    """lb dWf/dlb of the TIMR fibre, by hand (c3 = 10, c4 = 5, c5 = 400, lam_max = 1.1)."""
    c3, c4, c5, lm = 10.0, 5.0, 400.0, 1.1
    c6 = c3 * (np.exp(c4 * (lm - 1)) - 1) - c5 * lm
    return np.where(l < 1, 0.0, np.where(l < lm, c3 * (np.exp(c4 * (l - 1)) - 1), c5 * l + c6))


def test_trans_iso_mooney_rivlin_uniaxial_along_the_fibre():
    """Incompressible uniaxial stretch along the fibre: P = 2 (l - l^-2)(c1 + c2/l) + s(l)/l."""
    law = TransIsoMooneyRivlin(**TIMR, fiber=[0, 0, 1])
    l = np.array([0.8, 0.95, 1.02, 1.08, 1.1, 1.15, 1.4])
    t = l**-0.5
    F = np.zeros((l.size, 3, 3))
    F[:, 0, 0], F[:, 1, 1], F[:, 2, 2] = t, t, l
    P = law.stress(F)
    nominal = P[:, 2, 2] - P[:, 0, 0] * t / l
    expected = 2 * (l - l**-2) * (100.0 + 20.0 / l) + _fibre_s(l) / l
    np.testing.assert_allclose(nominal, expected, rtol=1e-9)
    # the fibre's energy is continuous at lam_max (its two integrals join)
    e = [law.energy_density(np.diag([t, t, 1.1 + h])[None])[0] for t, h in ((1.1**-0.5, -1e-9),
         (1.1**-0.5, 1e-9))]  # fmt: skip
    assert abs(e[1] - e[0]) < 1e-5


def test_hgo_principal_stresses_by_hand():
    """F = R diag(l) S^T with the fibre plane rotated by S: P = R diag(dW/dl_a) S^T."""
    c, k1, k2, kappa, gamma, k = (HGO[key] for key in ("c", "k1", "k2", "kappa", "gamma", "k"))
    rng = np.random.default_rng(2)
    R, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    S, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    law = HolzapfelGasserOgden(**HGO, mat_axis_a=S[:, 0], mat_axis_d=S[:, 1])
    n = np.array([np.cos(np.radians(gamma)), np.sin(np.radians(gamma)), 0.0])
    for lams in ([1.2, 0.9, 1.0], [1.1, 1.15, 0.7], [0.8, 0.85, 1.3]):
        lams = np.array(lams)
        J = lams.prod()
        I1, I4 = (lams**2).sum(), (lams**2 * n**2).sum()
        I1b, I4b = J ** (-2 / 3) * I1, J ** (-2 / 3) * I4
        dI1b = J ** (-2 / 3) * (2 * lams - 2 / 3 * I1 / lams)
        dI4b = J ** (-2 / 3) * (2 * lams * n**2 - 2 / 3 * I4 / lams)
        E = kappa * (I1b - 3) + (1 - 3 * kappa) * (I4b - 1)
        dphi = k1 * E * np.exp(k2 * E**2) if E >= 0 else 0.0  # both families alike
        dU = 0.5 * k * (J - 1 / J)  # FEBio's GOH bulk term
        dW = c / 2 * dI1b + 2 * dphi * (kappa * dI1b + (1 - 3 * kappa) * dI4b) + dU * J / lams
        F = R @ np.diag(lams) @ S.T
        np.testing.assert_allclose(
            law.stress(F[None])[0], R @ np.diag(dW) @ S.T, atol=1e-10 * np.abs(dW).max()
        )


def test_per_element_fibres_are_bound_to_points_and_assembled():
    mesh = box(divisions=(2, 1, 1))
    m = mesh.n_cells
    rng = np.random.default_rng(0)
    fibres = rng.standard_normal((m, 3))
    law = TransIsoMooneyRivlin(**TIMR, fiber=fibres)
    assert law.fibres.shape == (m, 1, 3)
    with pytest.raises(MaterialError, match="fibre directions"):
        law.evaluate(np.eye(3)[None].repeat(m + 1, axis=0))
    bound = law.bind(2 * m, 3)
    assert bound.fibres.shape == (2 * m, 1, 3) and law.fibres.shape == (m, 1, 3)
    np.testing.assert_array_equal(bound.fibres[1::2], law.fibres)
    with pytest.raises(MaterialError, match="do not match"):
        law.bind(2 * m + 1, 3)
    assert HolzapfelGasserOgden(**HGO).bind(50, 3).fibres.shape == (1, 2, 3)  # global: itself
    # element e uses fibre e: the assembled energy is the per-element sum, and its gradient
    # matches finite differences
    model = Model(mesh, law.bind(m, 3), np.ones(m), backend="numpy")
    x = mesh.points.ravel() + 0.05 * rng.standard_normal(mesh.points.size)
    F = model.kinematics.deformation_gradients(x)
    per_element = np.array(
        [TransIsoMooneyRivlin(**TIMR, fiber=f).energy_density(F[e : e + 1])[0] for e, f in
         enumerate(fibres)]
    )  # fmt: skip
    acc = model.evaluate(x, 1, False)
    assert acc.value == pytest.approx(per_element @ model.kinematics.weights, rel=1e-12)
    dx = rng.standard_normal(x.size)
    eps = 1e-6
    fd = model.evaluate(x + eps * dx, 0, False).value - model.evaluate(x - eps * dx, 0, False).value
    assert fd / (2 * eps) == pytest.approx(acc.gradient @ dx, rel=1e-6)


@pytest.mark.parametrize(
    "cls, params, message",
    [
        (HolzapfelGasserOgden, {**HGO, "kappa": 0.4}, "kappa must be in"),
        (HolzapfelGasserOgden, {**HGO, "k1": -1.0}, "k1 and k2 must be >= 0"),
        (HolzapfelGasserOgden, {**HGO, "mat_axis_d": [2, 0, 0]}, "must not be parallel"),
        (HolzapfelGasserOgden, {**HGO, "c": 0.0}, "c must be > 0"),
        (HGOUnconstrained, {**HGO, "pressure_model": "Abaqus"}, "has no pressure_model"),
        (TransIsoMooneyRivlin, {**TIMR, "fiber": [0, 0, 0]}, "non-zero"),
        (TransIsoMooneyRivlin, {**TIMR, "fiber": "x"}, "must be a vector"),
        (TransIsoMooneyRivlin, {**TIMR, "c4": 0.0}, "c4 must be > 0"),
        (TransIsoMooneyRivlin, {**TIMR, "lam_max": 0.9}, "lam_max >= 1"),
        (TransIsoMooneyRivlin, {**TIMR, "k": None}, "needs k"),
    ],
)
def test_parameter_errors(cls, params, message):
    with pytest.raises(MaterialError, match=message):
        cls(**params)


def test_output_fields_of_a_law_with_per_point_fibres():
    """continuum_fields keeps the batch aligned with the fibres: an inverted point gets NaN
    stresses, the others their own fibre's."""
    from tissuesim.materials.measures import continuum_fields

    fibres = np.eye(3)[[0, 1, 2, 0]]
    law = TransIsoMooneyRivlin(**TIMR, fiber=fibres)
    F = np.stack([np.diag([1.2, 1.0, 1.0])] * 4)
    F[2, 0, 0] = -1.0  # inverted
    fields = continuum_fields(law, F)
    sigma = fields["cauchy_stress"]
    assert np.isnan(sigma[2]).all() and np.isfinite(sigma[[0, 1, 3]]).all()
    np.testing.assert_allclose(sigma[3], sigma[0])  # same fibre, same stress
    assert sigma[0, 0, 0] > sigma[1, 0, 0]  # along its fibre it is stiffer
    assert fields["energy_density"][2] == np.inf


@pytest.mark.parametrize("name", ["hgo", "hgo_unconstrained", "trans_iso_mooney_rivlin"])
def test_mean_dilatation_with_fibres_matches_finite_differences(name):
    mesh = box(divisions=(2, 1, 1), order=2)
    law = LAWS[name]()
    md = Model(mesh, law, np.ones(mesh.n_cells), backend="numpy", formulation="mean_dilatation")
    rng = np.random.default_rng(3)
    x = mesh.points.ravel() + 0.03 * rng.standard_normal(mesh.points.size)
    acc = md.evaluate(x, 2, False)
    H = md.pattern.matrix(acc.hessian)
    dx = rng.standard_normal(x.size)
    eps = 1e-6
    plus, minus = md.evaluate(x + eps * dx, 1, False), md.evaluate(x - eps * dx, 1, False)
    assert (plus.value - minus.value) / (2 * eps) == pytest.approx(acc.gradient @ dx, rel=1e-6)
    fd_H = (plus.gradient - minus.gradient) / (2 * eps)
    np.testing.assert_allclose(fd_H, H @ dx, rtol=0, atol=1e-6 * np.abs(H @ dx).max())


@pytest.mark.parametrize("name", ["hgo", "hgo_unconstrained", "trans_iso_mooney_rivlin"])
def test_the_volumetric_part_is_the_k_term(name):
    from tissuesim.materials.volumetric import volumetric_part

    F = random_deformations(np.random.default_rng(6), 8, 3, 0.3)
    a, b = LAWS[name](), LAWS[name]()
    b.k = 2 * a.k  # the same law with another bulk modulus
    theta = volumetric_part(a).theta(F, 0)[0]
    diff = a.energy_density(F) - b.energy_density(F)
    Ua, Ub = volumetric_part(a).energy(theta, 0)[0], volumetric_part(b).energy(theta, 0)[0]
    np.testing.assert_allclose(diff, Ua - Ub, rtol=1e-10, atol=1e-9)


def test_scenes_take_fibre_laws_with_directions_per_element():
    import tomllib

    from tissuesim.scene.loader import build_scene

    page = (Path(__file__).resolve().parents[2] / "docs/guide/materials.md").read_text()
    blocks = [b.split("```")[0] for b in page.split("```toml\n")[1:]]
    shown = [b for b in blocks if "holzapfel_gasser_ogden" in b]  # the block, not the page after
    hgo = tomllib.loads(shown[0])["material"]
    assert hgo["model"] == "holzapfel_gasser_ogden"
    base = {
        "mesh": {"generator": "box", "lower": [0, 0, 0], "upper": [1, 0.4, 0.4],
                 "divisions": [3, 1, 1]},
        "simulation": {"density": 1000.0, "integrator": "quasistatic", "time_step": 1.0},
        "gravity": {"acceleration": [0.0, 0.0, -9.81]},
        "dirichlet": [{"vertices": {"on_plane": {"axis": 0, "value": 0.0}}}],
        "run": {"steps": 1},
    }  # fmt: skip
    m = 3 * 1 * 1 * 6
    per_element = {"model": "trans_iso_mooney_rivlin", "c1": 2000.0, "c3": 100.0, "c4": 5.0,
                   "c5": 3e4, "lam_max": 1.2, "k": 1e5, "fiber": [[1.0, 0.0, 0.0]] * m}  # fmt: skip
    for material in (hgo, per_element):
        sim = build_scene({**base, "material": material}, name="fibres").simulation
        sim.step()
        tip = np.isclose(sim.mesh.points[:, 0], 1.0)
        assert sim.displacement[tip, 2].mean() < 0
    with pytest.raises(Exception, match=f"{m - 1} vectors given, read as one per cell, but"):
        bad = {**per_element, "fiber": [[1.0, 0.0, 0.0]] * (m - 1)}
        build_scene({**base, "material": bad}, name="fibres").simulation.step()
