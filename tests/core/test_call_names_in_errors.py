"""Issue 41: an error names the call the user made: ``sim.fix(mask)`` spoke of
``add_dirichlet``, and ``grasp(..., (0, 0.01))`` of "grasper None"."""

from __future__ import annotations

import pytest

from tissuesim.errors import InputError


def test_fix_with_a_mask_names_fix(sim):
    mask = sim.body("organ").mesh.points[:, 2] < 1e-9
    with pytest.raises(InputError) as info:
        sim.fix(mask)
    said = str(info.value)
    assert said.startswith("fix: got a boolean mask") and "add_dirichlet" not in said
    with pytest.raises(InputError, match="^add_dirichlet: got a boolean mask"):
        sim.body("organ").add_dirichlet(mask)  # the call made, there too


def test_an_unnamed_grasp_is_not_grasper_none(sim):
    with pytest.raises(InputError) as info:
        sim.grasp([0, 1], (0, 0.01))
    said = str(info.value)
    assert said.startswith("grasp displacement must be 3 finite numbers") and "None" not in said
    with pytest.raises(InputError, match="^grasp: stiffness must be > 0"):
        sim.grasp([0, 1], (0, 0, 0.01), stiffness=-1.0)
    with pytest.raises(InputError, match="^grasper 'jaw' displacement must be 3"):
        sim.grasp([0, 1], (0, 0.01), name="jaw")
