"""FEBio's Shenoy material (``materials/shenoy.py``): energy, stress and tangent against central
differences (the fibre term on every branch), FEBio's Cauchy stress (``FEShenoyMaterial::
Stress``: the matrix and 1/J sum_a lambda_a fiberStress(lambda_a) n_a n_a) by hand, the fibre
function's branches and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material

P = dict(mu=0.77, k=1.67, Ef=134.6, lam_c=1.02, lam_t=0.255, n=5, m=3)


def _fiber_stress(lam: float) -> float:
    """FEBio's FEShenoyMaterial::fiberStress as it is written."""
    l1, l2 = P["lam_c"] - P["lam_t"] / 2, P["lam_c"] + P["lam_t"] / 2
    n, m, Ef = P["n"], P["m"], P["Ef"]
    if lam < l1:
        return 0.0
    if lam > l2:
        return Ef * ((l2 - l1) / (n + 1) + ((1 + lam - l2) ** (m + 1) - 1) / (m + 1))
    return Ef * ((lam - l1) / (l2 - l1)) ** n * (lam - l1) / (n + 1)


@pytest.mark.parametrize("spread", [0.05, 0.15, 0.3])
def test_stress_and_tangent_are_the_energys_derivatives(spread):
    law = make_material("Shenoy", **P)
    F = random_deformations(np.random.default_rng(6), 8, 3, spread)
    res = law.evaluate(F, 2)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7


def test_cauchy_stress_is_febios():
    law = make_material("Shenoy", **P)
    for F in random_deformations(np.random.default_rng(1), 5, 3, 0.2):
        J = np.linalg.det(F)
        B = F @ F.T
        Bbar = B * J ** (-2 / 3)
        sigma = P["mu"] / J * (Bbar - np.trace(Bbar) / 3 * np.eye(3)) + P["k"] * (J - 1) * np.eye(3)
        lam2, n = np.linalg.eigh(B)
        for la, na in zip(np.sqrt(lam2), n.T, strict=True):
            sigma += np.outer(na, na) * _fiber_stress(la) * la / J
        got = law.stress(F[None])[0] @ F.T / J
        np.testing.assert_allclose(got, sigma, atol=1e-10 * np.abs(sigma).max())


def test_at_rest_and_at_equal_stretches():
    """F = I with slack fibres (lam_c = 1.2): no stress; an equibiaxial F (two equal
    eigenvalues, the divided differences' limit) has a finite, symmetric tangent, the
    stress's derivative."""
    law = make_material("Shenoy", **{**P, "lam_c": 1.2})  # slack fibres at rest
    res = law.evaluate(np.eye(3)[None], 2)
    np.testing.assert_allclose(res.stress, 0.0, atol=1e-14)
    F = np.diag([1.3, 1.3, 0.9])[None]
    A = law.evaluate(F, 2).tangent.reshape(9, 9)
    assert np.isfinite(A).all()
    np.testing.assert_allclose(A, A.T, atol=1e-9 * np.abs(A).max())
    fd = central_difference(law.stress, F, 1e-6).reshape(9, 9)
    np.testing.assert_allclose(A, fd, atol=1e-6 * np.abs(A).max())


def test_refusals():
    with pytest.raises(MaterialError, match="lam_c >= 1"):
        make_material("Shenoy", **{**P, "lam_c": 0.9})
    with pytest.raises(MaterialError, match="n and m"):
        make_material("Shenoy", **{**P, "m": 0.5})
    with pytest.raises(MaterialError, match="3D only"):
        make_material("Shenoy", **P).stress(np.eye(2)[None])
