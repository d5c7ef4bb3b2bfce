"""Issue 41: selections combine conditions with and, or, not (they gave "BoolOp is not
allowed"), element by element, in scenes and in any expression."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.errors import SceneError
from tissuesim.scene.common import condition
from tissuesim.scene.expressions import compile_expression
from tissuesim.scene.loader import build_scene

POINTS = np.array([[-0.1, 0.0, 0.05], [-0.1, 0.0, 0.0], [0.0, 0.0, 0.05], [0.0, 0.0, 0.0]])


@pytest.mark.parametrize(
    ("text", "selected"),
    [
        ("x < -0.07 and z > 0.03", [True, False, False, False]),
        ("x < -0.07 or z > 0.03", [True, True, True, False]),
        ("not x < -0.07", [False, False, True, True]),
        ("not (x < -0.07 and z > 0.03)", [False, True, True, True]),
        ("x < -0.07 and z > 0.03 or x == 0 and z == 0", [True, False, False, True]),
        ("x < 0 and y == 0 and z > 0", [True, False, False, False]),
    ],
)
def test_conditions_combine_element_by_element(text, selected):
    assert condition(text, "where")(POINTS).tolist() == selected


def test_and_in_any_expression_is_one_or_zero():
    f = compile_expression("(x < 0 and t > 1) * 2", "displacement[0]")
    assert f(POINTS, 2.0).tolist() == [2.0, 2.0, 0.0, 0.0]


def test_chained_comparisons_point_to_and():
    with pytest.raises(SceneError, match="write e.g. 0 < x and x < 1"):
        compile_expression("0 < x < 1", "where")


def test_a_scene_fixes_the_vertices_both_conditions_select():
    scene = build_scene(
        {
            "mesh": {"generator": "box", "lower": [-0.1, -0.05, 0], "upper": [0.1, 0.05, 0.05],
                     "divisions": [4, 2, 2]},
            "material": {"model": "neo_hookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3},
            "simulation": {"integrator": "quasistatic", "time_step": 0.1},
            "dirichlet": [{"vertices": {"where": "x < -0.07 and z > 0.03"}}],
        },
        name="and",
    )  # fmt: skip
    sim = scene.simulation
    sim.build()
    points = sim.mesh.points
    expected = np.flatnonzero((points[:, 0] < -0.07) & (points[:, 2] > 0.03))
    fixed = np.unique(sim.system.prescribed_dofs // 3)
    assert fixed.tolist() == expected.tolist() and len(expected) > 0
