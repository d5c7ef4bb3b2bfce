"""The shipped wedge resection (examples/liver_wedge_resection.toml) on a coarser mesh: two
blades that cross part a wedge from the organ, the wedge falls onto the table and rests there
carrying its weight, no surface ever passes through another, and no gram is lost. Where the
blades cross, elements both cut are split into the parts between them."""

from __future__ import annotations

import numpy as np
import pytest
from test_liver_resection import run_coarse

from tissuesim.mesh.cutting.virtual_nodes import node_pieces

G = 9.81


def test_two_crossing_blades_part_a_wedge_that_falls_onto_the_table_and_rests():
    sim, body, mass, table, pieces = run_coarse("liver_wedge_resection")
    assert pieces[-1] == 2
    assert body.model.mass.lumped.sum() / 3 == pytest.approx(mass, rel=1e-12)
    state = body.cut_state
    for name in ("scalpel_a", "scalpel_b"):
        assert 0.0015 < state.area(name) < 0.003  # each blade's cut: 20-23 cm^2
    # elements both blades cross, split into the parts between the two cuts
    assert body.cut_state.vn.several.any()
    # the wedge: the piece without the hanger's vertices
    label = node_pieces(body.mesh.cells, body.mesh.n_points)
    held = np.unique(label[body.conditions[0][1].vertices])
    wedge = ~np.isin(label, held)
    weight = body.model.mass.lumped.reshape(-1, 3)[wedge, 0].sum() * G
    assert 0.2 < weight < 0.6  # the lobe's tip: under a tenth of the organ's 4.4 N
    assert np.mean(table[-10:]) == pytest.approx(weight, rel=0.05)


def test_a_third_blade_through_the_wedge_cuts_without_fighting_its_own_surface():
    """A third blade along y = 10 mm, down with the other two, crosses both: elements all
    three cut. Before the pieces part (steps 19-24, the blades deep in the organ) no step takes
    more than 25 Newton iterations (17-39 while the cut surface's own pairs within dhat at rest
    were pushed apart by the barrier: contact/cut/rest_proximity.py), nothing intersects, and no
    gram is lost."""
    import tomllib

    from tissuesim.cli import example_path
    from tissuesim.contact.cut.surface import level_stack
    from tissuesim.scene.loader import build_scene

    path = example_path("liver_wedge_resection")
    data = tomllib.loads(path.read_text())
    data["bodies"][0]["mesh"]["divisions"] = 6
    down = "0.095 - 0.5 * (t - 0.1)"
    data["cuts"].append({"name": "scalpel_c", "body": "liver", "start": 0.1, "end": 0.3,
                         "blade": [["-0.01", "0.01", down], ["0.1", "0.01", down]]})  # fmt: skip
    sim = build_scene(data, base_dir=path.parent).simulation
    body = sim.bodies["liver"]
    mass = body.model.mass.lumped.sum() / 3
    iterations = []
    for _ in range(24):
        iterations.append(sim.step().newton_iterations)
        assert not sim.system.contact.intersecting(sim.state.x)
    assert max(iterations[18:]) <= 25
    assert (np.isfinite(level_stack(body.mesh)).all(axis=2).sum(axis=1) == 3).any()
    assert body.model.mass.lumped.sum() / 3 == pytest.approx(mass, rel=1e-12)
