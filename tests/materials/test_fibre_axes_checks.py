"""Issue 41: a fibre axis of two components on a 3D body is refused (it was padded with z = 0
and run), and per-element axes of the wrong length say so (not "must not be parallel"), in
scenes and through the API."""

from __future__ import annotations

import pytest

import tissuesim as ts
from tissuesim.errors import MaterialError, SceneError
from tissuesim.scene.loader import build_scene

HGO = {"model": "holzapfel_gasser_ogden", "c": 1e3, "k1": 1e3, "k2": 1.0, "k": 1e5}
BOX = {"generator": "box", "lower": [0, 0, 0], "upper": [1, 0.4, 0.4], "divisions": [3, 1, 1]}


def scene(material: dict, mesh: dict = BOX) -> None:
    build_scene(
        {
            "mesh": mesh,
            "material": material,
            "simulation": {"integrator": "quasistatic", "time_step": 1.0},
            "run": {"steps": 1},
        },
        name="fibres",
    )


def n_cells() -> int:
    return ts.box((0, 0, 0), (1, 0.4, 0.4), (3, 1, 1)).n_cells


def test_a_two_component_axis_on_a_3d_body_is_refused_in_a_scene():
    with pytest.raises(SceneError, match=r"mat_axis_a: \[1.0, 0.0\] has 2 components on a 3D"):
        scene({**HGO, "mat_axis_a": [1.0, 0.0]})


def test_a_per_cell_list_of_the_wrong_length_says_so_in_a_scene():
    # two rows, the second parallel to the default mat_axis_d: it said "must not be parallel"
    with pytest.raises(SceneError) as info:
        scene({**HGO, "mat_axis_a": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]})
    said = str(info.value)
    assert f"2 vectors given, read as one per cell, but the body has {n_cells()} cells" in said
    assert "parallel" not in said


def body(material) -> None:
    sim = ts.Simulation(integrator="quasistatic", time_step=0.1)
    sim.add_body("b", ts.box((0, 0, 0), (1, 0.4, 0.4), (3, 1, 1)), material, density=1000.0)
    sim.build()


def test_the_api_refuses_them_too():
    law = ts.make_material(**{**HGO, "mat_axis_a": [1.0, 0.0]})
    with pytest.raises(MaterialError, match="mat_axis_a has 2 components on a 3D body"):
        body(law)
    fiber = ts.make_material(
        "trans_iso_mooney_rivlin", c1=2e3, c3=100.0, c4=5.0, c5=3e4, lam_max=1.2, k=1e5,
        fiber=[0.0, 1.0],
    )  # fmt: skip
    with pytest.raises(MaterialError, match="fiber has 2 components"):
        body(fiber)
    # three per-element axes for a body of more elements: silently repeated before
    law = ts.make_material(**{**HGO, "mat_axis_a": [[1.0, 0.0, 0.0]] * 3})
    with pytest.raises(MaterialError, match=f"3 fibre directions given.*{n_cells()} elements"):
        body(law)
    with pytest.raises(MaterialError, match="mat_axis_a gives 3 vectors and mat_axis_d 4"):
        ts.make_material(
            **{**HGO, "mat_axis_a": [[1.0, 0, 0]] * 3, "mat_axis_d": [[0, 1.0, 0]] * 4}
        )
    with pytest.raises(MaterialError, match="at direction 1 of the 2 given, one per element"):
        ts.make_material(**{**HGO, "mat_axis_a": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]})


def test_right_forms_still_run():
    body(ts.make_material(**{**HGO, "mat_axis_a": [[1.0, 0.0, 0.0]] * n_cells()}))
    body(ts.make_material(**{**HGO, "mat_axis_a": [1.0, 0.0, 0.0]}))
    scene({**HGO, "mat_axis_a": [[1.0, 0.0, 0.0]] * n_cells()})
    sim = ts.Simulation(integrator="quasistatic", time_step=0.1)  # 2D: in-plane axes
    sim.add_body("b", ts.rectangle((0, 0), (1, 0.4), (3, 1)),
                 ts.make_material(**{**HGO, "mat_axis_a": [1.0, 1.0]}), density=1000.0)  # fmt: skip
    sim.build()
