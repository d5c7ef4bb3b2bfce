"""The shipped wedge resection (examples/liver_wedge_resection.toml) on a coarser mesh: two
blades that cross part a wedge from the organ, the wedge falls onto the table and rests there
carrying its weight, no surface ever passes through another, and no gram is lost. Where the
blades cross, elements both cut are split into the parts between them."""

from __future__ import annotations

import numpy as np
import pytest
from test_liver_resection import run_coarse

from tissuesim.mesh.virtual_nodes import node_pieces

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
