"""FEBio's muscle material (``materials/muscle.py``): energy, stress and tangent against central
differences (passive and active, near the rest state where acosh's series is used), FEBio's
DevStress (``FEMuscleMaterial::DevStress`` written out) plus the bulk pressure, the fibre
function's integral, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material

P = dict(g1=500.0, g2=400.0, g3=100.0, p1=0.05, p2=6.6, Lofl=1.1, smax=3e5, lam_max=1.4,
         activation=0.3, k=1e5, fiber=[1.0, 0.5, 0.2])  # fmt: skip


def _febio_dev_stress(F: np.ndarray) -> np.ndarray:
    """FEBio's FEMuscleMaterial::DevStress as it is written (its pressure added apart)."""
    J = np.linalg.det(F)
    a0 = np.array(P["fiber"]) / np.linalg.norm(P["fiber"])
    a = F @ a0
    la = np.linalg.norm(a)
    a = a / la
    lat = la * J ** (-1 / 3)
    B = J ** (-2 / 3) * F @ F.T
    Ba = B @ a
    I1, I4 = np.trace(B), lat * lat
    I5 = I4 * (a @ Ba)
    w = 0.5 * (I1 * I4 - I5) / np.sqrt(I4)
    beta = 1.0
    if w > 1.0001:
        beta = np.arccosh(w) / np.sqrt(w * w - 1)
    G1, G2, G3 = P["g1"], P["g2"], P["g3"]
    L, lm, P1, P2 = P["Lofl"], P["lam_max"], P["p1"], P["p2"]
    F1D4, F1D5 = -2 * G1 * I5 / I4**3, G1 / I4**2
    F2D1 = G2 * beta * lat
    F2D4 = G2 * beta * (I1 * I4 + I5) * 0.5 * I4**-1.5
    F2D5 = -G2 * beta / lat
    F3D4 = 9 * G3 * 0.125 * np.log(I4) / I4
    if lat <= L:
        Fp = 0.0
    elif lat < lm:
        Fp = P1 * (np.exp(P2 * (lat / L - 1)) - 1)
    else:
        P3 = P1 * P2 * np.exp(P2 * (lm / L - 1))
        Fp = P3 * lat / L + P1 * (np.exp(P2 * (lm / L - 1)) - 1) - P3 * lm / L
    y = lat / L
    Fa = 0.0
    if 0.4 < y < 1.6:
        Fa = (
            9 * (y - 0.4) ** 2
            if y <= 0.6
            else 9 * (y - 1.6) ** 2
            if y >= 1.4
            else 1 - 4 * (1 - y) ** 2
        )
    FfD4 = 0.5 * P["smax"] * (Fp + P["activation"] * Fa) / L / lat
    W1, W4, W5 = F2D1, F1D4 + F2D4 + F3D4 + FfD4, F1D5 + F2D5
    T = B * W1 + np.outer(a, a) * I4 * W4 + (np.outer(a, Ba) + np.outer(Ba, a)) * I4 * W5
    return (T - np.trace(T) / 3 * np.eye(3)) * 2 / J


@pytest.mark.parametrize("spread", [0.02, 0.2])
@pytest.mark.parametrize("activation", [0.0, 0.3])
def test_stress_and_tangent_are_the_energys_derivatives(spread, activation):
    law = make_material("muscle material", **{**P, "activation": activation})
    F = random_deformations(np.random.default_rng(1), 8, 3, spread)
    res = law.evaluate(F, 2)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-6


def test_deviatoric_stress_is_febios():
    law = make_material("muscle material", **P)
    for F in random_deformations(np.random.default_rng(2), 6, 3, 0.2):
        J = np.linalg.det(F)
        sigma = law.stress(F[None])[0] @ F.T / J
        p = P["k"] * np.log(J) / J  # FEBio's default bulk term k/2 (ln J)^2
        want = _febio_dev_stress(F) + p * np.eye(3)
        np.testing.assert_allclose(sigma, want, atol=1e-9 * np.abs(want).max())


@pytest.mark.parametrize("lam_max", [1.4, 1.1])  # 1.1 = Lofl: no exponential part (FEBio's mu02)
def test_fibre_function_is_its_derivatives_integral(lam_max):
    law = make_material("muscle material", **{**P, "lam_max": lam_max})
    lam = np.linspace(0.3, 2.0, 41)
    f, df, ddf = law.fibre(lam)
    h = 1e-6
    np.testing.assert_allclose((law.fibre(lam + h)[0] - law.fibre(lam - h)[0]) / (2 * h), df,
                               atol=1e-6 * np.abs(df).max())  # fmt: skip
    np.testing.assert_allclose((law.fibre(lam + h)[1] - law.fibre(lam - h)[1]) / (2 * h), ddf,
                               atol=1e-5 * np.abs(ddf).max())  # fmt: skip


def test_refusals():
    with pytest.raises(MaterialError, match="lam_max must be >= Lofl"):
        make_material("muscle material", **{**P, "lam_max": 1.0})
    with pytest.raises(MaterialError, match="3D only"):
        make_material("muscle material", **P).stress(np.eye(2)[None])
