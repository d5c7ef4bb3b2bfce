"""The shipped liver resection by an instrument in contact (examples/liver_instrument.toml) on a
coarser mesh: the scalpel moves in the cut's kerf (no step intersects, the blade in contact at
every step), the lobe parts as with a blade that passes through the organ, falls onto the table
and lands there, and no gram is lost."""

from __future__ import annotations

import pytest

from tissuesim.cli import example_path
from tissuesim.scene.loader import build_scene


def test_the_instrument_resects_the_lobe_without_passing_through_it():
    import tomllib

    data = tomllib.loads(example_path("liver_instrument").read_text())
    data["bodies"][0]["mesh"]["divisions"] = 6  # 1,296 tetrahedra instead of 3,072
    sim = build_scene(data, base_dir=example_path("liver_instrument").parent).simulation
    body = sim.bodies["liver"]
    mass = body.model.mass.lumped.sum() / 3
    table, pieces = [], []
    for _ in range(32):
        record = sim.step()
        assert record.converged
        assert not sim.system.contact.intersecting(sim.state.x)
        cut = record.extra["cuts"]["incision"]
        assert cut["blade_contact"]
        table.append(record.extra["forces"]["table"][2])
        pieces.append(cut.get("pieces", pieces[-1] if pieces else 1))
    # parted while the blade went down (t = 0.1 .. 0.25 s), as the blade passing through does
    assert pieces[24] == 2 and pieces[20] == 1
    assert max(table[25:]) > 0.5  # the lobe has landed (its weight is about 1 N)
    assert body.model.mass.lumped.sum() / 3 == pytest.approx(mass, rel=1e-12)
    # the blade stopped 15 mm under the organ; the 34 cm^2 section at x = 30 mm is cut, and no
    # more than a step's travel and an element beyond it
    assert 0.0030 < cut["area_m2"] < 0.0040
