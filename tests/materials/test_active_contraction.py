"""FEBio's prescribed active contraction (``materials/active/prescribed_contraction.py``):
energy, stress and tangent against central differences, FEBio's Cauchy stresses in closed form
(sigma = T0/J b, T0/J (b - n n), T0/J n n), the time the law keeps through its steps (a
rejected step begun again), a curve-driven T0 and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material

LAWS = [
    f"{pre}prescribed_{kind}_active_contraction"
    for pre in ("", "uncoupled_")
    for kind in ("isotropic", "trans_iso", "uniaxial")
]


def _law(name: str, T0: object = 3.0, fiber=(1.0, 2.0, -0.5)):
    extra = {} if "isotropic" in name else {"fiber": fiber}
    return make_material(name, T0=T0, **extra)


@pytest.mark.parametrize("name", LAWS)
@pytest.mark.parametrize("d", [2, 3])
def test_stress_and_tangent_are_the_energys_derivatives(name, d):
    rng = np.random.default_rng(7)
    F = random_deformations(rng, 6, d, 0.3)
    law = _law(name)
    res = law.evaluate(F, 2)
    P_fd = central_difference(law.energy_density, F, 1e-6)
    A_fd = central_difference(law.stress, F, 1e-6)
    assert relative_difference(res.stress, P_fd) < 1e-8
    assert relative_difference(res.tangent, A_fd) < 1e-8
    assert np.allclose(law.evaluate(np.eye(d)[None], 0).energy, 0.0)


@pytest.mark.parametrize("name", LAWS)
def test_cauchy_stress_is_febios(name):
    """FEBio's Stress / DevStress: sigma = T0/J b, T0/J (b - n n), T0/J n n with n = F n0."""
    rng = np.random.default_rng(3)
    F = random_deformations(rng, 5, 3, 0.3)
    n0 = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    T0 = 3.0
    law = _law(name, T0)
    J = np.linalg.det(F)
    sigma = np.einsum("qij,qkj->qik", law.stress(F), F) / J[:, None, None]
    b = F @ np.swapaxes(F, 1, 2)
    n = F @ n0
    nn = np.einsum("qi,qj->qij", n, n)
    want = {"isotropic": b, "trans_iso": b - nn, "uniaxial": nn}
    kind = next(k for k in want if k in name)
    np.testing.assert_allclose(sigma, T0 / J[:, None, None] * want[kind], atol=1e-12)


def test_uniaxial_adds_t0_along_the_fibre():
    """Stretched by l along the fibre: the first Piola-Kirchhoff pull is T0 l, the Cauchy stress
    T0 l^2 / J, nothing across."""
    law = make_material("prescribed_uniaxial_active_contraction", T0=2.5, fiber=[0, 0, 1])
    F = np.diag([0.9, 1.1, 1.3])[None]
    P = law.stress(F)[0]
    np.testing.assert_allclose(P, np.diag([0.0, 0.0, 2.5 * 1.3]), atol=1e-14)


def test_time_follows_the_steps_and_a_rejected_step_starts_again():
    law = make_material("prescribed_isotropic_active_contraction", T0="2 * t")
    F = np.eye(3)[None] * 1.1
    assert law.stress(F)[0, 0, 0] == 0.0  # t = 0
    law.begin_step(0.5)
    assert law.stress(F)[0, 0, 0] == pytest.approx(2 * 0.5 * 1.1)
    law.begin_step(0.25)  # the step rejected, halved: from the accepted time 0
    assert law.active_stress() == pytest.approx(0.5)
    law.accept_step(F)
    law.begin_step(0.25)
    assert law.active_stress() == pytest.approx(1.0)
    saved = law.state_arrays()
    other = make_material("prescribed_isotropic_active_contraction", T0="2 * t")
    other.set_state_arrays(saved)
    assert other.time == pytest.approx(0.25)


def test_in_a_mixture_the_time_is_stepped():
    mix = make_material(
        "solid_mixture",
        components=[
            {"model": "neo_hookean", "youngs_modulus": 1.0, "poisson_ratio": 0.3},
            {"model": "prescribed uniaxial active contraction", "T0": "t", "fiber": [1, 0, 0]},
        ],
    )
    F = np.eye(3)[None]
    mix.begin_step(0.4)
    np.testing.assert_allclose(mix.stress(F)[0], np.diag([0.4, 0.0, 0.0]), atol=1e-15)
    mix.accept_step(F)
    assert mix.state_arrays()["c1_time"][0] == pytest.approx(0.4)


def test_refusals():
    with pytest.raises(MaterialError, match="T0 must be a number or an expression"):
        make_material("prescribed_isotropic_active_contraction", T0=[1.0])
    with pytest.raises(MaterialError, match="T0"):
        make_material("prescribed_isotropic_active_contraction", T0="2 * q")
    with pytest.raises(MaterialError, match="fiber"):
        make_material("prescribed_uniaxial_active_contraction", T0=1.0, fiber=[0, 0, 0])
    with pytest.raises(MaterialError, match="uncoupled"):
        make_material(
            "uncoupled_solid_mixture",
            k=10.0,
            components=[
                {"model": "mooney_rivlin", "c1": 1.0, "c2": 0.0},
                {"model": "prescribed_uniaxial_active_contraction", "T0": 1.0},
            ],
        )


def test_the_materials_page_example_runs(capsys):
    """docs/guide/materials.md's example: T0 = 1000 Pa along x at t = 0.5."""
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs/guide/materials.md").read_text()
    blocks = [b.split("```")[0] for b in page.split("```python\n")[1:]]
    exec(next(b for b in blocks if "prescribed_uniaxial_active_contraction" in b), {})
    assert float(capsys.readouterr().out.split()[-1]) == pytest.approx(1000.0)
