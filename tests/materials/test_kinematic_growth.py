"""FEBio's kinematic growth (``materials/active/kinematic_growth.py``): energy, stress and tangent
against central differences for each growth tensor, FEBio's inverses, the stress-free grown
state (F = Fg: no stress, no energy), the time the law keeps and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material

NEO = {"model": "neo_hookean", "youngs_modulus": 3.0, "poisson_ratio": 0.3}
CASES = {
    "volume": {"multiplier": 1.3},
    "area": {"multiplier": 1.7},
    "fiber": {"multiplier": 0.8},
    "general": {"iso": 1.2, "ani": 1.5},
}
FIBER = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])


def _law(growth: str, elastic: dict = NEO):
    return make_material(
        "kinematic_growth", elastic=elastic, growth=growth, fiber=FIBER.tolist(), **CASES[growth]
    )


@pytest.mark.parametrize("growth", sorted(CASES))
@pytest.mark.parametrize(
    "elastic",
    [NEO, {"model": "coupled_mooney_rivlin", "c1": 1.0, "c2": 0.4, "k": 20.0}],
    ids=["neo_hookean", "coupled_mooney_rivlin"],
)
def test_stress_and_tangent_are_the_energys_derivatives(growth, elastic):
    rng = np.random.default_rng(11)
    F = random_deformations(rng, 6, 3, 0.25)
    law = _law(growth, elastic)
    res = law.evaluate(F, 2)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7


def _febio_growth(growth: str) -> tuple[np.ndarray, np.ndarray]:
    """FEBio's GrowthTensor and GrowthTensorInverse as FEGrowthTensor.cpp writes them."""
    n = np.outer(FIBER, FIBER)
    c = CASES[growth]
    if growth == "volume":
        g = c["multiplier"]
        return g * np.eye(3), np.eye(3) / g
    if growth in ("area", "fiber"):
        gi = np.sqrt(c["multiplier"]) if growth == "area" else 1.0
        ga = 2 - gi if growth == "area" else c["multiplier"]
        return gi * np.eye(3) + n * (ga - 1), np.eye(3) / gi - n * ((ga - 1) / gi / (gi + ga - 1))
    gi, ga = c["iso"], c["ani"]
    den, da = gi + ga - 1, (ga - 1) / gi
    return gi * np.eye(3) + n * (ga - 1), np.eye(3) * (1 + da) / den - n * (da / den)


@pytest.mark.parametrize("growth", sorted(CASES))
def test_the_grown_state_is_stress_free_and_the_tensors_are_febios(growth):
    law = _law(growth)
    Fg, Fg_inv = _febio_growth(growth)
    np.testing.assert_allclose(law.growth_tensor(), Fg, atol=1e-14)
    np.testing.assert_allclose(Fg @ Fg_inv, np.eye(3), atol=1e-14)
    res = law.evaluate(Fg[None], 1)
    assert abs(res.energy[0]) < 1e-13
    np.testing.assert_allclose(res.stress[0], 0.0, atol=1e-13)
    # off the grown state: FEBio's Cauchy stress of the elastic law at Fe = F Fg^-1
    F = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.1], [0.05, 0.0, 1.2]])
    Fe = F @ Fg_inv
    base = make_material(**NEO)
    sigma_e = base.stress(Fe[None])[0] @ Fe.T / np.linalg.det(Fe)
    sigma = law.stress(F[None])[0] @ F.T / np.linalg.det(F)
    np.testing.assert_allclose(sigma, sigma_e, atol=1e-12)


def test_multiplier_follows_the_time():
    law = make_material("kinematic_growth", elastic=NEO, growth="volume", multiplier="1 + t")
    law.begin_step(0.5)
    np.testing.assert_allclose(law.growth_tensor(), 1.5 * np.eye(3))
    law.accept_step(np.eye(3)[None])
    law.begin_step(0.25)
    np.testing.assert_allclose(law.growth_tensor(), 1.75 * np.eye(3))
    assert law.state_arrays()["time"][0] == 0.5


def test_refusals():
    with pytest.raises(MaterialError, match="growth 'twist' is not one of"):
        make_material("kinematic_growth", elastic=NEO, growth="twist")
    with pytest.raises(MaterialError, match="volume growth takes multiplier, not iso"):
        make_material("kinematic_growth", elastic=NEO, growth="volume", iso=2.0)
    with pytest.raises(MaterialError, match="must be > 0"):
        make_material("kinematic_growth", elastic=NEO, growth="fiber", multiplier=-1.0)
    with pytest.raises(MaterialError, match="uncoupled"):
        make_material("kinematic_growth", elastic={"model": "mooney_rivlin", "c1": 1.0,
                                                   "c2": 0.0, "k": 10.0})  # fmt: skip
    with pytest.raises(MaterialError, match="3D only"):
        _law("volume").stress(np.eye(2)[None])


def test_the_materials_page_example_runs(capsys):
    """docs/guide/materials.md's example: the grown state is stress free."""
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs/guide/materials.md").read_text()
    blocks = [b.split("```")[0] for b in page.split("```python\n")[1:]]
    exec(next(b for b in blocks if '"kinematic_growth"' in b), {})
    assert float(capsys.readouterr().out.split()[-1]) < 1e-10
