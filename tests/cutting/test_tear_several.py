"""A body tears in several places (``bodies/organ_tear.py``): once its cracks stop growing, an
element over the strength far from every crack starts a new one (cut as ``tear2``, ...), while
the stress beside a crack starts none. A bar pulled in two spans tears in each at the load its
strength predicts; a prescribed stress field checks where a new crack may start."""

from __future__ import annotations

import numpy as np
import pytest
from test_tear_turning import _plate
from test_tearing import STEP, STRENGTH, H, L, W, predicted_force, strip

import tissuesim as ts
from tissuesim.bodies.organ_tear import FAR_CELLS


def two_spans() -> ts.Simulation:
    """The strip of test_tearing with a clamp at its middle (x only, free to narrow, pinned
    against rigid motion like the ends) pulled twice as fast as the far end gains on it: the
    near span stretches twice as fast as the far one."""
    sim = strip(20, rate=3.0)  # the far end: 1 STEP per step relative to the middle
    P = sim.mesh.points
    mid = np.abs(P[:, 0] - L / 2) < 1e-9
    sim.add_dirichlet(np.flatnonzero(mid), lambda X, t: np.column_stack(
        [2 * STEP * t + 0 * X[:, 0], 0 * X[:, 0], 0 * X[:, 0]]), (0,), name="middle")  # fmt: skip
    sim.add_dirichlet(np.flatnonzero(mid & (P[:, 1] < 1e-9) & (P[:, 2] < 1e-9)), None, (1, 2),
                      name="pinm")  # fmt: skip
    sim.add_dirichlet(np.flatnonzero(mid & (P[:, 1] > W - 1e-9) & (P[:, 2] < 1e-9)), None, (2,),
                      name="pinzm")  # fmt: skip
    return sim


def test_a_bar_pulled_in_two_spans_tears_in_each_at_its_strength():
    sim = two_spans()
    sim.set_tearing(body="body", stress=STRENGTH)
    mass = sim.model.mass.lumped.sum()
    torn, far = {}, []
    for k in range(70):
        record = sim.step()
        far.append(record.extra["forces"]["right"][0])
        for name in ("tear", "tear2"):
            report = record.extra["cuts"].get(f"body.{name}", {})
            if report.get("cells_cut", 0) and name not in torn:
                torn[name] = k
        if "tear2" in torn:
            break
    tearing = sim.organ_tears[0]
    assert [c.name for c in tearing.cracks] == ["tear", "tear2"]
    first, second = tearing.cracks
    middle = L / 2 + 2 * STEP * (k + 1)  # where the middle clamp is now
    assert first.point[0] < middle < second.point[0]  # the near span first, then the far one
    # normal to the pull within 2 degrees: the spans narrow differently, and the middle
    # section they share cannot take both widths, so the stress is not quite uniaxial
    assert abs(first.normal[0]) > np.cos(np.radians(2.0))
    assert abs(second.normal[0]) > np.cos(np.radians(2.0))
    # the far span tears at the pull its strength predicts, within one load increment
    F, k2 = predicted_force(), torn["tear2"]
    assert torn["tear"] < k2 and far[k2 - 1] < F <= far[k2]
    state = sim.bodies["body"].cut_state
    for name in ("tear", "tear2"):
        # each through the section (its area W H over the normal's x, to the narrowing)
        assert state.area(name) == pytest.approx(W * H, rel=1e-3)
    assert record.extra["cuts"]["body.tear2"]["pieces"] == 3
    after = sim.step().extra["forces"]["right"][0]
    assert abs(after) < 1e-6 * F  # parted: the far end carries nothing
    assert sim.model.mass.lumped.sum() == pytest.approx(mass, rel=1e-12)


def _field(over):
    """A stress along y of 2 (over the strength, 1) in the elements whose centroid ``over``
    accepts, largest near (0, 0.5), 0 elsewhere."""

    def measure(body, c):
        x = c.reshape(-1, 2)[body.mesh.cells].mean(axis=1)
        value = np.where(over(x), 2.0 - 0.1 * x[:, 0] - 0.1 * abs(x[:, 1] - 0.5), 0.0)
        return value, np.tile([0.0, 1.0], (len(x), 1))

    return measure


def test_a_new_crack_starts_only_far_from_the_cracks_and_only_when_they_stop():
    sim = _plate()
    tear, body = sim.organ_tears[0], sim.bodies["body"]

    def grow(over):  # as after a step: the cracks that cut new elements, or a new one
        tear.measure = _field(over)
        out = sim._grow_cracks(tear)
        return [key[5:] for key, report in out.items() if report["cells_cut"]]

    # the first crack: across the plate at the worst element's centroid (y = 0.475 or 0.525)
    assert grow(lambda x: x[:, 0] < 0.5) == ["tear"]
    y0 = tear.cracks[0].point[1]
    assert abs(y0 - 0.5) < 0.05
    # still over ahead of it: it grows, and no other crack starts while it does, though the
    # elements over the strength reach far from it
    assert grow(lambda x: np.ones(len(x), bool)) == ["tear"]
    assert body.cut_state.area("tear") == pytest.approx(1.0, rel=1e-9)  # across the plate
    size = 0.05 * np.sqrt(2.0)  # the cells' longest edge
    # stopped; over the strength only beside it (within FAR_CELLS cells): no new crack
    assert grow(lambda x: abs(x[:, 1] - y0) < 0.9 * FAR_CELLS * size) == []
    # over the strength everywhere: a new crack at the worst element far from the first
    assert grow(lambda x: np.ones(len(x), bool)) == ["tear2"]
    second = tear.cracks[1]
    assert abs(second.point[1] - y0) > FAR_CELLS * size
    assert abs(second.point[1] - y0) < FAR_CELLS * size + 2 * 0.05  # the nearest far row
    assert second.point[0] < 0.05  # at the left edge, where the stress is largest
    assert body.cut_state.area("tear2") == pytest.approx(1.0, rel=1e-9)  # across too


def test_the_two_spans_tear_in_turn_with_contact_on():
    """The same with contact on (dhat 0.2 mm): both cracks' faces are contact surfaces, no
    step intersects, and the bar still tears first in the near span, then in the far one."""
    sim = two_spans()
    sim.set_tearing(body="body", stress=STRENGTH)
    sim.set_contact(dhat=2e-4)
    started = {}
    for k in range(40):
        record = sim.step()
        assert not sim.system.contact.intersecting(sim.state.x)
        for key, report in record.extra["cuts"].items():
            if report["cells_cut"] and key not in started:
                started[key] = k
        if "body.tear2" in started:
            break
    assert list(started) == ["body.tear", "body.tear2"]
    assert started["body.tear"] < started["body.tear2"]
    assert record.extra["cuts"]["body.tear2"]["pieces"] == 3
