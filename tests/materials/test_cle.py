"""FEBio's conewise linear elastic laws (``materials/orthotropic/cle.py``): energy, stress and
tangent against central differences along turned axes, FEBio's stress (S = sum_a mu_a sym(A_a E)
+ sum_ab lam_ab (A_a : E) A_b, the diagonal lam switching with the sign of A_a : E) by hand,
the cubic law as the orthotropic one with equal moduli, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material

ORTHO = dict(lp11=2.0, lm11=0.2, lp22=1.0, lm22=0.1, lp33=1.5, lm33=0.3, l12=0.1, l23=0.15,
             l31=0.05, mu1=0.2, mu2=0.1, mu3=0.3)  # fmt: skip
AXES = dict(mat_axis_a=[1.0, 1.0, 0.2], mat_axis_d=[-1.0, 1.0, 0.5])


@pytest.mark.parametrize(
    "law",
    [
        make_material("orthotropic CLE", **ORTHO, **AXES),
        make_material("cubic CLE", lp1=1.0, lm1=0.2, l2=0.1, mu=0.2, **AXES),
    ],
    ids=["orthotropic", "cubic"],
)
@pytest.mark.parametrize("d", [2, 3])
def test_stress_and_tangent_are_the_energys_derivatives(law, d):
    rng = np.random.default_rng(2)
    F = random_deformations(rng, 8, d, 0.25)
    res = law.evaluate(F, 2)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7


def test_stress_is_febios_by_hand():
    """FEBio's FEOrthotropicCLE::Stress, written out, at random F along turned axes."""
    law = make_material("orthotropic CLE", **ORTHO, **AXES)
    a = np.array(AXES["mat_axis_a"]) / np.linalg.norm(AXES["mat_axis_a"])
    e3 = np.cross(a, AXES["mat_axis_d"])
    e3 /= np.linalg.norm(e3)
    Q = np.stack([a, np.cross(e3, a), e3], axis=1)
    mu = [ORTHO["mu1"], ORTHO["mu2"], ORTHO["mu3"]]
    off = {(0, 1): "l12", (1, 2): "l23", (0, 2): "l31"}
    rng = np.random.default_rng(9)
    for F in random_deformations(rng, 5, 3, 0.3):
        E = 0.5 * (F.T @ F - np.eye(3))
        A = [np.outer(Q[:, i], Q[:, i]) for i in range(3)]
        AE = [np.sum(A[i] * E) for i in range(3)]
        lam = np.zeros((3, 3))
        for (i, j), key in off.items():
            lam[i, j] = lam[j, i] = ORTHO[key]
        for i, n in enumerate(("11", "22", "33")):
            lam[i, i] = ORTHO[f"lp{n}"] if AE[i] >= 0 else ORTHO[f"lm{n}"]
        S = sum(mu[i] * 0.5 * (A[i] @ E + (A[i] @ E).T) for i in range(3))
        S = S + sum(lam[i, j] * AE[i] * A[j] for i in range(3) for j in range(3))
        np.testing.assert_allclose(law.stress(F[None])[0], F @ S, atol=1e-13)


def test_cubic_is_the_orthotropic_law_with_equal_moduli():
    cubic = make_material("cubic CLE", lp1=1.0, lm1=0.2, l2=0.1, mu=0.2, **AXES)
    same = dict(lp11=1.0, lp22=1.0, lp33=1.0, lm11=0.2, lm22=0.2, lm33=0.2, l12=0.1, l23=0.1,
                l31=0.1, mu1=0.2, mu2=0.2, mu3=0.2)  # fmt: skip
    ortho = make_material("orthotropic CLE", **same, **AXES)
    F = random_deformations(np.random.default_rng(4), 6, 3, 0.3)
    np.testing.assert_allclose(cubic.evaluate(F, 2).tangent, ortho.evaluate(F, 2).tangent)


def test_refusals():
    with pytest.raises(MaterialError, match="not positive definite"):
        make_material("cubic CLE", lp1=1.0, lm1=-5.0, l2=0.1, mu=0.2)
    with pytest.raises(MaterialError, match="lp1"):
        make_material("cubic CLE", lm1=0.2, l2=0.1, mu=0.2)
