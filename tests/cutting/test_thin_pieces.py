"""A piece of a cut body thinner than its cut faces' gap (dhat) gets a contact surface of its
own, built as for a barrier a quarter (then a sixteenth) as large (contact/cut/thin_pieces.py):
the surface is closed and free of intersection, lies in the piece, starts outside every
barrier, and the piece falls onto the floor and rests there with its weight without any
surface passing through another (the exact test sees it); in 2D too."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from test_cut_contact import G, across, block_on_floor
from test_several_cuts_contact import closed_and_free
from test_sliver_contact import slice_with_friction, sliver_on_floor, strip_over_floor_2d

from tissuesim.contact.cut.sliver_points import bare_pieces
from tissuesim.contact.cut.thin_pieces import SCALES, thin_surfaces
from tissuesim.contact.geometry.surfaces import cut_faces

DHAT = 1e-3  # block_on_floor's


@pytest.mark.parametrize("x0, scale", [(0.9995, SCALES[1]), (0.9985, SCALES[0])])
def test_a_sliver_gets_a_closed_surface_of_its_own_and_rests_on_the_floor(x0, scale):
    """The 1.5 mm slice gets its surface at dhat / 4; the 0.5 mm one at dhat / 16 (at dhat / 4
    the snapping, a quarter dhat, puts its whole region on the level set)."""
    sim, contact, messages = sliver_on_floor(x0)
    assert messages == []  # no contact points, no warning
    surface = contact.surfaces[0]
    assert surface.point_areas is None
    tri = surface.triangles
    assert closed_and_free(tri, surface.rest) == (True, True)
    sliver = np.unique(tri[(surface.rest[tri][:, :, 0] > x0).all(axis=1)])
    rest = surface.rest[sliver]
    # in the sliver, its cut face scale x dhat in (its 0.5 mm and 1.5 mm are under 1 dhat)
    assert rest[:, 0].min() == pytest.approx(x0 + scale * DHAT, abs=1e-12)
    assert rest[:, 0].max() <= 1.0 + 1e-12
    block = surface.rest[np.setdiff1d(np.unique(tri), sliver)]
    assert x0 - block[:, 0].max() >= DHAT * (1 - 1e-12)  # the block's face a dhat in
    assert contact.evaluate(sim.state.x, 0)[0] == 0.0  # nothing pushes at rest
    thickness = 1.0 - x0
    weight = 1000.0 * 0.2 * 0.2 * thickness * G
    floor = []
    for _ in range(80):
        record = sim.step()
        assert not contact.intersecting(sim.state.x)  # exact, the sliver's surface included
        assert contact.vertices(sim.state.x)[sliver, 2].min() > 0.0
        floor.append(record.extra["forces"]["floor"][2])
    assert floor[0] == 0.0  # 5 cm above the floor: not yet
    assert np.median(floor[-10:]) == pytest.approx(weight, rel=1e-3)  # resting with its weight


def test_only_pieces_without_a_surface_get_one_and_a_piece_too_thin_keeps_none():
    """thin_surfaces adds a surface to the bare piece only (the block's is kept as it was);
    a slice 0.05 mm thick (1/20 dhat) gets none even at the smallest scale."""
    sim = block_on_floor()
    sim.cut_body(across(0.9995))
    mesh = sim.bodies["body"].mesh
    W, tri = cut_faces(mesh, DHAT)
    assert bare_pieces(mesh, W, tri).any()
    W2, tri2 = thin_surfaces(mesh, W, tri, DHAT, cut_faces)
    assert (W2[: W.shape[0]] != W).nnz == 0 and np.array_equal(tri2[: len(tri)], tri)
    assert len(tri2) > len(tri) and not bare_pieces(mesh, W2, tri2).any()
    sim = block_on_floor()
    sim.cut_body(across(0.99995))
    mesh = sim.bodies["body"].mesh
    W, tri = cut_faces(mesh, DHAT)
    W2, tri2 = thin_surfaces(mesh, W, tri, DHAT, cut_faces)
    assert bare_pieces(mesh, W2, tri2).any() and len(tri2) == len(tri)


def test_a_2d_sliver_gets_a_closed_boundary_and_rests_on_a_floor_body():
    """A 0.5 mm slice of a 2D strip (its last 5 cm held, dhat 1 mm) gets a boundary of its own
    (every point starts one segment and ends one), falls 5 cm onto a floor body and rests
    there: the floor's support carries its weight (per metre of thickness) to 1e-3."""
    sim = strip_over_floor_2d()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        contact = sim.system.contact
    assert [str(w.message) for w in caught] == []
    surface = contact.surfaces[0]
    edges = surface.triangles
    assert np.array_equal(np.sort(edges[:, 0]), np.sort(edges[:, 1]))  # closed loops
    sliver = np.unique(edges[(surface.rest[edges][:, :, 0] > 0.9995).all(axis=1)])
    assert len(sliver) >= 4
    floor_weight = sim.bodies["floor"].model.mass.lumped.sum() / 2 * G
    support = []
    for _ in range(70):
        record = sim.step()
        assert contact.vertices(sim.state.x)[sliver, 1].min() > 0.0
        support.append(record.extra["forces"]["support"][1] - floor_weight)
    weight = 1000.0 * 0.2 * 0.0005 * G
    assert np.median(support[-20:]) == pytest.approx(weight, rel=1e-3)


def test_a_thin_slice_with_friction_stands_on_its_edge_with_its_weight():
    """The 0.5 mm slice with friction 0.5 on the floor, its own surface in contact: it stands
    on its edge, the floor carrying its weight to 1e-3 with a sideways force within the
    friction cone, and no surface passes through another."""
    sim = slice_with_friction()
    contact = sim.system.contact
    surface = contact.surfaces[0]
    assert surface.point_areas is None  # a surface, no points
    tri = surface.triangles
    sliver = np.unique(tri[(surface.rest[tri][:, :, 0] > 0.9995).all(axis=1)])
    for _ in range(60):
        record = sim.step()
        assert not contact.intersecting(sim.state.x)
    floor = np.array(record.extra["forces"]["floor"])
    weight = 1000.0 * 0.2 * 0.2 * 0.0005 * G
    assert floor[2] == pytest.approx(weight, rel=1e-3)
    assert 0.0 < np.hypot(floor[0], floor[1]) <= 0.5 * floor[2]
    x = contact.vertices(sim.state.x)[sliver, 0]
    assert np.ptp(x) < 1e-3  # still upright: its surface in one vertical slab
