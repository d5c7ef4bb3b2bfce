"""The soft-tissue laws by name: FEBio's type names and the aliases, keyword parameters, one-line
errors for wrong, missing or unphysical parameters, scene tables (Ogden's lists) and a step."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import MaterialError, SceneError
from tissuesim.materials import ALIASES, MATERIALS, SOFT_TISSUE_LAWS, make_material
from tissuesim.scene.loader import build_scene

PARAMS = {
    "mooney_rivlin": dict(c1=150.0, c2=40.0, k=3000.0),
    "coupled_mooney_rivlin": dict(c1=150.0, c2=40.0, k=3000.0),
    "ogden": dict(c=[300.0, -40.0], m=[4.0, -2.0], k=3000.0),
    "ogden_unconstrained": dict(c=[300.0, -40.0], m=[4.0, -2.0], cp=3000.0),
    "yeoh": dict(c1=150.0, c2=30.0, c3=5.0, k=3000.0),
    "coupled_yeoh": dict(c1=150.0, c2=30.0, c3=5.0, k=3000.0),
    "veronda_westmann": dict(c1=200.0, c2=1.5, k=3000.0),
    "coupled_veronda_westmann": dict(c1=200.0, c2=1.5, k=3000.0),
    "arruda_boyce": dict(mu=300.0, N=4.0, k=3000.0),
    "coupled_arruda_boyce": dict(mu=300.0, N=4.0, k=3000.0),
}
FEBIO_NAMES = {
    "Mooney-Rivlin": "mooney_rivlin",
    "coupled Mooney-Rivlin": "coupled_mooney_rivlin",
    "Ogden": "ogden",
    "Ogden unconstrained": "ogden_unconstrained",
    "Yeoh": "yeoh",
    "Veronda-Westmann": "veronda_westmann",
    "coupled Veronda-Westmann": "coupled_veronda_westmann",
    "Arruda-Boyce": "arruda_boyce",
}
F_TEST = np.array([[[1.2, 0.1, 0.0], [0.05, 0.9, 0.1], [0.0, -0.1, 1.05]]])


@pytest.mark.parametrize("name", sorted(PARAMS))
def test_every_law_by_name_and_back_from_its_parameters(name):
    law = make_material(name, **PARAMS[name])
    assert type(law) is MATERIALS[name] and law.name == name and type(law) in SOFT_TISSUE_LAWS
    again = make_material(name, **law.parameters())
    np.testing.assert_allclose(again.stress(F_TEST), law.stress(F_TEST), rtol=1e-15)
    assert repr(law).startswith(type(law).__name__ + "(")
    assert law.mu > 0 and law.lam + 2 * law.mu / 3 > 0


@pytest.mark.parametrize("febio, name", sorted(FEBIO_NAMES.items()))
def test_febio_type_names_give_the_febio_law(febio, name):
    law = make_material(febio, **PARAMS[name])
    assert law.name == name and law.febio_name == febio


def test_aliases():
    assert make_material("mooney_rivlin_uncoupled", **PARAMS["mooney_rivlin"]).name == (
        "mooney_rivlin"
    )
    assert make_material("Mooney-Rivlin coupled", **PARAMS["mooney_rivlin"]).name == (
        "coupled_mooney_rivlin"
    )
    assert make_material("ogden_coupled", **PARAMS["ogden_unconstrained"]).name == (
        "ogden_unconstrained"
    )
    for alias, name in ALIASES.items():
        assert name in MATERIALS, alias


def test_ogden_febio_indexed_terms_equal_the_lists():
    lists = make_material("ogden", c=[300.0, -40.0], m=[4.0, -2.0], k=3000.0)
    febio = make_material("Ogden", c1=300.0, m1=4.0, c2=-40.0, m2=-2.0, c3=0.0, m3=1.0, k=3e3)
    np.testing.assert_allclose(febio.stress(F_TEST), lists.stress(F_TEST), rtol=1e-14)
    # FEBio's default exponent is 1
    one = make_material("ogden", c1=300.0, k=3000.0)
    assert one.m.tolist() == [1.0]


BAD = [
    ("mooney_rivlin", dict(c1=150.0), "needs k"),
    ("mooney_rivlin", dict(c1=150.0, k=-1.0), "k .bulk modulus. must be > 0"),
    ("mooney_rivlin", dict(c1=150.0, k=True), "must be a number"),
    ("mooney_rivlin", dict(c1="soft", k=1.0), "c1 must be a number"),
    ("mooney_rivlin", dict(c1=-100.0, c2=40.0, k=1e3), "shear modulus"),
    ("mooney_rivlin", dict(c1=100.0, k=1e3, c3=1.0), "unknown parameter 'c3'"),
    ("coupled_mooney_rivlin", dict(c1=0.0, c2=50.0, k=1e3), "c1 must be > 0"),
    ("coupled_mooney_rivlin", dict(c1=10.0, c2=-5.0, k=1.0), "bulk modulus"),
    ("yeoh", dict(c2=1.0, k=1.0), "needs c1"),
    ("yeoh", dict(c1=1.0, c7=1.0, k=1.0), "unknown parameter 'c7'"),
    ("veronda_westmann", dict(c1=1.0, c2=0.0, k=1.0), "c2 must be > 0"),
    ("veronda_westmann", dict(c1=1.0, c2=float("inf"), k=1.0), "finite"),
    ("arruda_boyce", dict(mu=1.0, N=0.0, k=1.0), "N .links. must be > 0"),
    ("arruda_boyce", dict(mu=1.0, k=1.0), "needs N"),
    ("ogden", dict(c=[1.0, 2.0], m=[2.0], k=1.0), "same length"),
    ("ogden", dict(c=[1.0], m=[0.0], k=1.0), "must not be 0"),
    ("ogden", dict(c=[1.0], k=1.0), "needs both lists"),
    ("ogden", dict(c="abc", m=[1.0], k=1.0), "non-empty list"),
    ("ogden", dict(c=[], m=[], k=1.0), "non-empty list"),
    ("ogden", dict(c=[1.0], m=[2.0], c1=1.0, k=1.0), "not both"),
    ("ogden", dict(k=1.0), "needs its terms"),
    ("ogden", dict(c=[-10.0], m=[2.0], k=1.0), "shear modulus"),
    ("ogden_unconstrained", dict(c=[10.0], m=[2.0], cp=-100.0), "bulk modulus"),
    ("ogden_unconstrained", dict(c=[10.0], m=[2.0]), "needs cp"),
    ("ogdn", dict(c=[10.0], m=[2.0], k=1.0), "did you mean 'ogden'"),
]


@pytest.mark.parametrize("name, params, message", BAD)
def test_wrong_missing_or_unphysical_parameters_are_one_line(name, params, message):
    with pytest.raises(MaterialError, match=message) as info:
        make_material(name, **params)
    assert "\n" not in str(info.value)


def _scene(material: dict) -> dict:
    return {
        "mesh": {"generator": "box", "lower": [0, 0, 0], "upper": [1, 0.4, 0.4],
                 "divisions": [3, 1, 1]},
        "material": material,
        "simulation": {"density": 1000.0, "integrator": "quasistatic", "time_step": 1.0},
        "gravity": {"acceleration": [0.0, 0.0, -9.81]},
        "dirichlet": [{"vertices": {"on_plane": {"axis": 0, "value": 0.0}}}],
        "run": {"steps": 1},
    }  # fmt: skip


@pytest.mark.parametrize(
    "material",
    [
        {"model": "ogden", "c": [3000.0, -400.0], "m": [4.0, -2.0], "k": 3e4},
        {"model": "Mooney-Rivlin", "c1": 1500.0, "c2": 400.0, "k": 3e4},
        {"model": "arruda_boyce", "mu": 3000.0, "N": 4.0, "k": 3e4},
    ],
)
def test_scene_tables_take_the_laws_and_a_step_sags(material):
    scene = build_scene(_scene(material), name="soft")
    sim = scene.simulation
    sim.step()
    tip = np.isclose(sim.mesh.points[:, 0], 1.0)
    assert sim.displacement[tip, 2].mean() < 0


def test_scene_errors_name_the_table():
    with pytest.raises(SceneError, match=r"\[material\].*ogden: c and m must have the same"):
        build_scene(_scene({"model": "ogden", "c": [1.0, 2.0], "m": [2.0], "k": 1.0}), name="x")
    with pytest.raises(SceneError, match=r"\[material\].*mooney_rivlin needs k"):
        build_scene(_scene({"model": "mooney_rivlin", "c1": 1.0}), name="x")


def test_top_level_names():
    assert ts.Ogden is MATERIALS["ogden"] and ts.MooneyRivlin is MATERIALS["mooney_rivlin"]
    assert callable(ts.fit_material)
