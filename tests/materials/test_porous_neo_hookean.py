"""FEBio's porous neo-Hookean (``materials/porous_neo_hookean.py``): energy, stress and tangent
against central differences (3D and plane strain), FEBio's Cauchy stress
(``FEPorousNeoHookean::Stress`` written out), the small-strain moduli, the pores closing
(J -> phi0: an infinite energy) and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import InvertedElementError, MaterialError
from tissuesim.materials import make_material


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("phi0", [0.0, 0.3])
def test_stress_and_tangent_are_the_energys_derivatives(d, phi0):
    law = make_material("porous neo-Hookean", E=3.0, phi0=phi0)
    F = random_deformations(np.random.default_rng(8), 6, d, 0.2, jmin=0.6)
    res = law.evaluate(F, 2)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7


def test_cauchy_stress_is_febios():
    E, phi = 3.0, 0.3
    law = make_material("porous neo-Hookean", E=E, phi0=phi)
    mu = E / 3 * (1 + 0.5 * (1 - phi) ** 2)
    for F in random_deformations(np.random.default_rng(3), 5, 3, 0.25, jmin=0.6):
        J = np.linalg.det(F)
        b = F @ F.T
        R = ((J - phi) / (1 - phi) / J) ** (2 / 3)
        mu1 = mu / J
        sigma = b * mu1 * R + np.eye(3) * (mu1 * (phi * R * np.trace(b) / 3 - J)) / (J - phi)
        got = law.stress(F[None])[0] @ F.T / J
        np.testing.assert_allclose(got, sigma, atol=1e-13)


def test_small_strain_moduli_and_closing_pores():
    law = make_material("porous neo-Hookean", E=3.0, phi0=0.2)
    e = 1e-7
    P = law.stress((1 + e) * np.eye(3)[None])[0]
    assert P[0, 0] / e == pytest.approx(2 * law.mu + 3 * law.lam, rel=1e-6)
    shear = np.eye(3) + e * np.eye(3)[[1, 0, 2]] * [[0, 1, 0], [1, 0, 0], [0, 0, 0]]
    assert law.stress(shear[None])[0, 0, 1] / e == pytest.approx(2 * law.mu, rel=1e-6)
    closed = np.diag([0.2, 1.0, 1.0])[None]  # J = phi0: the pores are shut
    assert np.isinf(law.energy_density(closed)[0])
    with pytest.raises(InvertedElementError):
        law.stress(closed)


def test_refusals():
    with pytest.raises(MaterialError, match="phi0 must be in"):
        make_material("porous neo-Hookean", E=1.0, phi0=1.0)
    with pytest.raises(MaterialError, match="E"):
        make_material("porous neo-Hookean", E=-1.0, phi0=0.1)
