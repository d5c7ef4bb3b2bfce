"""The soft-tissue laws (Mooney-Rivlin, Ogden, Yeoh, Veronda-Westmann, Arruda-Boyce; coupled and
uncoupled) in 2D and 3D: P = dpsi/dF and A = dP/dF by central differences, the stress- and
energy-free rest state, the small-strain moduli (derived by hand), objectivity, plane strain,
J <= 0, and Ogden at equal and nearly equal principal stretches."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import InvertedElementError
from tissuesim.materials import SOFT_TISSUE_LAWS, make_material, project_tangent_psd

#: parameters of each law, and its small-strain (mu, lam) worked out by hand (docstrings)
A_FEBIO = (0.5, 0.1, 11 / 350, 19 / 1750, 519 / 134750)


def _ab_w1_w11(mu, N, I1=3.0):
    w1 = mu * sum(i * a * (I1 / N) ** (i - 1) for i, a in enumerate(A_FEBIO, 1))
    w11 = mu / N * sum(i * (i - 1) * a * (I1 / N) ** (i - 2) for i, a in enumerate(A_FEBIO, 1))
    return w1, w11


_AB_W1, _AB_W11 = _ab_w1_w11(300.0, 4.0)
CASES = {
    "mooney_rivlin": (dict(c1=150.0, c2=40.0, k=3000.0), 380.0, 3000.0 - 2 * 380.0 / 3),
    "coupled_mooney_rivlin": (dict(c1=150.0, c2=40.0, k=3000.0), 380.0, 3000.0 + 160.0),
    "ogden": (
        dict(c=[300.0, -40.0, 20.0], m=[4.0, -2.0, 9.0], k=3000.0),
        140.0,
        3000.0 - 2 * 140.0 / 3,
    ),
    "ogden_unconstrained": (
        dict(c=[300.0, -40.0, 20.0], m=[4.0, -2.0, 9.0], cp=3000.0),
        140.0,
        3000.0,
    ),
    "yeoh": (dict(c1=150.0, c2=30.0, c3=5.0, k=3000.0), 300.0, 3000.0 - 200.0),
    "coupled_yeoh": (dict(c1=150.0, c2=30.0, c3=5.0, k=3000.0), 300.0, 3000.0 + 240.0),
    "veronda_westmann": (dict(c1=200.0, c2=1.5, k=3000.0), 300.0, 3000.0 - 200.0),
    "coupled_veronda_westmann": (
        dict(c1=200.0, c2=1.5, k=3000.0),
        300.0,
        3000.0 + 4 * 200.0 * 1.5**2 - 2 * 200.0 * 1.5,
    ),
    "arruda_boyce": (dict(mu=300.0, N=4.0, k=3000.0), 2 * _AB_W1, 3000.0 - 4 * _AB_W1 / 3),
    "coupled_arruda_boyce": (dict(mu=300.0, N=4.0, k=3000.0), 2 * _AB_W1, 3000.0 + 4 * _AB_W11),
}
NAMES = sorted(CASES)
DIMS = (2, 3)


def test_every_soft_tissue_law_is_tested():
    assert {cls.name for cls in SOFT_TISSUE_LAWS} == set(CASES)


@pytest.fixture(params=NAMES)
def law(request):
    return make_material(request.param, **CASES[request.param][0])


@pytest.mark.parametrize("d", DIMS)
def test_stress_and_tangent_match_finite_differences(law, d):
    rng = np.random.default_rng(100 + d)
    for spread, jmin in ((0.1, 0.5), (0.35, 0.3)):
        F = random_deformations(rng, 6, d, spread, jmin)
        res = law.evaluate(F, 2)
        assert res.energy.shape == (6,) and res.stress.shape == F.shape
        assert res.tangent.shape == (6, d, d, d, d)
        assert (
            relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
        ), law.name
        assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7, (
            law.name
        )
        At = np.transpose(res.tangent, (0, 3, 4, 1, 2))
        np.testing.assert_allclose(res.tangent, At, atol=1e-12 * np.abs(At).max())
        low = law.evaluate(F, 0)
        assert low.stress is None and low.tangent is None
        np.testing.assert_allclose(low.energy, res.energy, rtol=1e-13)
        np.testing.assert_allclose(law.evaluate(F, 1).stress, res.stress, rtol=1e-13)


def test_finite_differences_catch_a_wrong_tangent(law):
    """The check above can fail: a tangent off by a small term is caught."""
    F = random_deformations(np.random.default_rng(5), 4, 3, 0.3, 0.3)
    A = law.stress_derivative(F) * (1 + 1e-5)
    assert relative_difference(A, central_difference(law.stress, F, 1e-6)) > 1e-6


@pytest.mark.parametrize("d", DIMS)
def test_rest_state_is_energy_and_stress_free_with_the_hand_moduli(law, d):
    _, mu, lam = CASES[law.name]
    assert law.mu == pytest.approx(mu, rel=1e-13) and law.lam == pytest.approx(lam, rel=1e-13)
    res = law.evaluate(np.eye(d)[None].repeat(2, axis=0))
    np.testing.assert_allclose(res.energy, 0.0, atol=1e-12 * mu)
    np.testing.assert_allclose(res.stress, 0.0, atol=1e-12 * mu)
    I = np.eye(d)
    hooke = mu * (np.einsum("ik,jl->ijkl", I, I) + np.einsum("il,jk->ijkl", I, I))
    hooke = hooke + lam * np.einsum("ij,kl->ijkl", I, I)
    sym = 0.5 * (res.tangent + np.transpose(res.tangent, (0, 2, 1, 3, 4)))
    sym = 0.5 * (sym + np.transpose(sym, (0, 1, 2, 4, 3)))
    np.testing.assert_allclose(sym, np.broadcast_to(hooke, sym.shape), atol=1e-11 * lam)
    # and a small strain: P(I + eps H) = Hooke : eps sym(H) + O(eps^2)
    H = np.random.default_rng(0).standard_normal((d, d))
    eps = 1e-7
    P = law.stress((I + eps * H)[None])[0]
    linear = eps * np.einsum("ijkl,kl->ij", hooke, 0.5 * (H + H.T))
    np.testing.assert_allclose(P, linear, atol=1e-5 * np.abs(linear).max())


@pytest.mark.parametrize("d", DIMS)
def test_objectivity(law, d):
    rng = np.random.default_rng(20 + d)
    F = random_deformations(rng, 8, d, 0.35, 0.3)
    Q, _ = np.linalg.qr(rng.standard_normal((8, d, d)))
    Q[np.linalg.det(Q) < 0, :, 0] *= -1.0
    psi, P = law.energy_density(F), law.stress(F)
    np.testing.assert_allclose(law.energy_density(Q @ F), psi, rtol=1e-11, atol=1e-12 * law.mu)
    np.testing.assert_allclose(law.stress(Q @ F), Q @ P, rtol=1e-10, atol=1e-11 * law.mu)
    # and isotropy: psi(F Q) = psi(F)
    np.testing.assert_allclose(law.energy_density(F @ Q), psi, rtol=1e-11, atol=1e-12 * law.mu)


def test_plane_strain_is_3d_with_unit_out_of_plane_stretch(law):
    F2 = random_deformations(np.random.default_rng(3), 5, 2, 0.3, 0.3)
    F3 = np.zeros((5, 3, 3))
    F3[:, :2, :2], F3[:, 2, 2] = F2, 1.0
    r2, r3 = law.evaluate(F2), law.evaluate(F3)
    np.testing.assert_allclose(r2.energy, r3.energy, rtol=1e-12)
    np.testing.assert_allclose(r2.stress, r3.stress[:, :2, :2], rtol=1e-10, atol=1e-10 * law.mu)
    np.testing.assert_allclose(
        r2.tangent, r3.tangent[:, :2, :2, :2, :2], rtol=1e-10, atol=1e-10 * law.lam
    )


@pytest.mark.parametrize("d", DIMS)
def test_inverted_and_degenerate_points(law, d):
    F = np.stack([np.eye(d), np.eye(d), np.eye(d), np.eye(d)])
    F[1, 0, 0] = -1.0  # J = -1
    F[2, 0, 0] = 0.0  # J = 0
    F[3, 0, 0] = np.nan
    psi = law.energy_density(F)
    assert psi[0] == 0.0 and np.all(np.isposinf(psi[1:]))
    with pytest.raises(InvertedElementError, match=law.name) as info:
        law.stress(F)
    assert list(info.value.indices) == [1, 2, 3]
    with pytest.raises(InvertedElementError):
        law.stress_derivative(F[1:2])


def test_psd_projection_of_a_compressed_tangent(law):
    F = np.diag([0.45, 1.6, 1.3])[None]
    out = project_tangent_psd(law.stress_derivative(F))
    assert np.linalg.eigvalsh(out.reshape(1, 9, 9)).min() > -1e-9 * law.lam


# -- Ogden at equal principal stretches --------------------------------------------------------


@pytest.mark.parametrize("name", ["ogden", "ogden_unconstrained"])
@pytest.mark.parametrize("d", DIMS)
def test_ogden_at_equal_and_nearly_equal_stretches(name, d):
    law = make_material(name, **CASES[name][0])
    l = 1.17
    diag = {
        "identity": [1.0, 1.0, 1.0],
        "equibiaxial": [l, l, l**-2],
        "spherical": [l, l, l],
        "near": [l, l * (1 + 1e-9), 0.9],
        "near_far": [l, l * (1 + 3e-6), 0.9],
        "three_near": [l, l * (1 + 1e-12), l * (1 - 1e-12)],
    }
    rng = np.random.default_rng(d)
    R, _ = np.linalg.qr(rng.standard_normal((d, d)))
    for label, stretches in diag.items():
        D = np.diag(stretches[:d])
        F = np.stack([D, R @ D @ R.T])
        res = law.evaluate(F)
        assert np.all(np.isfinite(res.tangent)), label
        # the rotated tangent is the rotation of the tangent: no dependence on the eigenvectors
        rot = np.einsum("ia,jb,kc,ld,abcd->ijkl", R, R, R, R, res.tangent[0])
        np.testing.assert_allclose(res.tangent[1], rot, atol=1e-10 * law.lam, err_msg=label)
        A_fd = central_difference(law.stress, F, 1e-6)
        assert relative_difference(res.tangent, A_fd) < 1e-7, label
    # continuity: nearly equal stretches give the tangent of equal ones
    A_eq = law.stress_derivative(np.diag([l, l, 0.9][:d])[None])
    for delta in (1e-13, 1e-10, 1e-7):
        A = law.stress_derivative(np.diag([l, l * (1 + delta), 0.9][:d])[None])
        assert relative_difference(A, A_eq) < 10 * delta + 1e-13, delta


# FEBio's Holmes-Mow laws (issue 42): finite differences, small strain and the rest in
# test_materials_febio_laws.py; listed here for test_every_soft_tissue_law_is_tested
CASES.update(
    holmes_mow=(dict(E=1000.0, v=0.3, beta=0.5), 1000.0 / 2.6, 300.0 / (1.3 * 0.4)),
    uncoupled_holmes_mow=(dict(mu=300.0, beta=2.0, k=3000.0), 300.0, 3000.0 - 200.0),
)

# FEBio's Arruda-Boyce unconstrained (issue 42): tested in test_materials_febio_laws.py
CASES["arruda_boyce_unconstrained"] = (dict(ksi=300.0, N=4.0, kappa=3000.0), None, None)

# FEBio's isotropic Hencky (issue 42): tested in test_materials_febio_laws.py
CASES["isotropic_hencky"] = (dict(E=1000.0, v=0.3), 1000.0 / 2.6, 300.0 / (1.3 * 0.4))
