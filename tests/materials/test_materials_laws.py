"""Checks every law in 2D and 3D: P = dpsi/dF and A = dP/dF by central differences, symmetry,
zero stress at rest, objectivity, plane-strain consistency and closed-form homogeneous states."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

from tissuesim.errors import InvertedElementError, MaterialError
from tissuesim.materials import (
    FIBRE_LAWS,
    MATERIALS,
    SOFT_TISSUE_LAWS,
    CourseNeoHookean,
    FixedCorotated,
    LinearElastic,
    NeoHookean,
    StVenantKirchhoff,
)

E, NU = 1000.0, 0.3
MU, LAM = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
#: the laws given by (E, nu) or (mu, lambda); the soft-tissue laws: test_materials_soft_tissue.py
ALL = [cls for cls in MATERIALS.values() if cls not in SOFT_TISSUE_LAWS + FIBRE_LAWS]
DIMS = (2, 3)


def _random_F(rng, q, d, spread, jmin=None, jmax=None):
    """q random F = I + spread * N(0, 1), resampled until jmin < J < jmax."""
    out = []
    while len(out) < q:
        F = np.eye(d) + spread * rng.standard_normal((d, d))
        J = np.linalg.det(F)
        if (jmin is None or J > jmin) and (jmax is None or J < jmax):
            out.append(F)
    return np.array(out)


def _rotations(rng, q, d):
    Q, _ = np.linalg.qr(rng.standard_normal((q, d, d)))
    Q[np.linalg.det(Q) < 0, :, 0] *= -1.0
    return Q


def _samples(cls, d, rng):
    """(label, F) batches each law must handle: near identity, large, inverted where defined."""
    cases = [
        ("near", _random_F(rng, 6, d, 0.1, jmin=0.5)),
        ("large", _random_F(rng, 6, d, 0.5, jmin=0.2)),
    ]
    if cls in (CourseNeoHookean, FixedCorotated, StVenantKirchhoff, LinearElastic):
        cases.append(("inverted", _random_F(rng, 6, d, 0.8, jmin=-3.0, jmax=-0.2)))
    return cases


def _central_diff(fun, F, h):
    """d fun / dF by central differences, one batched call; fun (q, d, d) -> (q, ...)."""
    q, d = F.shape[:2]
    basis = np.eye(d * d).reshape(d * d, d, d) * h
    Fp = (F[:, None] + basis[None]).reshape(-1, d, d)
    Fm = (F[:, None] - basis[None]).reshape(-1, d, d)
    diff = (fun(Fp) - fun(Fm)) / (2 * h)  # (q * d * d, ...)
    diff = diff.reshape((q, d, d) + diff.shape[1:])
    return np.moveaxis(diff, (1, 2), (-2, -1))  # derivative indices last


def _rel(a, b, scale):
    return np.max(np.abs(a - b)) / (np.max(np.abs(b)) + scale)


@pytest.fixture(params=ALL, ids=lambda c: c.name)
def law(request):
    return request.param(youngs_modulus=E, poisson_ratio=NU)


@pytest.mark.parametrize("d", DIMS)
def test_stress_and_tangent_match_finite_differences(law, d):
    rng = np.random.default_rng(1000 + d)
    for label, F in _samples(type(law), d, rng):
        res = law.evaluate(F, 2)
        assert res.energy.shape == (len(F),)
        assert res.stress.shape == F.shape
        assert res.tangent.shape == (len(F), d, d, d, d)
        P_fd = _central_diff(law.energy_density, F, 1e-5)
        assert _rel(res.stress, P_fd, MU) < 1e-7, (law.name, d, label)
        A_fd = _central_diff(law.stress, F, 1e-6)
        assert _rel(res.tangent, A_fd, MU) < 1e-6, (law.name, d, label)
        # major symmetry A_ijkl = A_klij (the tangent is a Hessian)
        At = np.transpose(res.tangent, (0, 3, 4, 1, 2))
        assert _rel(res.tangent, At, MU) < 1e-12, (law.name, d, label)
        # the accessors agree with evaluate, and lower orders leave the rest out
        np.testing.assert_allclose(law.stress_derivative(F), res.tangent)
        low = law.evaluate(F, 0)
        assert low.stress is None and low.tangent is None
        np.testing.assert_allclose(low.energy, res.energy)


@pytest.mark.parametrize("d", DIMS)
def test_rest_state_is_stress_free(law, d):
    res = law.evaluate(np.eye(d)[None].repeat(2, axis=0))
    np.testing.assert_allclose(res.energy, 0.0, atol=1e-12)
    np.testing.assert_allclose(res.stress, 0.0, atol=1e-12)
    # at rest every law linearises to the same isotropic Hooke tangent
    I = np.eye(d)
    hooke = MU * (
        np.einsum("ik,jl->ijkl", I, I) + np.einsum("il,jk->ijkl", I, I)
    ) + LAM * np.einsum("ij,kl->ijkl", I, I)
    sym = 0.5 * (res.tangent + np.transpose(res.tangent, (0, 2, 1, 3, 4)))  # acting on sym(dF)
    sym = 0.5 * (sym + np.transpose(sym, (0, 1, 2, 4, 3)))
    np.testing.assert_allclose(sym, np.broadcast_to(hooke, sym.shape), atol=1e-9 * MU)


@pytest.mark.parametrize("d", DIMS)
def test_rotation_invariance(law, d):
    rng = np.random.default_rng(7 + d)
    F = _random_F(rng, 8, d, 0.3, jmin=0.3)
    Q = _rotations(rng, 8, d)
    if isinstance(law, LinearElastic):
        # small-strain elasticity is not objective: a rigid rotation stores energy
        c, s = np.cos(0.5), np.sin(0.5)
        Rz = np.eye(d)
        Rz[:2, :2] = [[c, -s], [s, c]]
        assert law.energy_density(Rz[None])[0] > 0.01 * MU
        assert not np.allclose(law.energy_density(Rz @ F), law.energy_density(F))
        return
    np.testing.assert_allclose(
        law.energy_density(Q @ F), law.energy_density(F), rtol=1e-10, atol=1e-9
    )
    np.testing.assert_allclose(law.stress(Q @ F), Q @ law.stress(F), rtol=1e-9, atol=1e-8 * MU)


@pytest.mark.parametrize("cls", ALL, ids=lambda c: c.name)
def test_plane_strain_equals_3d_with_unit_out_of_plane_stretch(cls):
    law = cls(shear_modulus=MU, lame_lambda=LAM)
    F2 = _random_F(np.random.default_rng(3), 5, 2, 0.3, jmin=0.3)
    F3 = np.zeros((5, 3, 3))
    F3[:, :2, :2], F3[:, 2, 2] = F2, 1.0
    r2, r3 = law.evaluate(F2), law.evaluate(F3)
    np.testing.assert_allclose(r2.energy, r3.energy, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(r2.stress, r3.stress[:, :2, :2], rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(r2.tangent, r3.tangent[:, :2, :2, :2, :2], rtol=1e-10, atol=1e-8)


def _diag_stress(name, f):
    """Closed-form diagonal P for F = diag(f) (f > 0), written independently of the kernels."""
    J = np.prod(f)
    if name == "neo_hookean":
        return MU * f + (LAM * np.log(J) - MU) / f
    if name == "course_neo_hookean":
        x = J - 1
        r, dr = x - x**2 / 2 + x**3 / 3, 1 - x + x**2
        return MU * f + (LAM * r - MU) * dr * J / f
    if name == "stvk":
        Ed = (f**2 - 1) / 2
        return f * (LAM * Ed.sum() + 2 * MU * Ed)
    if name == "linear":
        return 2 * MU * (f - 1) + LAM * (f - 1).sum()
    if name == "fixed_corotated":
        return 2 * MU * (f - 1) + LAM * (J - 1) * J / f
    raise AssertionError(name)


@pytest.mark.parametrize("d", DIMS)
def test_diagonal_stretch_closed_form(law, d):
    for f in ([1.3, 0.8, 1.1][:d], [0.5, 0.6, 0.9][:d], [2.0, 1.5, 1.2][:d]):
        f = np.array(f)
        P = law.stress(np.diag(f)[None])[0]
        np.testing.assert_allclose(P, np.diag(_diag_stress(law.name, f)), rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("d", DIMS)
def test_small_uniaxial_stretch_recovers_young_and_poisson(law, d):
    """Free lateral contraction: 3D gives E and nu, plane strain E/(1-nu^2) and nu/(1-nu)."""
    eps = 1e-6
    s = 1 + eps

    def lateral_stress(t):
        return law.stress(np.diag([s] + [t] * (d - 1))[None])[0, 1, 1]

    t = brentq(lateral_stress, 1 - 10 * eps, 1 + 10 * eps, xtol=1e-15)
    P11 = law.stress(np.diag([s] + [t] * (d - 1))[None])[0, 0, 0]
    modulus, ratio = (E, NU) if d == 3 else (E / (1 - NU**2), NU / (1 - NU))
    assert P11 / eps == pytest.approx(modulus, rel=1e-4)
    assert (1 - t) / eps == pytest.approx(ratio, rel=1e-4)


def test_stvk_large_uniaxial_stretch_closed_form():
    """StVK uniaxial: lateral Green strain = -nu E11 and S11 = E E11, so P11 = s E (s^2 - 1)/2."""
    law = StVenantKirchhoff(youngs_modulus=E, poisson_ratio=NU)

    def P(s, t):
        return law.stress(np.diag([s, t, t])[None])[0]

    for s in (0.7, 1.5, 2.0):
        t = brentq(lambda t, s=s: P(s, t)[1, 1], 0.1, 1.0 if s > 1 else 1.5, xtol=1e-14)
        assert t == pytest.approx(np.sqrt(1 - NU * (s**2 - 1)), rel=1e-10)
        assert P(s, t)[0, 0] == pytest.approx(s * E * (s**2 - 1) / 2, rel=1e-10)


def test_neo_hookean_large_uniaxial_stretch_closed_form():
    """NH uniaxial: mu t^2 = mu - lam ln(s t^2) fixes t; then P11 = mu (s - t^2/s)."""
    law = NeoHookean(youngs_modulus=E, poisson_ratio=NU)
    for s in (0.6, 1.5, 3.0):
        t = brentq(lambda t, s=s: MU * t**2 - MU + LAM * np.log(s * t**2), 0.05, 5.0, xtol=1e-14)
        P = law.stress(np.diag([s, t, t])[None])[0]
        assert abs(P[1, 1]) < 1e-9 * E
        assert P[0, 0] == pytest.approx(MU * (s - t**2 / s), rel=1e-10)


@pytest.mark.parametrize("d", DIMS)
def test_neo_hookean_inverted(d):
    law = NeoHookean(youngs_modulus=E, poisson_ratio=NU)
    F = np.array([np.eye(d)] * 4)
    F[1, 0, 0] = -1.0  # J = -1
    F[3, 0, 0] = 0.0  # J = 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        psi = law.energy_density(F)
    assert np.isinf(psi[[1, 3]]).all() and np.isfinite(psi[[0, 2]]).all()
    for order in (1, 2):
        with pytest.raises(InvertedElementError, match="neo_hookean") as info:
            law.evaluate(F, order)
        np.testing.assert_array_equal(info.value.indices, [1, 3])


def test_course_neo_hookean_is_finite_through_inversion():
    law = CourseNeoHookean(youngs_modulus=E, poisson_ratio=NU)
    F = np.array([np.diag([a, 1.0]) for a in np.linspace(-2.0, 2.0, 41)])
    res = law.evaluate(F)
    for arr in (res.energy, res.stress, res.tangent):
        assert np.isfinite(arr).all()


def test_fixed_corotated_rotation_of_inverted_and_degenerate_F():
    law = FixedCorotated(youngs_modulus=E, poisson_ratio=NU)
    for d in DIMS:
        F = _random_F(np.random.default_rng(d), 5, d, 0.8, jmin=-3.0, jmax=-0.2)
        F = np.concatenate([F, np.zeros((1, d, d))])
        res = law.evaluate(F)
        for arr in (res.energy, res.stress, res.tangent):
            assert np.isfinite(arr).all()


def test_bad_input_shapes_and_order():
    law = LinearElastic(youngs_modulus=E, poisson_ratio=NU)
    with pytest.raises(MaterialError, match="shape"):
        law.evaluate(np.eye(3))
    with pytest.raises(MaterialError, match="order"):
        law.evaluate(np.eye(3)[None], 3)


def test_repr_names_parameters():
    for cls in ALL:
        text = repr(cls(shear_modulus=2.0, lame_lambda=3.0))
        assert cls.__name__ in text and "shear_modulus=2.0" in text and "lame_lambda=3.0" in text
