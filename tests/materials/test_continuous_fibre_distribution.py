"""FEBio's continuous fibre distribution (``materials/fibres/continuous_distribution.py``,
``fibre_distribution.py``): the derived Gauss-Kronrod rule against the integrals of
polynomials, the energy, stress and tangent against central finite differences (exact for the
fixed points of a scheme, to the quadrature's accuracy for the adaptive Gauss-Kronrod one), the
distribution's normalisation and the energy of a stretched isotropic (spherical) distribution
against the integrals done by SciPy's quad, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.fibres.continuous_distribution import fibre_sum
from tissuesim.materials.fibres.fibre_distribution import gauss_kronrod, make_distribution

FIBRE = {"model": "fiber_exp_pow", "ksi": 5.0, "alpha": 2.0, "beta": 2.5}
FIBRE_UC = {**FIBRE, "model": "fiber_exp_pow_uncoupled"}
GKT = {"model": "fibers_3d_gkt", "nph": 11, "nth": 31}
TRAP = {"model": "fibers_2d_trapezoidal", "nth": 31}


@pytest.mark.parametrize("npoints", [7, 11, 15, 19, 23, 27])
def test_gauss_kronrod_rule_integrates_polynomials_to_degree_3m_plus_1(npoints):
    """The 2m+1 points hold the m Gauss-Legendre nodes and integrate x^k exactly, k <= 3m+1
    (2/(k+1) for even k, 0 for odd); FEBio's 12-digit table agrees (its 11-point rule's first
    Kronrod node 0.984085360095)."""
    x, w = gauss_kronrod(npoints)
    m = (npoints - 1) // 2
    gauss = np.polynomial.legendre.leggauss(m)[0]
    assert np.min(np.abs(x[:, None] - gauss[None]), axis=0).max() < 1e-14
    for k in range(3 * m + 2):
        exact = 2.0 / (k + 1) if k % 2 == 0 else 0.0
        assert np.dot(w, x**k) == pytest.approx(exact, abs=1e-13)
    assert np.all(w > 0.0)
    if npoints == 11:
        assert x[-1] == pytest.approx(0.984085360095, abs=1e-12)


@pytest.mark.parametrize("uncoupled", [False, True])
def test_fibre_sum_stress_and_tangent_are_the_energys_derivatives(uncoupled):
    """W = sum c_k f(I4_k) (uncoupled: f(J^(-2/3) I4_k)) over fixed random directions: P and
    dP/dF against central differences of W and P."""
    rng = np.random.default_rng(3)
    law = make_material(**(FIBRE_UC if uncoupled else FIBRE), fiber=[1, 0, 0])
    a = rng.standard_normal((1, 40, 3))
    a /= np.linalg.norm(a, axis=-1, keepdims=True)
    c = rng.uniform(0.1, 1.0, (1, 40))
    F = random_deformations(rng, 6, 3, 0.25)
    res = fibre_sum(law, F, a, c, uncoupled, 2)
    assert np.all(res.energy > 0.0)
    dW = central_difference(lambda G: fibre_sum(law, G, a, c, uncoupled, 0).energy, F, 1e-6)
    dP = central_difference(lambda G: fibre_sum(law, G, a, c, uncoupled, 1).stress, F, 1e-6)
    assert relative_difference(res.stress, dW) < 1e-7
    assert relative_difference(res.tangent, dP) < 1e-6


@pytest.mark.parametrize("uncoupled", [False, True])
@pytest.mark.parametrize(
    "distribution",
    [{"model": "elliptical", "spa1": 5.0, "spa2": 1.0}, {"model": "von_mises_2d", "b": 3.0}],
)
def test_planar_distribution_is_consistent_in_turned_axes(uncoupled, distribution):
    """The 2D trapezoidal scheme's points are fixed: W, P and A consistent to round-off, in
    local axes turned by mat_axis (a = (1, 1, 0), d = (0, 0, 1))."""
    law = make_material(
        "continuous_fiber_distribution" + ("_uncoupled" if uncoupled else ""),
        fibers=FIBRE_UC if uncoupled else FIBRE,
        distribution=distribution,
        scheme=TRAP,
        mat_axis_a=[1, 1, 0],
        mat_axis_d=[0, 0, 1],
    )
    F = random_deformations(np.random.default_rng(5), 6, 3, 0.25)
    res = law.evaluate(F)
    dW = central_difference(lambda G: law.evaluate(G, 0).energy, F, 1e-6)
    dP = central_difference(lambda G: law.evaluate(G, 1).stress, F, 1e-6)
    assert relative_difference(res.stress, dW) < 1e-7
    assert relative_difference(res.tangent, dP) < 1e-6


@pytest.mark.parametrize("uncoupled", [False, True])
def test_adaptive_gauss_kronrod_is_consistent_to_its_accuracy(uncoupled):
    """fibers-3d-gkt moves its points with C (the stretched cap only), as FEBio's; in the
    global axes its stress is the energy's derivative to the quadrature's accuracy, and its
    tangent (points held) the stress's."""
    law = make_material(
        "continuous_fiber_distribution" + ("_uncoupled" if uncoupled else ""),
        fibers=FIBRE_UC if uncoupled else FIBRE,
        distribution={"model": "von_mises_3d", "b": 3.0},
        scheme=GKT,
    )
    F = random_deformations(np.random.default_rng(7), 6, 3, 0.2)
    res = law.evaluate(F)
    dW = central_difference(lambda G: law.evaluate(G, 0).energy, F, 1e-6)
    dP = central_difference(lambda G: law.evaluate(G, 1).stress, F, 1e-6)
    assert relative_difference(res.stress, dW) < 1e-5
    assert relative_difference(res.tangent, dP) < 2e-4


def _uniaxial(lam: float) -> np.ndarray:
    return np.diag([lam, lam**-0.5, lam**-0.5])[None]


@pytest.mark.parametrize("lam", [1.2, 0.85])
def test_spherical_distribution_energy_is_the_sphere_average(lam):
    """Isotropic (spherical) fibres in isochoric uniaxial stretch lam: W is the average over
    the sphere of f(I4), I4 = lam^2 x^2 + (1 - x^2) / lam, x the cosine to the stretch, i.e.
    1/2 of its integral over x in [-1, 1] (by quad, split where I4 = 1); the adaptive rule
    integrates the stretched cap only (lam > 1: around the axis; lam < 1: the waist)."""
    fibre = make_material(**FIBRE, fiber=[1, 0, 0])
    law = make_material(
        "continuous_fiber_distribution",
        fibers=FIBRE,
        distribution={"model": "spherical"},
        scheme=GKT,
    )

    def f(x):
        return fibre.fibre(np.array([lam**2 * x * x + (1 - x * x) / lam]), 0)[0][0]

    x0 = np.sqrt((1 / lam - 1) / (1 / lam - lam**2))  # I4 = 1
    exact = quad(f, 0.0, x0, epsabs=0, epsrel=1e-13)[0]
    exact += quad(f, x0, 1.0, epsabs=0, epsrel=1e-13)[0]
    assert exact > 0.0
    assert law.evaluate(_uniaxial(lam), 0).energy[0] == pytest.approx(exact, rel=1e-7)


@pytest.mark.parametrize("b", [0.3, 3.0, 30.0])
def test_von_mises_normalisation_is_the_schemes_integral(b):
    """FEBio divides by the scheme's integral of R: with exp(b (2 x^2 - 1)) over the sphere,
    2 pi int_-1^1 exp(b (2 x^2 - 1)) dx (quad); the 11 x 31 Gauss-Kronrod points get it to
    the rule's accuracy (b = 30: a sharp peak, 1e-2)."""
    law = make_material(
        "continuous_fiber_distribution",
        fibers=FIBRE,
        distribution={"model": "von_mises_3d", "b": b},
        scheme=GKT,
    )
    exact = 2 * np.pi * quad(lambda x: np.exp(b * (2 * x * x - 1)), -1, 1, epsrel=1e-13)[0]
    assert law.ifd == pytest.approx(exact, rel=1e-9 if b < 10 else 1e-2)


def test_refusals_name_the_part():
    base = dict(fibers=FIBRE, distribution={"model": "von_mises_3d", "b": 1.0}, scheme=GKT)
    with pytest.raises(MaterialError, match="needs a 2D scheme"):
        make_material("continuous_fiber_distribution", **{**base, "distribution": {
            "model": "elliptical", "spa1": 2.0, "spa2": 1.0}})  # fmt: skip
    with pytest.raises(MaterialError, match="fibers-3d-fei"):
        make_material("continuous_fiber_distribution", **{**base, "scheme": {
            "model": "fibers-3d-fei", "resolution": 196}})  # fmt: skip
    with pytest.raises(MaterialError, match="nph must be 7, 11"):
        make_material("continuous_fiber_distribution", **{**base, "scheme": {**GKT, "nph": 9}})
    with pytest.raises(MaterialError, match="uncoupled fibre law"):
        make_material("continuous_fiber_distribution_uncoupled", **base)
    with pytest.raises(MaterialError, match="mu > 0"):
        make_material("continuous_fiber_distribution", **{**base, "fibers": {**FIBRE, "mu": 1.0}})
    with pytest.raises(MaterialError, match="fibers-3d-gkt takes its points in the eigenvectors"):
        make_material("continuous_fiber_distribution", **base, mat_axis_a=[1, 1, 0],
                      mat_axis_d=[0, 0, 1])  # fmt: skip
    law = make_material("continuous_fiber_distribution", **base, mat_axis_a=[2, 0, 0])
    assert law.Q.shape == (1, 3, 3)  # the global axes, given: run
    with pytest.raises(MaterialError, match="b must be >= 0"):
        make_distribution({"model": "von_mises_3d", "b": -1.0})


def test_the_documented_components_build_and_pull():
    """docs/guide/materials.md's continuous distribution components, with a matrix, give a
    mixture whose stress along the Gauss-Kronrod family's x exceeds the matrix's."""
    import tomllib
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs/guide/materials.md").read_text()
    blocks = [b.split("```")[0] for b in page.split("```toml\n")[1:]]
    shown = tomllib.loads(next(b for b in blocks if "continuous_fiber_distribution" in b))
    parts = shown["material"]["components"]
    assert [p["scheme"]["model"] for p in parts] == ["fibers_3d_gkt", "fibers_2d_trapezoidal"]
    matrix = {"model": "neo_hookean", "youngs_modulus": 1.0, "poisson_ratio": 0.3}
    law = make_material("solid_mixture", components=[matrix, *parts])
    F = np.diag([1.1, 0.96, 0.96])[None]
    alone = make_material(**matrix).stress(F)[0, 0, 0]
    assert law.stress(F)[0, 0, 0] > 1.5 * alone
