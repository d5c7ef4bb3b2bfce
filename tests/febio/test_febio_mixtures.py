"""FEBio's solid mixtures and fibre laws read from .feb files (tests/febio/models
mixture_fibre_uniaxial.feb, uncoupled_mixture_uniaxial.feb; both also run against their
converted scenes in test_febio.py): the pull of a cube stretched along the fibre against the
closed form, the components' directions turned by the mixture's mat_axis, and the refusals,
each one line naming the XML element and its line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from tissuesim.febio import FebError, febio_scene, load_febio, read_feb
from tissuesim.materials import make_material

MODELS = Path(__file__).parent / "models"


def _stretched(name: str) -> tuple[np.ndarray, float]:
    """The cube's stretches (x, y, z) after the 3 steps and the pull on its x = 1 face."""
    sim = load_febio(MODELS / f"{name}.feb").simulation
    for _ in range(3):
        sim.step()
    X, x = sim.body("body").mesh.points, sim.body_positions("body")
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    return stretch, abs(sim.step().extra["forces"]["pull"][0])


def test_mixture_of_neo_hookean_and_fibres_pulled_along_the_fibre_by_hand():
    """Neo-Hookean (E = 1e4, nu = 0.3) + fiber-exp-pow along x (its local (0,-1,0) turned by
    the mixture's mat_axis a = y, d = -x) + fiber-pow-linear along y (compressed: slack). By
    hand, with l = 1.15 and the lateral stretch t from P_yy = mu (t - 1/t) + lam ln J / t = 0:
    the pull is P_xx = mu (l - 1/l) + lam ln J / l + 2 l ksi x^(beta-1) exp(alpha x^beta),
    x = l^2 - lam0^2, on the unit face."""
    E, nu = 1e4, 0.3
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    ksi, alpha, beta, lam0 = 5000.0, 2.0, 2.5, 1.02
    l = 1.15
    t = brentq(lambda t: mu * (t - 1 / t) + lam * np.log(l * t * t) / t, 0.5, 1.0, xtol=1e-15)
    x = l**2 - lam0**2
    pull = mu * (l - 1 / l) + lam * np.log(l * t * t) / l
    pull += 2 * l * ksi * x ** (beta - 1) * np.exp(alpha * x**beta)
    stretch, force = _stretched("mixture_fibre_uniaxial")
    np.testing.assert_allclose(stretch, [l, t, t], rtol=1e-7)
    assert force == pytest.approx(pull, rel=1e-6)
    assert force > 1.3 * (mu * (l - 1 / l) + lam * np.log(l * t * t) / l)  # the fibre pulls


def test_uncoupled_mixture_pull_is_the_laws_stress():
    """Mooney-Rivlin + fiber-exp-pow-uncoupled + uncoupled fiber-exp-linear, both along x,
    with the mixture's k (the components' k = 0 and pressure_model ignored, as in
    FEBio; hex8: FEBio's three-field element, tissuesim's mean dilatation): a homogeneous state
    whose lateral stresses are zero and whose pull is P_xx of the law, itself checked
    against finite differences elsewhere."""
    law = make_material(
        "uncoupled_solid_mixture",
        k=1e5,
        components=[
            {"model": "Mooney-Rivlin", "c1": 1000.0, "c2": 200.0},
            {"model": "fiber-exp-pow-uncoupled", "ksi": 5000.0, "alpha": 2.0, "beta": 2.0},
            {"model": "uncoupled fiber-exp-linear", "c3": 100.0, "c4": 10.0, "c5": 2e4,
             "lam_max": 1.1},
        ],
    )  # fmt: skip
    data, _ = febio_scene(read_feb(MODELS / "uncoupled_mixture_uniaxial.feb"), "x")
    assert data["simulation"]["formulation"] == "mean_dilatation"
    stretch, force = _stretched("uncoupled_mixture_uniaxial")
    P = law.stress(np.diag(stretch)[None])[0]
    assert stretch[0] == pytest.approx(1.15)
    np.testing.assert_allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)


def test_component_directions_are_turned_by_the_mixtures_axes():
    """FEBio's GetLocalCS: a component's fibre is Q_mixture Q_own fiber; with a = y, d = -x the
    local (0,-1,0) is global x, and the angles theta = 0, phi = 90 (local x) global y."""
    data, _ = febio_scene(read_feb(MODELS / "mixture_fibre_uniaxial.feb"), "x")
    components = data["material"]["components"]
    assert [c["model"] for c in components] == ["neo_hookean", "fiber-exp-pow", "fiber-pow-linear"]
    assert "fiber" not in components[0]
    np.testing.assert_allclose(components[1]["fiber"], [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(components[2]["fiber"], [0.0, 1.0, 0.0], atol=1e-15)


FIBRE_SOLID = '<solid type="fiber-exp-pow">'
MATERIAL = '<material id="1"'
#: case -> (text replaced, its replacement, the element named, a text on its line, message)
REFUSALS = {
    "unknown": (FIBRE_SOLID, '<solid type="fiber-Kiousis-uncoupled">', "solid",
                "fiber-Kiousis", "not supported by tissuesim in a solid mixture"),
    "nested": (FIBRE_SOLID, '<solid type="solid mixture">', "solid",
               '<solid type="solid mixture">', "a mixture is not a component of a mixture"),
    "alone": ('type="solid mixture">', 'type="fiber-exp-pow">', "material", MATERIAL,
              "read as a mixture's <solid> only"),
    "mu": ("<mu>0</mu>", "<mu>-2</mu>", "material", MATERIAL, "mu (the fibre's shear modulus)"),
    "uncoupled": ('type="solid mixture">', 'type="uncoupled solid mixture"><k>1e5</k>', "material",
                  MATERIAL, "not an uncoupled law"),
    "param": ("<density>1000</density>", "<density>1000</density><c1>1</c1>", "c1", "<c1>",
              "parameter 'c1' of 'solid mixture'"),
    "fiber_type": ('<fiber type="vector">0,-1,0', '<fiber type="user">0,-1,0', "fiber",
                   'type="user"', "fiber type 'user'"),
    "element_data": ("</Mesh>", '</Mesh>\n  <MeshData>\n    <ElementData type="fiber" '
                     'elem_set="cube">\n      <e lid="1">1,0,0</e>\n    </ElementData>\n'
                     "  </MeshData>", "e", '<e lid="1">',
                     "fiber element data on a 'solid mixture'"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(REFUSALS))
def test_refusals_name_the_element_and_line(case, tmp_path):
    old, new, tag, marker, message = REFUSALS[case]
    text = (MODELS / "mixture_fibre_uniaxial.feb").read_text()
    assert old in text
    text = text.replace(old, new, 1)
    feb = tmp_path / "bad.feb"
    feb.write_text(text)
    line = next(i for i, s in enumerate(text.splitlines(), 1) if marker in s)
    with pytest.raises(FebError) as info:
        febio_scene(read_feb(feb), "x")
    said = str(info.value)
    assert "\n" not in said and message in said, said
    assert f"bad.feb:{line} <{tag}>" in said, said
