"""FEBio's laws added for its verification suite (issue 42): finite differences of stress and
tangent in 2D and 3D, the rest state, objectivity, anisotropy where the law has it, the way back
from ``parameters()``, the mean-dilatation volumetric part, and the parameter refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.volumetric import volumetric_part

ORTHO = dict(E1=1000.0, E2=2000.0, E3=3000.0, G12=600.0, G23=400.0, G31=500.0)
ORTHO.update(v12=0.3, v23=0.2, v31=0.25)
AXES = dict(mat_axis_a=[1.0, 0.3, 0.2], mat_axis_d=[0.0, 1.0, 0.4])
TIMR = dict(c1=100.0, c2=20.0, c3=10.0, c4=5.0, c5=400.0, lam_max=1.1, k=5000.0)
TIVW = dict(c1=200.0, c2=1.5, c3=10.0, c4=5.0, c5=400.0, lam_max=1.1, k=5000.0)
#: name -> (registry name, parameters, FEBio type, isotropic)
LAWS = {
    "tivw": ("trans_iso_veronda_westmann", {**TIVW, "fiber": [1, 1, 0]},
             "trans iso Veronda-Westmann", False),
    "tivw_goh": ("trans_iso_veronda_westmann",
                 {**TIVW, "fiber": [0.2, 1, 0.5], "pressure_model": "Abaqus (GOH)"},
                 "trans iso Veronda-Westmann", False),
    "ctimr": ("coupled_trans_iso_mooney_rivlin",
              {**TIMR, "fiber": [1, 1, 0]}, "coupled trans-iso Mooney-Rivlin", False),
    "tc": ("tc_nonlinear_orthotropic",
           {"c1": 100.0, "c2": 20.0, "beta": [2.5, 3.0, 4.0], "ksi": [800.0, 300.0, 500.0],
            "k": 5000.0, **AXES}, "TC nonlinear orthotropic", False),
    "ortho": ("orthotropic_elastic", {**ORTHO, **AXES}, "orthotropic elastic", False),
    "fung": ("fung_orthotropic", {**ORTHO, **AXES, "c": 800.0, "k": 9000.0}, "Fung orthotropic",
             False),
    "fung_compressible": ("fung_ortho_compressible", {**ORTHO, **AXES, "c": 800.0, "k": 9000.0},
                          "Fung-ortho-compressible", False),
    "holmes_mow": ("holmes_mow", {"E": 1000.0, "v": 0.3, "beta": 0.5}, "Holmes-Mow", True),
    "holmes_mow_v0": ("holmes_mow", {"E": 1000.0, "v": 0.0, "beta": 2.0}, "Holmes-Mow", True),
    "uncoupled_holmes_mow": ("uncoupled_holmes_mow", {"mu": 300.0, "beta": 2.0, "k": 3000.0},
                             "uncoupled Holmes-Mow", True),
    "abu": ("arruda_boyce_unconstrained", {"ksi": 300.0, "N": 4.0, "kappa": 3000.0},
            "Arruda-Boyce unconstrained", True),
    "abu_short": ("arruda_boyce_unconstrained",
                  {"ksi": 300.0, "N": 2.0, "n_term": 3, "kappa": 300.0},
                  "Arruda-Boyce unconstrained", True),
    "hencky": ("isotropic_hencky", {"E": 1000.0, "v": 0.3}, "isotropic Hencky", True),
}  # fmt: skip
UNCOUPLED = ("tivw", "tivw_goh", "fung", "uncoupled_holmes_mow", "tc")


def _law(key: str):
    name, params, _, _ = LAWS[key]
    return make_material(name, **params)


@pytest.mark.parametrize("key", sorted(LAWS))
@pytest.mark.parametrize("d", [2, 3])
def test_stress_and_tangent_match_finite_differences(key, d):
    law = _law(key)
    F = random_deformations(np.random.default_rng(d), 8, d, 0.25)
    res = law.evaluate(F)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7
    At = np.transpose(res.tangent, (0, 3, 4, 1, 2))
    np.testing.assert_allclose(res.tangent, At, atol=1e-12 * np.abs(At).max())


@pytest.mark.parametrize("key", sorted(LAWS))
def test_rest_state_objectivity_and_anisotropy(key):
    law = _law(key)
    res = law.evaluate(np.eye(3)[None])
    assert abs(res.energy[0]) < 1e-12 * law.mu and np.abs(res.stress).max() < 1e-12 * law.mu
    rng = np.random.default_rng(4)
    F = random_deformations(rng, 6, 3, 0.3)
    Q, _ = np.linalg.qr(rng.standard_normal((6, 3, 3)))
    Q[np.linalg.det(Q) < 0, :, 0] *= -1
    psi = law.energy_density(F)
    np.testing.assert_allclose(law.energy_density(Q @ F), psi, rtol=1e-11)
    scale = np.abs(law.stress(F)).max()
    np.testing.assert_allclose(law.stress(Q @ F), Q @ law.stress(F), rtol=1e-9, atol=1e-11 * scale)
    turned = np.max(np.abs(law.energy_density(F @ Q) - psi) / np.abs(psi))
    assert turned < 1e-10 if LAWS[key][3] else turned > 1e-3


@pytest.mark.parametrize("key", sorted(LAWS))
def test_by_febio_name_and_back_from_its_parameters(key):
    name, params, febio, _ = LAWS[key]
    law = make_material(febio, **params)
    assert law.name == name and law.febio_name == febio
    again = make_material(name, **law.parameters())
    F = random_deformations(np.random.default_rng(7), 4, 3, 0.3)
    np.testing.assert_allclose(again.stress_derivative(F), law.stress_derivative(F), rtol=1e-12)


@pytest.mark.parametrize("key", UNCOUPLED)
def test_volumetric_part_is_the_bulk_term(key):
    """The mean-dilatation split of an uncoupled law: U(J) is its bulk term (k, pressure model),
    and psi - U(J) is zero under a pure dilatation (the deviatoric part does not see J)."""
    law = _law(key)
    part = volumetric_part(law)
    assert (part.theta_kind, part.u_kind, part.lam) == ("J", law.bulk_kind, law.k)
    F = np.eye(3)[None] * np.array([0.9, 1.0 + 1e-3, 1.2])[:, None, None]
    U = part.energy(np.linalg.det(F), 0)[0]
    np.testing.assert_allclose(law.energy_density(F), U, rtol=1e-12, atol=1e-12 * law.k)
    assert U[0] > 0.0 and U[2] > 0.0


def test_trans_iso_veronda_westmann_without_fibre_is_veronda_westmann():
    F = random_deformations(np.random.default_rng(9), 6, 3, 0.3)
    ti = make_material("trans_iso_veronda_westmann", c1=200.0, c2=1.5, k=5000.0)
    vw = make_material("veronda_westmann", c1=200.0, c2=1.5, k=5000.0)
    np.testing.assert_allclose(ti.stress_derivative(F), vw.stress_derivative(F), rtol=1e-11)
    # the fibre bears tension only: compressed along it, the law is the matrix
    fibre = make_material("trans_iso_veronda_westmann", **TIVW)
    G = np.diag([0.9, 1.05, 1.05])[None]
    np.testing.assert_allclose(fibre.stress(G), ti.stress(G), rtol=1e-12)
    assert (
        fibre.stress(np.diag([1.1, 0.95, 0.95])[None])[0, 0, 0]
        > ti.stress(np.diag([1.1, 0.95, 0.95])[None])[0, 0, 0] + 1.0
    )


@pytest.mark.parametrize(
    "params, message",
    [({"c2": 1.0, "k": 1.0}, "needs c1"), ({**TIVW, "c2": 0.0}, "c2 must be > 0"),
     ({**TIVW, "c4": -1.0}, "c3, c4, c5 must be >= 0"), ({**TIVW, "k": None}, "needs k")],
)  # fmt: skip
def test_trans_iso_veronda_westmann_refusals(params, message):
    with pytest.raises(MaterialError, match=message):
        make_material("trans_iso_veronda_westmann", **params)


def test_orthotropic_elastic_with_isotropic_constants_is_st_venant_kirchhoff():
    """E1 = E2 = E3 = E, G = E / (2 (1 + v)), v12 = v23 = v31 = v: FEBio's isotropic elastic
    (St Venant-Kirchhoff) in any axes; and Fung's law tends to it as c grows."""
    iso = dict(E1=1000.0, E2=1000.0, E3=1000.0, v12=0.3, v23=0.3, v31=0.3)
    iso.update(G12=1000.0 / 2.6, G23=1000.0 / 2.6, G31=1000.0 / 2.6)
    F = random_deformations(np.random.default_rng(3), 6, 3, 0.3)
    ortho = make_material("orthotropic_elastic", **iso, **AXES)
    stvk = make_material("stvk", youngs_modulus=1000.0, poisson_ratio=0.3)
    np.testing.assert_allclose(ortho.energy_density(F), stvk.energy_density(F), rtol=1e-12)
    np.testing.assert_allclose(ortho.stress_derivative(F), stvk.stress_derivative(F), atol=1e-9)
    fung = make_material("fung_ortho_compressible", **ORTHO, **AXES, c=1e9, k=1e-9)
    near = make_material("orthotropic_elastic", **ORTHO, **AXES)
    np.testing.assert_allclose(fung.stress(F), near.stress(F), rtol=1e-5, atol=1e-6)


def test_orthotropic_axes_turn_the_law():
    """The law along axes Q equals the law along the global axes on F Q (material frame)."""
    law = make_material("orthotropic_elastic", **ORTHO, **AXES)
    glob = make_material("orthotropic_elastic", **ORTHO)
    e1 = np.array(AXES["mat_axis_a"]) / np.linalg.norm(AXES["mat_axis_a"])
    e3 = np.cross(e1, AXES["mat_axis_d"])
    e3 /= np.linalg.norm(e3)
    Q = np.stack([e1, np.cross(e3, e1), e3], axis=1)
    F = random_deformations(np.random.default_rng(5), 6, 3, 0.3)
    np.testing.assert_allclose(law.energy_density(F), glob.energy_density(F @ Q), rtol=1e-12)


@pytest.mark.parametrize(
    "change, message",
    [({"E2": 0.0}, "E2 must be > 0"), ({"G12": -1.0}, "G12 must be >= 0"),
     ({"v12": 0.8}, r"v12 must be <= sqrt\(E1/E2\)"), ({"v31": None}, "needs v31"),
     ({"v12": 0.7, "v23": 0.6, "v31": 1.0}, "not positive definite")],
)  # fmt: skip
def test_orthotropic_refusals(change, message):
    with pytest.raises(MaterialError, match=message):
        make_material("orthotropic_elastic", **{**ORTHO, **change})


def test_fung_refusals():
    with pytest.raises(MaterialError, match="needs c"):
        make_material("fung_orthotropic", **ORTHO, k=100.0)
    with pytest.raises(MaterialError, match="needs k"):
        make_material("fung_ortho_compressible", **ORTHO, c=100.0)


def test_the_guides_orthotropic_scene_runs():
    """The materials guide's orthotropic_elastic block, in a scene: a bar under gravity
    sags; its per-element axes (a list, one per cell) run too."""
    import tomllib
    from pathlib import Path

    from tissuesim.scene.loader import build_scene

    page = (Path(__file__).resolve().parents[2] / "docs/guide/materials.md").read_text()
    blocks = [b.split("```")[0] for b in page.split("```toml\n")[1:]]
    shown = tomllib.loads(next(b for b in blocks if "orthotropic_elastic" in b))["material"]
    assert shown["model"] == "orthotropic_elastic"
    base = {
        "mesh": {"generator": "box", "lower": [0, 0, 0], "upper": [1, 0.4, 0.4],
                 "divisions": [3, 1, 1]},
        "simulation": {"density": 1.0, "integrator": "quasistatic", "time_step": 1.0},
        "gravity": {"acceleration": [0.0, 0.0, -9.81]},
        "dirichlet": [{"vertices": {"on_plane": {"axis": 0, "value": 0.0}}}],
        "run": {"steps": 1},
    }  # fmt: skip
    m = 3 * 1 * 1 * 6
    per_element = {**shown, "mat_axis_a": [[1.0, 0.0, 0.0]] * m}
    for material in (shown, per_element):
        sim = build_scene({**base, "material": material}, name="ortho").simulation
        sim.step()
        tip = np.isclose(sim.mesh.points[:, 0], 1.0)
        assert sim.displacement[tip, 2].mean() < 0


@pytest.mark.parametrize("v", [0.0, 0.3, 0.45])
def test_holmes_mow_at_small_strain_is_hookes_law(v):
    """The tangent at rest is lam I (x) I + 2 mu sym, mu = E / (2 (1 + v)), lam = E v /
    ((1 + v)(1 - 2 v)); the uncoupled law's shear modulus is its mu."""
    E = 1000.0
    mu, lam = E / (2 * (1 + v)), E * v / ((1 + v) * (1 - 2 * v))
    A = make_material("holmes_mow", E=E, v=v, beta=0.7).stress_derivative(np.eye(3)[None])[0]
    I = np.eye(3)
    hooke = lam * np.einsum("ij,kl->ijkl", I, I) + mu * (
        np.einsum("ik,jl->ijkl", I, I) + np.einsum("il,jk->ijkl", I, I)
    )
    np.testing.assert_allclose(A, hooke, atol=1e-9 * E)
    uc = make_material("uncoupled_holmes_mow", mu=300.0, beta=2.0, k=3000.0)
    assert (uc.mu, uc.lam) == (300.0, 3000.0 - 200.0)
    F = np.eye(3)[None].copy()
    F[0, 0, 1] = 1e-6
    assert uc.stress(F)[0, 0, 1] == pytest.approx(300.0e-6, rel=1e-6)


def test_holmes_mow_volumetric_part_is_none():
    """The coupled law's J terms sit inside its exponential: mean dilatation keeps it whole."""
    part = volumetric_part(make_material("holmes_mow", E=1000.0, v=0.3, beta=0.5))
    assert (part.theta_kind, part.lam) == ("J", 0.0)


@pytest.mark.parametrize(
    "model, params, message",
    [("holmes_mow", {"E": 1.0, "v": 0.5, "beta": 1.0}, r"v must be in \(-1, 0.5\)"),
     ("holmes_mow", {"E": 1.0, "v": 0.2, "beta": 0.0}, "beta must be > 0"),
     ("holmes_mow", {"v": 0.2, "beta": 1.0}, "needs E"),
     ("uncoupled_holmes_mow", {"mu": 1.0, "beta": 1.0}, "needs k"),
     ("uncoupled_holmes_mow", {"mu": -1.0, "beta": 1.0, "k": 1.0}, "mu must be > 0")],
)  # fmt: skip
def test_holmes_mow_refusals(model, params, message):
    with pytest.raises(MaterialError, match=message):
        make_material(model, **params)


def test_coupled_trans_iso_mooney_rivlin_is_coupled_mooney_rivlin_and_febios_fibre():
    """Without fibre it is coupled Mooney-Rivlin; with c3 = 0 its fibre stays slack up to
    lam_max and then pulls with l dWf/dl = c5 (l - lam_max) (FEBio's coupled law keeps c3 = 0,
    where the uncoupled one takes the continuous-slope c3)."""
    F = random_deformations(np.random.default_rng(9), 6, 3, 0.3)
    ti = make_material("coupled_trans_iso_mooney_rivlin", c1=100.0, c2=20.0, k=5000.0)
    mr = make_material("coupled_mooney_rivlin", c1=100.0, c2=20.0, k=5000.0)
    np.testing.assert_allclose(ti.stress_derivative(F), mr.stress_derivative(F), rtol=1e-11)
    linear = dict(c1=100.0, c2=20.0, c5=400.0, c4=5.0, lam_max=1.1, k=5000.0)
    law = make_material("coupled_trans_iso_mooney_rivlin", **linear)
    for l, pull in ((1.05, 0.0), (1.2, 400.0 * (1.2 - 1.1))):
        t = l**-0.5
        Fl = np.diag([l, t, t])[None]
        P, Pm = law.stress(Fl)[0], mr.stress(Fl)[0]
        # the fibre's P_11 - P_22 t / l: 2 W4 l = l dWf/dl / l
        assert (P[0, 0] - P[1, 1] * t / l) - (Pm[0, 0] - Pm[1, 1] * t / l) == pytest.approx(
            pull / l, abs=1e-9
        )
    uncoupled = make_material("trans_iso_mooney_rivlin", **linear)
    assert uncoupled.c3 == 0.0 and uncoupled._fibre._c3 > 0.0  # its continuous slope


def test_tc_nonlinear_orthotropic_fibres_bear_tension_only():
    """Compressed along every axis (a pure isochoric squeeze is impossible, so: each axis in
    turn stretched while the others shorten) only the stretched family adds to the matrix,
    and with ksi = 0 the law is Mooney-Rivlin; one beta for all axes is three equal ones."""
    mr = make_material("mooney_rivlin", c1=100.0, c2=20.0, k=5000.0)
    one = dict(c1=100.0, c2=20.0, k=5000.0, beta=3.0)
    zero = make_material("tc_nonlinear_orthotropic", **one, ksi=0.0)
    F = random_deformations(np.random.default_rng(2), 5, 3, 0.3)
    np.testing.assert_allclose(zero.stress_derivative(F), mr.stress_derivative(F), rtol=1e-11)
    law = make_material("tc_nonlinear_orthotropic", **one, ksi=[500.0, 0.0, 0.0])
    same = make_material("tc_nonlinear_orthotropic", **{**one, "beta": [3.0] * 3}, ksi=[500, 0, 0])
    np.testing.assert_allclose(law.stress(F), same.stress(F), rtol=1e-14)
    squeezed = np.diag([0.9, 1.0 / 0.9**0.5, 1.0 / 0.9**0.5])[None]  # a_1 shorter: slack
    np.testing.assert_allclose(law.stress(squeezed), mr.stress(squeezed), rtol=1e-12)
    pulled = np.diag([1.2, 1.2**-0.5, 1.2**-0.5])[None]
    extra = law.energy_density(pulled) - mr.energy_density(pulled)
    np.testing.assert_allclose(extra, 500.0 * 0.2**3, rtol=1e-12)


@pytest.mark.parametrize(
    "change, message",
    [({"beta": 1.5}, "beta must be >= 2"), ({"ksi": [1.0, 2.0]}, "ksi takes 1 or 3 values"),
     ({"ksi": None}, "needs ksi")],
)  # fmt: skip
def test_tc_nonlinear_orthotropic_refusals(change, message):
    params = dict(c1=1.0, k=10.0, beta=3.0, ksi=1.0)
    with pytest.raises(MaterialError, match=message):
        make_material("tc_nonlinear_orthotropic", **{**params, **change})


def test_arruda_boyce_unconstrained_series_is_the_inverse_langevin_function():
    """The coefficients are the inverse Langevin function's series (reverted here from
    L(x) = coth x - 1/x = x/3 - x^3/45 + 2 x^5/945 - x^7/4725 + ... by Newton's iteration on
    the truncated series), and at rest the law is Hooke's with mu = W10, lam = 2 kappa + 4 w11."""
    from tissuesim.materials.soft_tissue.arruda_boyce_unconstrained import INVERSE_LANGEVIN

    y = np.linspace(0.05, 0.5, 10)
    inverse = np.polynomial.polynomial.polyval(
        y, np.ravel(np.c_[0 * INVERSE_LANGEVIN, INVERSE_LANGEVIN])
    )
    langevin = 1 / np.tanh(inverse) - 1 / inverse
    np.testing.assert_allclose(langevin, y, rtol=1e-13)
    np.testing.assert_allclose(
        INVERSE_LANGEVIN[:5], [3, 9 / 5, 297 / 175, 1539 / 875, 126117 / 67375]
    )
    law = make_material("arruda_boyce_unconstrained", ksi=300.0, N=4.0, kappa=3000.0)
    A = law.stress_derivative(np.eye(3)[None])[0]
    I = np.eye(3)
    hooke = law.lam * np.einsum("ij,kl->ijkl", I, I) + law.mu * (
        np.einsum("ik,jl->ijkl", I, I) + np.einsum("il,jk->ijkl", I, I)
    )
    np.testing.assert_allclose(A, hooke, atol=1e-9 * law.lam)
    assert law.lam > 2 * 3000.0 and law.mu > 300.0


@pytest.mark.parametrize(
    "change, message",
    [({"n_term": 2}, "n_term must be a whole number in 3..30"),
     ({"n_term": 3.5}, "n_term must be a whole number"), ({"kappa": 0.0}, "kappa must be > 0"),
     ({"N": None}, "needs N")],
)  # fmt: skip
def test_arruda_boyce_unconstrained_refusals(change, message):
    with pytest.raises(MaterialError, match=message):
        make_material(
            "arruda_boyce_unconstrained", **{"ksi": 1.0, "N": 4.0, "kappa": 1.0, **change}
        )


def test_isotropic_hencky_is_hookes_law_on_the_logarithmic_strain():
    """Kirchhoff stress 2 mu ln V + lam ln J I (FEBio's), at a random F and at equal stretches
    (the divided differences' limit), and the tangent equal to finite differences there."""
    law = make_material("isotropic_hencky", E=1000.0, v=0.3)
    mu, lam = 1000.0 / 2.6, 300.0 / (1.3 * 0.4)
    F = random_deformations(np.random.default_rng(11), 5, 3, 0.3)
    for G in (F, np.diag([1.2, 1.2, 0.9])[None], np.eye(3)[None] * 1.1):
        b = G @ np.swapaxes(G, 1, 2)
        w, v = np.linalg.eigh(b)
        h = np.einsum("qia,qa,qja->qij", v, 0.5 * np.log(w), v)
        J = np.linalg.det(G)
        tau = 2 * mu * h + (lam * np.log(J))[:, None, None] * np.eye(3)
        np.testing.assert_allclose(law.stress(G) @ np.swapaxes(G, 1, 2), tau, atol=1e-9 * mu)
        A = law.stress_derivative(G)
        assert relative_difference(A, central_difference(law.stress, G, 1e-6)) < 1e-7
