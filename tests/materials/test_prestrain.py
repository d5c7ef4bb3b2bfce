"""FEBio's prestrain elastic (``materials/prestrain.py``): energy, stress and tangent against
central differences (a prestrain gradient, an in-situ stretch along the elastic law's fibre),
the reference stress (at F = I FEBio's Cauchy stress of the elastic law at Fp), the released
state F = Fp^-1 free of stress, per-element values bound to the points, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material

NEO = {"model": "neo_hookean", "youngs_modulus": 3.0, "poisson_ratio": 0.3}
TIMR = {"model": "coupled trans-iso Mooney-Rivlin", "c1": 1.0, "c2": 0.2, "c3": 0.5, "c4": 5.0,
        "c5": 20.0, "lam_max": 1.1, "k": 30.0, "fiber": [0.6, 0.8, 0.0]}  # fmt: skip
F0 = np.array([[1.1, 0.05, 0.0], [0.02, 0.95, 0.03], [0.0, -0.04, 1.02]])


def _gradient(ramp: float = 1.0):
    return make_material("prestrain_elastic", elastic=NEO, F0=F0.tolist(), ramp=ramp)


def _in_situ(isochoric: bool = True):
    return make_material(
        "prestrain_elastic",
        elastic=TIMR,
        prestrain="in_situ_stretch",
        stretch=1.08,
        isochoric=isochoric,
    )


@pytest.mark.parametrize(
    "law", [_gradient, lambda: _gradient(0.6), _in_situ, lambda: _in_situ(False)]
)
def test_stress_and_tangent_are_the_energys_derivatives(law):
    law = law()
    rng = np.random.default_rng(5)
    F = random_deformations(rng, 6, 3, 0.2)
    res = law.evaluate(F, 2)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7


def test_reference_stress_is_the_elastic_laws_at_the_prestrain():
    """At F = I: sigma = sigma_e(Fp) (FEBio's Stress at F Fp); released, F = Fp^-1: none."""
    law = _gradient(0.6)
    Fp = 0.4 * np.eye(3) + 0.6 * F0
    base = make_material(**NEO)
    sigma_e = base.stress(Fp[None])[0] @ Fp.T / np.linalg.det(Fp)
    np.testing.assert_allclose(law.stress(np.eye(3)[None])[0], sigma_e, atol=1e-13)
    np.testing.assert_allclose(law.stress(np.linalg.inv(Fp)[None])[0], 0.0, atol=1e-13)
    # the in-situ stretch: Fp = lam a a + (I - a a) / sqrt(lam) along the fibre
    a = np.array([0.6, 0.8, 0.0])
    A = np.outer(a, a)
    Fp = 1.08 * A + (np.eye(3) - A) / np.sqrt(1.08)
    np.testing.assert_allclose(_in_situ().gradient(1)[0], Fp, atol=1e-15)
    np.testing.assert_allclose(_in_situ().stress(np.linalg.inv(Fp)[None])[0], 0.0, atol=1e-12)


def test_per_element_values_are_bound_to_the_points():
    stretches = [1.05, 1.1]
    law = make_material(
        "prestrain_elastic", elastic=TIMR, prestrain="in_situ_stretch", stretch=stretches
    )
    bound = law.bind(4, 3, 2)  # two elements of two points
    np.testing.assert_allclose(bound.stretch, [1.05, 1.05, 1.1, 1.1])
    F = np.broadcast_to(np.eye(3), (4, 3, 3))
    one = make_material("prestrain_elastic", elastic=TIMR, prestrain="in_situ_stretch", stretch=1.1)
    np.testing.assert_allclose(bound.stress(F)[3], one.stress(F[:1])[0], atol=1e-14)
    with pytest.raises(MaterialError, match="2 values of stretch"):
        law.bind(6, 3, 3)


def test_refusals():
    with pytest.raises(MaterialError, match="prestrain 'twist'"):
        make_material("prestrain_elastic", elastic=NEO, prestrain="twist")
    with pytest.raises(MaterialError, match="F0 must be a 3 x 3"):
        make_material("prestrain_elastic", elastic=NEO, F0=[1.0, 2.0])
    with pytest.raises(MaterialError, match="det > 0"):
        make_material("prestrain_elastic", elastic=NEO, F0=(-np.eye(3)).tolist())
    with pytest.raises(MaterialError, match="fibre"):
        make_material("prestrain_elastic", elastic=NEO, prestrain="in_situ_stretch")
    with pytest.raises(MaterialError, match="3D only"):
        _gradient().stress(np.eye(2)[None])


def test_the_materials_page_example_runs(capsys):
    """docs/guide/materials.md's example: stressed at rest, free of stress released."""
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs/guide/materials.md").read_text()
    blocks = [b.split("```")[0] for b in page.split("```python\n")[1:]]
    exec(next(b for b in blocks if '"prestrain_elastic"' in b), {})
    assert capsys.readouterr().out.split() == ["True", "True"]
