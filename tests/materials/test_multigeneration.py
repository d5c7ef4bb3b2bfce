"""FEBio's multigeneration (``materials/multigeneration.py``): a generation born at the start of
the step that reaches its start time, with the accepted F as its reference (FEBio's Update), so
that it is free of stress there; the stress by hand as FEBio's sum of Cauchy stresses; energy,
stress and tangent against central differences with generations born; a rejected step and a
checkpoint; the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material

NEO = {"model": "neo_hookean", "youngs_modulus": 3.0, "poisson_ratio": 0.3}
HM = {"model": "holmes_mow", "E": 2.0, "v": 0.2, "beta": 0.3}


def _law(q: int = 1):
    law = make_material(
        "multigeneration",
        generations=[{"start_time": 0.0, "solid": NEO}, {"start_time": 0.5, "solid": HM}],
    )
    return law.bind(q, 3)


def test_a_generation_is_born_free_of_stress_at_the_accepted_shape():
    law = _law()
    F1 = np.array([[1.2, 0.1, 0.0], [0.0, 0.95, 0.05], [0.0, 0.0, 1.05]])[None]
    law.begin_step(0.4)  # t = 0.4: one generation
    law.accept_step(F1)
    first = make_material(**NEO).stress(F1)
    np.testing.assert_allclose(law.stress(F1), first)
    law.begin_step(0.1)  # t = 0.5: the second is born with F1 as its reference
    np.testing.assert_allclose(law.stress(F1), first, atol=1e-13)
    F = np.eye(3)[None]  # back at rest: the second generation is stretched by F1^-1
    Fe = np.linalg.inv(F1[0])
    hm = make_material(**HM)
    sigma = hm.stress(Fe[None])[0] @ Fe.T / np.linalg.det(Fe)  # FEBio: sum of Cauchy stresses
    np.testing.assert_allclose(law.stress(F)[0], sigma, atol=1e-13)
    law.begin_step(0.05)  # rejected, halved: from the accepted state, no generation yet
    np.testing.assert_allclose(law.stress(F), 0.0, atol=1e-14)


def test_derivatives_with_two_generations():
    rng = np.random.default_rng(4)
    for F0 in random_deformations(rng, 3, 3, 0.15):
        law = _law(1)
        law.begin_step(0.4)
        law.accept_step(F0[None])
        law.begin_step(0.2)
        law.accept_step(F0[None])  # t = 0.6: born with F0
        F = random_deformations(rng, 4, 3, 0.2)
        res = law.evaluate(F, 2)
        P_fd = central_difference(law.energy_density, F, 1e-6)
        assert relative_difference(res.stress, P_fd) < 1e-7
        assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7
        other = _law(1)
        other.set_state_arrays(law.state_arrays())
        np.testing.assert_allclose(other.stress(F), res.stress)


def test_refusals():
    with pytest.raises(MaterialError, match="first generation starts at 0"):
        make_material("multigeneration", generations=[{"start_time": 1.0, "solid": NEO}])
    with pytest.raises(MaterialError, match="takes start_time and solid"):
        make_material("multigeneration", generations=[{"time": 0.0, "solid": NEO}])
    with pytest.raises(MaterialError, match="binds it"):
        make_material("multigeneration", generations=[{"start_time": 0, "solid": NEO}]).begin_step(
            1
        )


def test_the_materials_page_table_builds():
    """docs/guide/materials.md's [material] table builds the law with its two generations."""
    import tomllib
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs/guide/materials.md").read_text()
    blocks = [b.split("```")[0] for b in page.split("```toml\n")[1:]]
    table = dict(tomllib.loads(next(b for b in blocks if "multigeneration" in b))["material"])
    law = make_material(table.pop("model"), **table)
    assert law.times == [0.0, 0.6] and len(law.solids) == 2
