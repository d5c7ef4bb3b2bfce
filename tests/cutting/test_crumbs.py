"""Crumbs (mesh/cutting/crumbs.py): a piece a cut frees that is too small for the mesh to carry on
its own (under 1 % of the cells it lies in) and too thin for a contact surface stays attached to the
piece it was part of. Three cuts that nearly meet in a line leave a prism 0.5 mm across in the
middle: with contact on it stays with a neighbour (6 pieces, not 7), nothing moves when it joins, no
gram is lost, the contact surface is the one without it, and the steps after it converge as they do
without such a piece; without contact it is a piece of its own."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from test_crossing_cuts_contact import tilted
from test_cut_contact import block_on_floor
from test_several_cuts_contact import closed_and_free

import tissuesim.bodies.cut_state as cut_state
from tissuesim.contact.cut.sliver_points import bare_pieces
from tissuesim.contact.geometry.surfaces import cut_faces
from tissuesim.mesh.cutting.crumbs import CRUMB, attach_crumbs, joined, small_pieces
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, virtual_node_cut

#: the prism's axis (along z, through the beam of block_on_floor) and its inradius (m)
CENTRE, INRADIUS = np.array([0.47, 0.1, 0.15]), 3e-4


def three_cuts() -> list[tuple[str, PlanarCut]]:
    """Three planes along z, 120 degrees apart, each INRADIUS from the axis: a triangular
    prism 1 mm on a side between them (dhat 1 mm: thinner than the kerf, 2 dhat)."""
    cuts = []
    for name, angle in zip("abc", (90.0, 210.0, 330.0), strict=True):
        n = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle)), 0.0])
        cuts.append((name, tilted(CENTRE + INRADIUS * n, n)))
    return cuts


def cut_three_ways(contact: bool = True):
    """block_on_floor cut by the three planes, one after another: (the simulation, its mass
    before, each cut's report, the warnings)."""
    sim = block_on_floor()
    if not contact:
        sim.contact = None
    mass = sim.system.bodies[0].mass.lumped.sum() / 3
    reports = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for name, cut in three_cuts():
            before = sim.body_positions("body")
            report = sim.cut_body(cut, name=name)
            report["moved"] = np.abs(sim.body_positions("body") - before[report["origin"]]).max()
            reports.append(report)
        assert (sim.system.contact is not None) == contact  # built with the cut surface
    return sim, mass, reports, [str(w.message) for w in caught]


def test_a_crumb_where_three_cuts_meet_stays_with_the_piece_it_came_from():
    sim, mass, reports, messages = cut_three_ways()
    assert [r["pieces"] for r in reports] == [2, 4, 6]  # 7 with the crumb on its own
    assert all(r["moved"] == 0.0 for r in reports)  # nothing moves when it joins
    assert sim.system.bodies[0].mass.lumped.sum() / 3 == pytest.approx(mass, rel=1e-12)
    assert not any("too thin for a contact surface" in m for m in messages)
    # the crumb's element parts are all kept (as many copies as the cut without contact)
    original = sim.bodies["body"].cut_state.original
    alone = virtual_node_cut(original.points, original.cells, [c for _, c in three_cuts()])
    assert len(sim.bodies["body"].cut_state.vn.cells) == len(alone.cells)


def test_without_contact_the_crumb_is_a_piece_of_its_own():
    _, _, reports, _ = cut_three_ways(contact=False)
    assert [r["pieces"] for r in reports] == [2, 4, 7]


def test_the_crumb_is_small_and_bare_and_its_host_keeps_its_contact_surface():
    """The crumb is under CRUMB of its cells and has no surface; attached, the contact
    surface is the same points and triangles as without it, closed and free of intersection."""
    sim = block_on_floor()
    original = sim.bodies["body"].mesh
    vn = virtual_node_cut(original.points, original.cells, [cut for _, cut in three_cuts()])
    mesh = vn.to_mesh(original)
    W, tri = cut_faces(mesh, 1e-3)
    small, bare = small_pieces(vn, original.points), bare_pieces(mesh, W, tri)
    assert vn.n_pieces == 7 and (small & bare).any()
    assert not (small & ~bare).any() and CRUMB == 0.01
    glued, carry, renamed = attach_crumbs(vn, vn.origin, small & bare)  # all from the uncut
    assert glued.n_pieces == 6 and np.array_equal(carry[renamed], vn.origin)
    assert np.array_equal(glued.points[renamed], vn.points)  # a node joins a copy of itself
    n = original.n_points
    assert np.array_equal(glued.origin[:n], np.arange(n))  # the originals stay first
    W2, tri2 = cut_faces(glued.to_mesh(original), 1e-3)
    V, V2 = W @ mesh.points, W2 @ glued.points
    assert len(tri2) == len(tri)
    assert np.array_equal(np.unique(V, axis=0), np.unique(V2, axis=0))
    assert closed_and_free(tri2, V2) == (True, True)


@pytest.mark.parametrize("dhat", [1e-3, 1e-5])
def test_small_pieces_are_found_bare_from_the_surface_round_them_as_from_the_whole(dhat):
    """``bare_small_pieces`` builds the contact surface of the cells round the small pieces
    only: it finds the crumb bare at dhat 1 mm as the whole surface does, and at dhat 0.01 mm
    (a kerf thinner than the prism) neither finds it bare; the same with a blade's gap."""
    sim = block_on_floor()
    state = cut_state.CutState.of_model(sim.bodies["body"].model)
    vn = virtual_node_cut(
        state.original.points, state.original.cells, [cut for _, cut in three_cuts()]
    )
    small = small_pieces(vn, state.original.points)
    mesh = vn.to_mesh(state.original)
    for blade in (False, True):
        W, tri = cut_faces(mesh, dhat, blade)
        whole = small & bare_pieces(mesh, W, tri)
        local = cut_state.bare_small_pieces(state, vn, small, dhat, blade)
        assert np.array_equal(local, whole)
        assert whole.any() == (dhat == 1e-3)


def test_steps_after_the_crumb_converge_as_without_one(monkeypatch):
    """The cut beam's outer pieces fall onto the floor: five steps, no intersection, 2-15
    Newton iterations a step; with the crumb left on its own (contact by points, squeezed
    between the pieces) the same steps took 15-79."""
    sim, _, _, _ = cut_three_ways()
    iterations = []
    for _ in range(5):
        iterations.append(sim.step().newton_iterations)
        assert not sim.system.contact.intersecting(sim.state.x)
    assert max(iterations) <= 20
    monkeypatch.setattr(cut_state, "attach_crumbs_in_contact", lambda s, vn, c, d, b: (vn, c))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        loose, _, reports, _ = cut_three_ways()
        assert reports[-1]["pieces"] == 7
        assert max(loose.step().newton_iterations for _ in range(5)) > 20


def test_joined_nodes_take_the_smallest_of_their_class():
    """The node a class of joined nodes becomes is its smallest, whatever order the pairs
    come in: an original node (index below every copy's) is never dropped for a copy. Joining
    (2, 7) then (5, 7) used to make 2 and 7 into 5."""
    target = joined(9, np.array([2, 5, 8]), np.array([7, 7, 6]))
    assert target.tolist() == [0, 1, 2, 3, 4, 2, 6, 2, 6]
