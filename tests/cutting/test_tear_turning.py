"""A tearing crack turns where the principal direction ahead of it turns
(``bodies/organ_tear.py``): a new planar piece from its front, joined to the crack along the
front's edge, normal to the new direction; the body is cut along both pieces (a swept surface)
and parts. Driven by a prescribed stress field, so the geometry of the rule is checked alone."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.bodies.organ_tear import TURN_DEGREES

THETA = np.radians(45.0)  # the principal direction's turn beyond x = 0.5


def _plate() -> ts.Simulation:
    mesh = ts.rectangle((0.0, 0.0), (1.0, 1.0), (20, 20))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
                        integrator="quasistatic")  # fmt: skip
    sim.set_tearing(body="body", stress=1.0)
    return sim


def _field(front: float):
    """A stress over the strength (2) in the elements left of ``front``, largest at the left
    edge's middle; its direction y up to x = 0.5, turned by THETA beyond."""

    def measure(body, c):
        x = c.reshape(-1, 2)[body.mesh.cells].mean(axis=1)  # 3D: c holds x and y only
        value = np.where(x[:, 0] < front, 2.0 - 0.1 * x[:, 0] - 0.1 * abs(x[:, 1] - 0.5), 0.0)
        turned = np.array([-np.sin(THETA), np.cos(THETA)])
        direction = np.where((x[:, 0] < 0.5)[:, None], [0.0, 1.0], turned)
        return value, direction

    return measure


def test_the_crack_turns_with_the_stress_ahead_of_it_and_parts_the_plate():
    sim = _plate()
    tear, done = sim.organ_tears[0], {"pieces": 1}
    for front in (0.25, 0.5, 0.75, 1.0, 1.25):
        tear.measure = _field(front)
        done = sim._grow_cracks(tear).get("body.tear", done)
        if done.get("pieces") == 2:
            break
    assert len(tear.cracks) == 1
    tear = tear.cracks[0]
    # one turn: the first piece along y = 0.5, the second turned by 45 degrees about its front
    assert len(tear.pieces) == 1 and TURN_DEGREES < 45.0
    assert np.allclose(tear.pieces[0].normal[:2], [0.0, 1.0], atol=1e-12)
    assert np.allclose(tear.normal[:2], [-np.sin(THETA), np.cos(THETA)], atol=1e-12)
    kink, y0 = tear.point, tear.pieces[0].point[1]  # the first piece: through the worst cell
    assert abs(y0 - 0.5) < 0.05 and abs(kink[0] - 0.5) <= 0.05
    assert kink[1] == pytest.approx(y0, abs=1e-12)  # on the first piece's front
    # the plate parts: from the left edge along y = y0, then up the 45-degree line to where it
    # leaves the plate (its right edge here, just under the top right corner)
    assert done["pieces"] == 2
    length = kink[0] + min((1.0 - kink[0]) / np.cos(THETA), (1.0 - kink[1]) / np.sin(THETA))
    assert done["area_m2"] == pytest.approx(length, rel=0.02)
    # the cut copies beyond the kink are cut along the turned line (each cell's level zero set)
    vn = sim.bodies["body"].cut_state.vn
    cut = vn.side != 0
    x = vn.points[vn.cells[cut]]
    level = vn.level[cut] * vn.side[cut, None]
    beyond = x.mean(axis=1)[:, 0] > kink[0] + 0.1
    assert beyond.any()
    n = tear.normal[:2]
    for cell, lev in zip(x[beyond], level[beyond], strict=True):
        for a, b in ((0, 1), (0, 2), (1, 2)):
            if lev[a] * lev[b] < 0.0:
                p = cell[a] + lev[a] / (lev[a] - lev[b]) * (cell[b] - cell[a])
                assert abs((p - kink[:2]) @ n) < 1e-9


def test_a_crack_through_a_3d_plate_turns_about_its_front_edge():
    """The same field on a plate 0.1 thick (3D tetrahedra): the crack runs through the
    thickness, turns about its front edge (along z) and parts the plate; the cut's area is the
    2D crack's length times the thickness (a cell's worth)."""
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 0.1), (10, 10, 1))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
                        integrator="quasistatic")  # fmt: skip
    sim.set_tearing(body="body", stress=1.0)
    tear, done = sim.organ_tears[0], {"pieces": 1}
    for front in (0.25, 0.5, 0.75, 1.0, 1.25):
        plane = _field(front)

        def measure(body, c, plane=plane):
            value, direction = plane(body, c.reshape(-1, 3)[:, :2].ravel())
            return value, np.column_stack([direction, np.zeros(len(direction))])

        tear.measure = measure
        done = sim._grow_cracks(tear).get("body.tear", done)
        if done.get("pieces") == 2:
            break
    assert len(tear.cracks) == 1
    tear = tear.cracks[0]
    assert len(tear.pieces) == 1 and done["pieces"] == 2
    assert np.allclose(tear.normal, [-np.sin(THETA), np.cos(THETA), 0.0], atol=1e-9)
    kink = tear.point
    length = kink[0] + min((1.0 - kink[0]) / np.cos(THETA), (1.0 - kink[1]) / np.sin(THETA))
    assert done["area_m2"] == pytest.approx(0.1 * length, rel=0.01)
