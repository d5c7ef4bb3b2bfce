"""FEBio's 2D trans iso Mooney-Rivlin (``materials/fibres/trans_iso_2d_mooney_rivlin.py``): energy,
stress and tangent against central finite differences, the fibres of the plane normal to the
axis in an equibiaxial stretch of that plane against the closed form (each fibre at the same
stretch: the matrix plus f(lam^2)), FEBio's rotation of x onto the axis, the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.fibres.trans_iso_2d_mooney_rivlin import rotation_from_x

PARAMS = dict(c1=1.0, c2=0.3, k=50.0, c3=8.0, c4=5.0, c5=30.0, lam_max=1.2)


@pytest.mark.parametrize("w", [(1.0, 1.0), (3.0, 1.0)])
def test_derivatives_are_consistent(w):
    law = make_material("2D trans iso Mooney-Rivlin", **PARAMS, w=list(w), fiber=[0.3, 0.4, 1.0])
    F = random_deformations(np.random.default_rng(11), 6, 3, 0.2)
    res = law.evaluate(F)
    dW = central_difference(lambda G: law.evaluate(G, 0).energy, F, 1e-6)
    dP = central_difference(lambda G: law.evaluate(G, 1).stress, F, 1e-6)
    assert relative_difference(res.stress, dW) < 1e-7
    assert relative_difference(res.tangent, dP) < 1e-6


@pytest.mark.parametrize("axis", [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
def test_equibiaxial_stretch_of_the_fibre_plane(axis):
    """Stretch lam in the plane normal to the axis, 1/lam^2 along it (J = 1): every fibre has
    I4 = lam^2, so W = c1 (I1 - 3) + c2 (I2 - 3) + f(lam^2) whatever the weights."""
    lam = 1.1
    r = np.array(axis) / np.linalg.norm(axis)
    R = rotation_from_x(r[None])[0]
    F = R @ np.diag([lam**-2, lam, lam]) @ R.T
    law = make_material("2D trans iso Mooney-Rivlin", **PARAMS, w=[2.0, 1.0], fiber=axis)
    fibre = make_material("fiber_exp_linear_uncoupled", c3=8.0, c4=5.0, c5=30.0, lam_max=1.2)
    I1, I2 = lam**-4 + 2 * lam**2, 2 * lam**-2 + lam**4
    f = fibre.fibre(np.array([lam**2]), 0)[0][0]
    expected = PARAMS["c1"] * (I1 - 3) + PARAMS["c2"] * (I2 - 3) + f
    assert f > 0.0
    assert law.evaluate(F[None], 0).energy[0] == pytest.approx(expected, rel=1e-12)
    np.testing.assert_allclose(R[:, 0], r, atol=1e-15)  # x taken onto the axis
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-15)


def test_refusals():
    with pytest.raises(MaterialError, match="active_contraction"):
        make_material("2D trans iso Mooney-Rivlin", **PARAMS, active_contraction=1.0)
    with pytest.raises(MaterialError, match="along -x"):
        make_material("2D trans iso Mooney-Rivlin", **PARAMS, fiber=[-1.0, 0.0, 0.0])
    with pytest.raises(MaterialError, match="w must be two numbers"):
        make_material("2D trans iso Mooney-Rivlin", **PARAMS, w=[1.0, 0.0])
