"""An instrument in contact with the body it cuts (``add_cut(obstacle, ...)`` with contact on):
the cut is made ahead of the blade (``mesh/cutting/cut_ahead.py``), so the blade moves in the cut's
kerf: no step intersects, the cut leads the blade by little (a step's travel, at most a cell
edge, and a cell), nothing presses on the blade while the body is at rest, and when a side
leans on the blade the instrument carries it (its force and the support's balance the body's
weight)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.frames.sampling import Surface
from tissuesim.mesh.cutting.cut_ahead import touched_cells
from tissuesim.mesh.cutting.planar_cut import PlanarCut
from tissuesim.mesh.cutting.swept_cut import SweptCut

pytest.importorskip("ipctk")

#: a scalpel's flat blade in the plane y = 0.015, its edge slanting down to z = 0.025
CORNERS = np.array([[-0.06, 0.015, 0.025], [-0.02, 0.015, 0.06], [-0.06, 0.015, 0.06]])
H = 0.01  # the block's cell size
WEIGHT = 0.1 * 0.04 * 0.04 * 1000.0 * 9.81  # N


def _swept_area(shift: float) -> float:
    """The area of the block the blade swept moving by ``shift`` along x (its edge inside the
    block's length): left of the edge x = shift - 0.06 + (0.04 / 0.035) (z - 0.025), above
    z = 0.025, in closed form."""
    a, b, depth = shift - 0.06, 0.04 / 0.035, 0.04 - 0.025
    assert a >= 0.0 and a + b * depth <= 0.1
    return a * depth + 0.5 * b * depth**2


def _block(contact: bool, stop: float) -> ts.Simulation:
    mesh = ts.box((0, 0, 0), (0.1, 0.04, 0.04), (10, 4, 4))
    # the sideways load comes at once in one quasistatic step, where the flap meets the blade
    # (or, passing through, the kerf's other face): Newton takes 30-40 iterations there, and
    # the number moves with the last bits of ipctk's thread sums, so 40 is too tight
    newton = ts.NewtonOptions(max_iterations=100)
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=3e3, poisson_ratio=0.4),
                        density=1000.0, integrator="quasistatic", time_step=0.25,
                        newton=newton)  # fmt: skip
    sim.fix(ts.select.vertices_on_plane(mesh, axis=2, value=0.0), name="table")
    sim.set_contact(dhat=1e-4)
    sim.add_obstacle("scalpel", Surface(CORNERS, np.array([[0, 1, 2]])),
                     translation=lambda t: np.array([0.2 * min(t, stop), 0.0, 0.0]))  # fmt: skip
    sim.add_cut("scalpel", 0.0, math.inf, body="body", name="incision", contact=contact)
    return sim


def test_the_blade_moves_in_the_cuts_kerf_and_the_cut_leads_it_by_little():
    """Driven 0.1 m along x into the block (5 cells a step) and stopped: every step free of
    intersection, the blade clear of the body's surface, no Newton iteration (nothing presses
    on it), and the cut's area between what the blade swept and that plus a cell's band along
    the blade's edges inside the block (the blade stops: its last moving step leads by
    nothing, the band is the cells it touches); without contact the cut trails: at most what
    it swept."""
    sim = _block(contact=True, stop=0.5)
    table = sim.system.contact.table
    assert table.enabled[table.names.index("body"), table.names.index("scalpel")]
    for _ in range(3):
        record = sim.step()
        contact = sim.system.contact
        assert record.converged and record.newton_iterations == 0
        assert record.extra["cuts"]["incision"]["blade_contact"]
        assert not contact.intersecting(sim.state.x)
        assert contact.min_distance(sim.state.x) > 1e-4  # outside the barrier: 1.1 dhat
    area = record.extra["cuts"]["incision"]["area_m2"]
    swept = _swept_area(0.1)
    inside = 0.04 + math.hypot(0.015 * 0.04 / 0.035, 0.015)  # its edges inside the block
    assert swept < area <= swept + H * inside + H**2
    ghost = _block(contact=False, stop=0.5)
    for _ in range(3):
        trailing = ghost.step().extra["cuts"]["incision"]["area_m2"]
    assert trailing <= swept < area


def test_a_side_leaning_on_the_blade_is_carried_by_it():
    """The blade stops in the block, then gravity pulls the block sideways (+y): the flap on
    the blade's -y side leans on it. The instrument feels that push (+y); its force and the
    table's balance the weight (1e-6), no step intersects; the blade that passes through the
    body (contact off) carries nothing and the flap moves through it."""
    sim = _block(contact=True, stop=0.5)
    for _ in range(3):
        sim.step()
    sim.add_gravity([0.0, 9.81, 0.0])
    for _ in range(2):
        record = sim.step()
        assert record.converged and not sim.system.contact.intersecting(sim.state.x)
    blade = np.asarray(record.extra["forces"]["incision"])
    table = np.asarray(record.extra["forces"]["table"])
    assert blade[1] > 0.2 * WEIGHT  # a third of the weight leans on it here
    # the instrument feels -(its push on the body): weight + table - blade = 0 on the body
    assert np.allclose(np.array([0.0, WEIGHT, 0.0]) + table - blade, 0.0, atol=1e-6 * WEIGHT)
    ghost = _block(contact=False, stop=0.5)
    for _ in range(3):
        ghost.step()
    ghost.add_gravity([0.0, 9.81, 0.0])
    for _ in range(2):
        record = ghost.step()
    assert np.allclose(record.extra["forces"]["incision"], 0.0)
    assert record.extra["forces"]["table"][1] == pytest.approx(-WEIGHT, rel=1e-6)


def test_touched_cells_are_those_the_blade_reaches_within_the_margin():
    """Three unit cubes of tetrahedra along x, the plane y = 0.5: a blade whose swept
    polygon ends at x = 1.5 touches the crossed cells of cubes 0 and 1, not 2; one whose tip
    lies in cube 2 touches the cells holding it as well; a wider margin reaches into cube 2;
    a planar cut and the same surface as a swept cut agree."""
    mesh = ts.box((0, 0, 0), (3.0, 1.0, 1.0), (3, 1, 1))  # 3 cubes of 6 tetrahedra
    x_cell = mesh.points[mesh.cells]
    cube = np.floor(x_cell.mean(axis=1)[:, 0]).astype(int)
    n = np.array([0.0, 1.0, 0.0])
    ring = np.array([[-1.0, 0.5, -1.0], [1.5, 0.5, -1.0], [1.5, 0.5, 2.0], [-1.0, 0.5, 2.0]])
    edge = np.array([[1.5, 0.5, -1.0], [1.5, 0.5, 2.0]])
    planar = PlanarCut(np.array([0.0, 0.5, 0.0]), n, ring)
    hit, _, _, d = touched_cells(planar, x_cell, [edge], 1e-3)
    crossed = (d.max(axis=1) > 0) & (d.min(axis=1) < 0)
    assert set(cube[hit]) == {0, 1} and np.all(hit == (crossed & (cube <= 1)))
    swept = SweptCut.from_blades([np.array([[-1.0, 0.5, -1.0], [-1.0, 0.5, 2.0]]), edge])
    hit_swept, *_ = touched_cells(swept, x_cell, [edge], 1e-3)
    assert np.array_equal(hit, hit_swept)
    # the blade's tip pokes 0.7 into cube 2 at mid-height: it holds the tip's cells
    tip = np.array([[1.5, 0.5, 0.5], [2.7, 0.5, 0.5]])
    hit, *_ = touched_cells(planar, x_cell, [tip], 1e-3)
    assert 2 in set(cube[hit]) and hit[cube == 0].any()
    # a margin of 0.6 reaches across into cube 2 from the polygon's edge at x = 1.5
    hit, *_ = touched_cells(planar, x_cell, [edge], 0.6)
    assert set(cube[hit]) == {0, 1, 2}
    # a plane beside the body crosses no cell: nothing is touched (its tip is not looked for)
    beside = PlanarCut(np.array([0.0, 5.0, 0.0]), n, ring + [0.0, 4.5, 0.0])
    hit, *_ = touched_cells(beside, x_cell, [tip + [0.0, 4.5, 0.0]], 1e-3)
    assert not hit.any()


def test_an_instrument_driven_off_its_plane_cuts_along_its_sweep_in_contact():
    """Driven live along x, then 2 mm off its plane (y) as it goes on: its cut becomes a swept
    surface (mesh/cutting/cut_ahead.py's fans over the touched cells), no step intersects, the blade
    stays in contact, the cut grows; its flat, moved sideways, pushes the tissue it faces, so
    the instrument feels a force against the sideways motion."""
    mesh = ts.box((0, 0, 0), (0.1, 0.04, 0.04), (10, 4, 4))
    # the sideways load comes at once in one quasistatic step, where the flap meets the blade
    # (or, passing through, the kerf's other face): Newton takes 30-40 iterations there, and
    # the number moves with the last bits of ipctk's thread sums, so 40 is too tight
    newton = ts.NewtonOptions(max_iterations=100)
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=3e3, poisson_ratio=0.4),
                        density=1000.0, integrator="quasistatic", time_step=0.25,
                        newton=newton)  # fmt: skip
    sim.fix(ts.select.vertices_on_plane(mesh, axis=2, value=0.0), name="table")
    sim.set_contact(dhat=1e-4)
    sim.add_obstacle("scalpel", Surface(CORNERS, np.array([[0, 1, 2]])))
    tool = sim.add_cut("scalpel", 0.0, math.inf, body="body", name="incision")
    areas = []
    for target in ((0.05, 0.0, 0.0), (0.07, 0.002, 0.0)):
        sim.drive_obstacle("scalpel", translation=target)
        record = sim.step()
        cut = record.extra["cuts"]["incision"]
        assert record.converged and cut["blade_contact"]
        assert not sim.system.contact.intersecting(sim.state.x)
        areas.append(cut["area_m2"])
    assert tool.curved and areas[1] > areas[0] > 0.0
    assert record.extra["forces"]["incision"][1] < 0.0  # the tissue it pushes sideways (+y)


def test_the_lead_follows_the_blades_next_step_when_its_motion_is_known():
    """A prescribed blade leads by where it will be a step later: not at all when it stops,
    along its next move when it turns; a live one (``following`` None) by this step's travel,
    at most a cell's edge."""
    from tissuesim.mesh.cutting.cut_ahead import lead

    cube = ts.box((0, 0, 0), (1, 1, 1), (4, 4, 4))  # cell edges 0.25 (0.35 diagonals)
    x_cell = cube.points[cube.cells]
    first = np.array([[0.2, 0.5, 0.9], [0.2, 0.5, 0.7]])  # an upright edge in y = 0.5
    last = first + [0.1, 0.0, 0.0]  # this step: along +x
    plane = (np.array([0.0, 0.5, 0.0]), np.array([0.0, 1.0, 0.0]))
    swept = PlanarCut.hull(np.concatenate([first, last]), *plane)
    same, blades = lead(swept, x_cell, [first, last], following=last)
    assert same is swept and np.array_equal(blades[-1], last)  # it stops: no lead
    turned, blades = lead(swept, x_cell, [first, last], following=last + [0.0, 0.0, -0.1])
    assert np.allclose(blades[-1], last + [0.0, 0.0, -0.1])  # along its next move (-z)
    assert turned.polygon[:, 2].min() == pytest.approx(0.6)
    assert turned.polygon[:, 0].max() == pytest.approx(0.3)  # not on along +x
    live, blades = lead(swept, x_cell, [first, last])
    assert np.allclose(blades[-1], last + [0.1, 0.0, 0.0])  # this step's travel, < an edge
    assert live.polygon[:, 0].max() == pytest.approx(0.4)


@pytest.mark.parametrize("x0", [0.04, 0.0437])
def test_a_blade_crossing_an_earlier_cut_moves_in_its_kerf_with_the_kerf_gap(x0, monkeypatch):
    """The instrument's cut crosses an earlier cut across the block, along the mesh's faces
    (x0 = 0.04: it parted nodes and copied no cell) or through cells: no step intersects.
    Where cells both cross, the contact surface is built with the kerf's gap (BLADE_GAP)
    every time, not the plain cut faces' gap."""
    import tissuesim.contact.cut.surface as cut_surface_module
    from tissuesim.contact.cut.surface import BLADE_GAP

    built = cut_surface_module.cut_surface
    gaps = []

    def recording(mesh, dhat, gap=cut_surface_module.GAP):
        gaps.append(gap)
        return built(mesh, dhat, gap)

    monkeypatch.setattr(cut_surface_module, "cut_surface", recording)
    sim = _block(True, math.inf)
    sim.cut_body(PlanarCut.swept_segment((x0, -1, 1), (x0, 1, 1), (x0, -1, -1), (x0, 1, -1)),
                 body="body", name="across")  # fmt: skip
    for _ in range(4):
        record = sim.step()
        assert not sim.system.contact.intersecting(sim.state.x)
    assert record.extra["cuts"]["incision"]["blade_contact"]
    assert record.newton_iterations == 0  # nothing presses: the body stays where it is
    vn = sim.bodies["body"].cut_state.vn
    if x0 == 0.04:  # the copies with a node the first cut parts are shaved by it
        assert vn.shave is not None and len(vn.shave.copy) > 0
    else:
        assert vn.several.any()  # cells both cuts cross
    assert gaps and set(gaps) == {BLADE_GAP}
