"""Homogeneous uniaxial, equibiaxial and simple-shear stresses of the soft-tissue laws against
closed forms worked out by hand from the principal stretches (1e-8 relative).

Incompressible (J = 1, the pressure eliminated through the traction-free faces), with
W1 = dW/dI1, W2 = dW/dI2 of each law written out below:

    uniaxial     F = diag(l, l^-1/2, l^-1/2)   P = 2 (l - l^-2) (W1 + W2 / l)
    equibiaxial  F = diag(l, l, l^-2)          P = 2 (l - l^-5) (W1 + l^2 W2)
    shear        F = I + g e1 (x) e2           P12 = 2 g (W1 + W2),  I1 = I2 = 3 + g^2
    Ogden        uniaxial  sum c/m (l^(m-1) - l^(-m/2-1)); equibiaxial sum c/m (l^(m-1) -
                 l^(-2m-1)); shear sum c/m (L^m - L^-m) / (L + 1/L), L = g/2 + sqrt(1 + g^2/4)

Compressible, F = R diag(l1, l2, l3) R'^T: P = R diag(dW/dl_a) R'^T with dW/dl_a by the chain
rule through I1 = sum l^2, I2 = sum_{a<b} l_a^2 l_b^2, J = l1 l2 l3 (isochoric: I1b = J^-2/3 I1,
I2b = J^-4/3 I2), or through the stretches themselves (Ogden).
"""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.materials import make_material

A = (0.5, 0.1, 11 / 350, 19 / 1750, 519 / 134750)  # FEBio's Arruda-Boyce coefficients


def mr_w(p, I1, I2):
    return p["c1"] + 0 * I1, p["c2"] + 0 * I1


def yeoh_w(p, I1, I2):
    c = [p.get(f"c{i}", 0.0) for i in range(1, 7)]
    x = I1 - 3
    return sum(i * c[i - 1] * x ** (i - 1) for i in range(1, 7)), 0 * I1


def vw_w(p, I1, I2):
    c1, c2 = p["c1"], p["c2"]
    return c1 * c2 * np.exp(c2 * (I1 - 3)), -c1 * c2 / 2 + 0 * I1


def ab_w(p, I1, I2):
    # d/dI1 of mu [(I1 - 3)/2 + (I1^2 - 9)/(10 N) + 11 (I1^3 - 27)/(350 N^2)
    #              + 19 (I1^4 - 81)/(1750 N^3) + 519 (I1^5 - 243)/(134750 N^4)]
    mu, N = p["mu"], p["N"]
    w1 = mu * (
        0.5
        + I1 / (5 * N)
        + 33 * I1**2 / (350 * N**2)
        + 76 * I1**3 / (1750 * N**3)
        + 2595 * I1**4 / (134750 * N**4)
    )
    return w1, 0 * I1


AB_W1_REST = ab_w({"mu": 300.0, "N": 4.0}, 3.0, 3.0)[0]
INVARIANT_LAWS = {
    # name: (parameters, W1/W2 of the law, coefficient s of -s ln J in the coupled form or None)
    "mooney_rivlin": (dict(c1=150.0, c2=40.0, k=3000.0), mr_w, None),
    "coupled_mooney_rivlin": (dict(c1=150.0, c2=40.0, k=3000.0), mr_w, 2 * (150 + 80)),
    "yeoh": (dict(c1=150.0, c2=30.0, c3=5.0, k=3000.0), yeoh_w, None),
    "coupled_yeoh": (dict(c1=150.0, c2=30.0, c3=5.0, k=3000.0), yeoh_w, 2 * 150.0),
    "veronda_westmann": (dict(c1=200.0, c2=1.5, k=3000.0), vw_w, None),
    "coupled_veronda_westmann": (dict(c1=200.0, c2=1.5, k=3000.0), vw_w, 0.0),
    "arruda_boyce": (dict(mu=300.0, N=4.0, k=3000.0), ab_w, None),
    "coupled_arruda_boyce": (dict(mu=300.0, N=4.0, k=3000.0), ab_w, 2 * AB_W1_REST),
}
OGDEN = dict(c=[300.0, -40.0, 20.0], m=[4.0, -2.0, 9.0])
STRETCHES = np.array([0.6, 0.85, 0.999, 1.0001, 1.2, 1.6, 2.1])
SHEARS = np.array([-0.7, 0.01, 0.3, 1.0, 1.8])


def _assert_rel(actual, expected, what):
    err = np.max(np.abs(actual - expected) / np.maximum(np.abs(expected), 1e-300))
    assert err < 1e-8, (what, err)


def _uniaxial(law, l):
    t = l**-0.5
    F = np.zeros((l.size, 3, 3))
    F[:, 0, 0], F[:, 1, 1], F[:, 2, 2] = l, t, t
    P = law.stress(F)
    return P[:, 0, 0] - P[:, 1, 1] * t / l


def _equibiaxial(law, l):
    t = l**-2.0
    F = np.zeros((l.size, 3, 3))
    F[:, 0, 0], F[:, 1, 1], F[:, 2, 2] = l, l, t
    P = law.stress(F)
    return P[:, 0, 0] - P[:, 2, 2] * t / l


def _shear(law, g, d=3):
    F = np.broadcast_to(np.eye(d), (g.size, d, d)).copy()
    F[:, 0, 1] = g
    return law.stress(F)[:, 0, 1]


@pytest.mark.parametrize("name", sorted(INVARIANT_LAWS))
def test_invariant_laws_incompressible_closed_forms(name):
    params, w, _ = INVARIANT_LAWS[name]
    law = make_material(name, **params)
    l, g = STRETCHES, SHEARS
    W1, W2 = w(params, l**2 + 2 / l, 2 * l + l**-2)
    _assert_rel(_uniaxial(law, l), 2 * (l - l**-2) * (W1 + W2 / l), "uniaxial")
    W1, W2 = w(params, 2 * l**2 + l**-4, l**4 + 2 * l**-2)
    _assert_rel(_equibiaxial(law, l), 2 * (l - l**-5) * (W1 + l**2 * W2), "equibiaxial")
    W1, W2 = w(params, 3 + g**2, 3 + g**2)
    for d in (2, 3):
        _assert_rel(_shear(law, g, d), 2 * g * (W1 + W2), f"shear {d}D")


def _ogden_terms():
    return zip(OGDEN["c"], OGDEN["m"], strict=True)


@pytest.mark.parametrize("name", ["ogden", "ogden_unconstrained"])
def test_ogden_incompressible_closed_forms(name):
    bulk = {"k": 3000.0} if name == "ogden" else {"cp": 3000.0}
    law = make_material(name, **OGDEN, **bulk)
    l, g = STRETCHES, SHEARS
    uni = sum(c / m * (l ** (m - 1) - l ** (-m / 2 - 1)) for c, m in _ogden_terms())
    _assert_rel(_uniaxial(law, l), uni, "uniaxial")
    bi = sum(c / m * (l ** (m - 1) - l ** (-2 * m - 1)) for c, m in _ogden_terms())
    _assert_rel(_equibiaxial(law, l), bi, "equibiaxial")
    L = g / 2 + np.sqrt(1 + g**2 / 4)
    tau = sum(c / m * (L**m - L**-m) / (L + 1 / L) for c, m in _ogden_terms())
    for d in (2, 3):
        _assert_rel(_shear(law, g, d), tau, f"shear {d}D")


def _principal_cases():
    rng = np.random.default_rng(11)
    lams = np.array([[1.3, 0.8, 1.1], [0.7, 0.7, 1.25], [1.5, 1.5, 1.5], [0.9, 1.2, 0.6]])
    R, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    S, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    return lams, R, S


def _check_principal(law, lams, dW):
    """P(R diag(l) S^T) = R diag(dW/dl) S^T for each row of stretches."""
    _, R, S = _principal_cases()
    F = np.einsum("ia,qa,ja->qij", R, lams, S)
    expected = np.einsum("ia,qa,ja->qij", R, dW, S)
    err = np.abs(law.stress(F) - expected).max() / np.abs(dW).max()
    assert err < 1e-10, (law.name, err)


@pytest.mark.parametrize("name", sorted(INVARIANT_LAWS))
def test_invariant_laws_compressible_principal_stresses(name):
    params, w, s = INVARIANT_LAWS[name]
    law = make_material(name, **params)
    k = params["k"]
    lams, _, _ = _principal_cases()
    J = lams.prod(axis=1)[:, None]
    I1 = (lams**2).sum(axis=1)[:, None]
    I2 = (lams[:, [0]] * lams[:, [1]]) ** 2 + (lams[:, [1]] * lams[:, [2]]) ** 2
    I2 = I2 + (lams[:, [0]] * lams[:, [2]]) ** 2
    dI1 = 2 * lams
    dI2 = 2 * lams * (I1 - lams**2)
    if s is None:  # uncoupled: W(I1b, I2b) + k/2 ln^2 J
        W1, W2 = w(params, J ** (-2 / 3) * I1, J ** (-4 / 3) * I2)
        dI1b = J ** (-2 / 3) * (dI1 - 2 / 3 * I1 / lams)
        dI2b = J ** (-4 / 3) * (dI2 - 4 / 3 * I2 / lams)
        dW = W1 * dI1b + W2 * dI2b + k * np.log(J) / lams
    else:  # coupled: W(I1, I2) - s ln J + k/2 ln^2 J
        W1, W2 = w(params, I1, I2)
        dW = W1 * dI1 + W2 * dI2 + (k * np.log(J) - s) / lams
    _check_principal(law, lams, dW)


def test_ogden_compressible_principal_stresses():
    lams, _, _ = _principal_cases()
    J = lams.prod(axis=1)[:, None]
    k = 3000.0
    # ogden: sum c/m^2 (sum_b lb_b^m - 3) + k/2 ln^2 J, lb = J^-1/3 l;
    # d lb_b / d l_a = J^-1/3 (delta_ab - l_b / (3 l_a))
    lb = J ** (-1 / 3) * lams
    dW = k * np.log(J) / lams
    for c, m in _ogden_terms():
        dW = dW + c / m * (lb**m - (lb**m).sum(axis=1, keepdims=True) / 3) / lams
    _check_principal(make_material("ogden", **OGDEN, k=k), lams, dW)
    # ogden_unconstrained: sum c/m^2 (sum l^m - 3 - m ln J) + cp/2 (J - 1)^2
    dW = k * (J - 1) * J / lams
    for c, m in _ogden_terms():
        dW = dW + c / m * (lams ** (m - 1) - 1 / lams)
    _check_principal(make_material("ogden_unconstrained", **OGDEN, cp=k), lams, dW)


def test_closed_form_check_can_fail():
    """A law with other parameters misses the closed form: the comparisons are sharp."""
    params, w, _ = INVARIANT_LAWS["mooney_rivlin"]
    law = make_material("mooney_rivlin", **{**params, "c2": params["c2"] * (1 + 1e-6)})
    l = STRETCHES
    W1, W2 = w(params, l**2 + 2 / l, 2 * l + l**-2)
    with pytest.raises(AssertionError):
        _assert_rel(_uniaxial(law, l), 2 * (l - l**-2) * (W1 + W2 / l), "uniaxial")
