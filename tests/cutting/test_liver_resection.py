"""The shipped liver resection (examples/liver_resection.toml) on a coarser mesh: the blade parts
the organ, the lobe falls onto the table and rests there carrying its weight, no surface ever
passes through another, and no gram is lost."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.cli import example_path
from tissuesim.scene.loader import build_scene

G = 9.81


def run_coarse(name: str, steps: int = 80):
    """Shipped example ``name`` on the coarser mesh (divisions 6: 1,296 tetrahedra instead of
    3,072), no step intersecting: (sim, the liver, its mass, the table's force per step, the
    pieces per step: the most any cut reports)."""
    import tomllib

    data = tomllib.loads(example_path(name).read_text())
    data["bodies"][0]["mesh"]["divisions"] = 6
    sim = build_scene(data, base_dir=example_path(name).parent).simulation
    body = sim.bodies["liver"]
    mass = body.model.mass.lumped.sum() / 3
    table, pieces = [], []
    for _ in range(steps):
        record = sim.step()
        assert not sim.system.contact.intersecting(sim.state.x)
        table.append(record.extra["forces"]["table"][2])
        cuts = record.extra["cuts"].values()
        pieces.append(max(c.get("pieces", pieces[-1] if pieces else 1) for c in cuts))
    return sim, body, mass, table, pieces


def test_the_resected_lobe_falls_onto_the_table_and_rests_there():
    sim, body, mass, table, pieces = run_coarse("liver_resection")
    assert pieces[-1] == 2 and table[10] == 0.0  # parted; nothing touched the table before
    assert body.model.mass.lumped.sum() / 3 == pytest.approx(mass, rel=1e-12)
    # the lobe: the piece without the hanger's vertices
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    cells, n = body.mesh.cells, body.mesh.n_points
    graph = coo_matrix((np.ones(cells.size), (np.repeat(cells[:, 0], 4), cells.ravel())), (n, n))
    label = connected_components(graph, directed=False)[1]
    held = np.unique(label[body.conditions[0][1].vertices])
    lobe = ~np.isin(label, held)
    weight = body.model.mass.lumped.reshape(-1, 3)[lobe, 0].sum() * G
    assert 0.5 < weight < 1.5  # about a quarter of the organ's 4.4 N
    assert np.mean(table[-10:]) == pytest.approx(weight, rel=0.05)
