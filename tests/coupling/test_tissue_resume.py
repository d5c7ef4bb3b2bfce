"""A run with connective tissue saved and loaded (io/checkpoints/tissue.py) goes on exactly
(np.array_equal) as the run that never stopped: while a blade cuts through the tissue, while it
tears, and after the organ under it was cut (its attachments moved to the copies on their
side). Before, checkpoints refused a tissue."""

from __future__ import annotations

import numpy as np
import pytest
from test_coupled_mechanics import GAP, _blade, two_boxes

from tissuesim.errors import InputError


def _cut_through():
    sim = two_boxes(gravity=9.81)
    sim.add_cut(_blade(0.5 * GAP + 0.05), 1.0, 2.0)
    return sim


def _tearing():
    sim = two_boxes(gravity=None, lift=0.3, peel=True)
    sim.set_tearing(0.3)
    return sim


def _organ_cut(sim):
    from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

    plane = np.array([[0.53, -1, -1], [0.53, 2, -1], [0.53, 2, 1], [0.53, -1, 1]], dtype=float)
    cut = PlanarCut(np.array([0.53, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), plane)
    sim.cut_body(cut, body="lower")


def _assert_same(a, b) -> None:
    assert np.array_equal(a.state.x, b.state.x)
    assert np.array_equal(a.state.v, b.state.v)
    assert a.time == b.time
    assert [r.extra["forces"] for r in a.history] == [r.extra["forces"] for r in b.history]
    da, db = a.tissue.dissection, b.tissue.dissection
    assert np.array_equal(da.alive, db.alive) and np.array_equal(da.severed, db.severed)
    for ca, cb in zip(a.tissue.contacts, b.tissue.contacts, strict=True):
        assert np.array_equal(ca.cells, cb.cells)


@pytest.mark.parametrize(
    ("make", "before", "after", "changed"),
    [(_cut_through, 5, 3, "severed"), (_tearing, 3, 2, "alive")],
)
def test_a_tissue_cut_or_torn_mid_run_resumes_bit_identically(
    tmp_path, make, before, after, changed
):
    whole = make()
    for _ in range(before + after):
        whole.step()
    first = make()
    for _ in range(before):
        first.step()
    d = first.tissue.dissection  # the topology had changed when it was saved
    assert d.severed.size > 0 if changed == "severed" else not d.alive.all()
    first.save(tmp_path / "tissue.npz")
    resumed = make()
    resumed.load(tmp_path / "tissue.npz")
    for _ in range(after):
        resumed.step()
    _assert_same(resumed, whole)


def test_a_tissue_on_a_cut_organ_resumes_with_its_attachments_on_their_side(tmp_path):
    whole = two_boxes()
    whole.step()
    _organ_cut(whole)
    for _ in range(3):
        whole.step()
    first = two_boxes()
    first.step()
    _organ_cut(first)
    first.step()
    first.save(tmp_path / "organ_cut.npz")
    resumed = two_boxes()  # not cut: the checkpoint holds the cut organ and the cells
    resumed.load(tmp_path / "organ_cut.npz")
    for _ in range(2):
        resumed.step()
    _assert_same(resumed, whole)


def test_a_checkpoint_without_the_tissue_or_of_another_tissue_is_one_error_line(tmp_path):
    sim = two_boxes()
    sim.step()
    sim.save(tmp_path / "with.npz")
    cut = _cut_through()  # another set-up of the tissue: its cuts
    with pytest.raises(InputError, match="tissue") as info:
        cut.load(tmp_path / "with.npz")
    assert "\n" not in str(info.value)
