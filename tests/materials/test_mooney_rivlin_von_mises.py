"""FEBio's Mooney-Rivlin von Mises Fibers (``materials/fibres/mooney_rivlin_von_mises.py``):
energy, stress and tangent against central finite differences, the von Mises densities'
integrals over the half circle by the rule against 1 and against SciPy's quad, the equibiaxial
stretch of the fibre plane against the closed form, the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import i0, i1
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.fibres.mooney_rivlin_von_mises import von_mises_rule

PARAMS = dict(c1=1.0, c2=0.2, k=100.0, c3=5.0, c4=5.0, c5=40.0, lam_max=1.2)


@pytest.mark.parametrize("vmc", [1, 2])
def test_derivatives_are_consistent(vmc):
    law = make_material("Mooney-Rivlin von Mises Fibers", **PARAMS, kf=5.0, tp=0.4, gipt=20,
                        vmc=vmc, var_n=2.0, mat_axis_a=[1, 1, 0], mat_axis_d=[0, 0, 1])  # fmt: skip
    F = random_deformations(np.random.default_rng(13), 6, 3, 0.2)
    res = law.evaluate(F)
    dW = central_difference(lambda G: law.evaluate(G, 0).energy, F, 1e-6)
    dP = central_difference(lambda G: law.evaluate(G, 1).stress, F, 1e-6)
    assert relative_difference(res.stress, dW) < 1e-7
    assert relative_difference(res.tangent, dP) < 1e-6


@pytest.mark.parametrize(("kf", "vmc"), [(0.0, 1), (20.0, 1), (20.0, 2), (3.0, 2)])
def test_the_rule_integrates_the_density(kf, vmc):
    """Both densities integrate to 1 over the half circle; the rule's moment of cos^2 (t - 0.3)
    against quad's (40 points: to 1e-6 for the sharp kf = 20)."""
    tp, n = 0.7, 2.0
    t, c = von_mises_rule(kf, tp, 40, vmc, n)
    tol = 1e-6 if kf > 10 else 1e-10
    assert c.sum() == pytest.approx(1.0, rel=tol)
    b = (i1(kf) / i0(kf)) ** n if vmc == 2 else 1.0

    def density(s):
        return (1 - b) / np.pi + b * np.exp(kf * np.cos(2 * (s - tp))) / (np.pi * i0(kf))

    exact = quad(lambda s: density(s) * np.cos(s - 0.3) ** 2, tp - np.pi / 2, tp + np.pi / 2,
                 epsabs=0, epsrel=1e-13)[0]  # fmt: skip
    assert np.dot(c, np.cos(t - 0.3) ** 2) == pytest.approx(exact, rel=tol)


def test_equibiaxial_stretch_of_the_fibre_plane():
    """Stretch lam in the e1-e2 plane (a = (1, 1, 0), d = (-1, 1, 0): e3 = z), 1/lam^2 along
    e3: every fibre at I4 = lam^2, so W = c1 (I1 - 3) + c2 (I2 - 3) + f(lam^2) (the density
    integrates to 1: to the rule's 1e-7 for this sharp kf = 20)."""
    lam = 1.1
    law = make_material("Mooney-Rivlin von Mises Fibers", **PARAMS, kf=20.0, tp=0.785398163,
                        gipt=40, vmc=2, var_n=2.0, mat_axis_a=[1, 1, 0],
                        mat_axis_d=[-1, 1, 0])  # fmt: skip
    F = np.diag([lam, lam, lam**-2])[None]
    fibre = make_material("fiber_exp_linear_uncoupled", c3=5.0, c4=5.0, c5=40.0, lam_max=1.2)
    f = fibre.fibre(np.array([lam**2]), 0)[0][0]
    I1, I2 = 2 * lam**2 + lam**-4, lam**4 + 2 * lam**-2
    expected = PARAMS["c1"] * (I1 - 3) + PARAMS["c2"] * (I2 - 3) + f
    assert f > 0.0
    assert law.evaluate(F, 0).energy[0] == pytest.approx(expected, rel=1e-7)


def test_refusals():
    with pytest.raises(MaterialError, match="gipt must be a multiple of 10"):
        make_material("Mooney-Rivlin von Mises Fibers", **PARAMS, gipt=15)
    with pytest.raises(MaterialError, match="vmc must be 1"):
        make_material("Mooney-Rivlin von Mises Fibers", **PARAMS, vmc=3)
