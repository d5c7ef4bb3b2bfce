"""Contact of a body where three or more cuts cross the same cells (contact/cut/surface.py with
any number of levels per copy): the surface is closed, oriented and free of intersection, its
enclosed volume is that of the contact region (counted independently, part by part), and the
pieces of three cuts fall onto a floor and onto each other and rest there."""

from __future__ import annotations

import ipctk
import numpy as np
import pytest
from test_crossing_cuts_contact import BOX, DHAT, outer_pieces_fall_and_rest, plane_cut, tilted
from test_cut_contact import across, block_on_floor

import tissuesim as ts
import tissuesim.contact.cut.surface as cut_surface_module
import tissuesim.contact.cut.surface_2d as cut_surface_2d_module
from tissuesim.contact.cut.surface import GAP, SNAP_IN, SNAP_OUT, cut_surface, level_stack
from tissuesim.mesh.cutting.plane_split import region_fractions
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, virtual_node_cut

#: three oblique cuts meeting in a few cells where merging the surface's close points folded
#: it through itself (a cluster's mean moved past its neighbours' triangles)
FOLDED = [
    ((0.4466, 0.2614, 0.1082), (0.477, -0.2448, 0.6692)),
    ((0.427, 0.2472, 0.104), (0.3236, 1.1007, 0.2968)),
    ((0.4293, 0.265, 0.1113), (-0.6378, 0.616, 1.917)),
]
#: two cuts 8 degrees apart crossing each other inside the box, and a third across them: the
#: thin wedge between the first two collapses to two coincident polygons, opposite ways round
WEDGE = [
    ((0.4769, 0.2176, 0.1367), (0.9839, 0.0826, -0.0336)),
    ((0.4798, 0.2333, 0.1457), (0.0223, 0.3256, 0.1552)),
    ((0.4711, 0.2078, 0.1461), (1.9031, 0.0868, -0.3117)),
]


def build(cuts):
    cm = virtual_node_cut(BOX.points, BOX.cells, cuts).to_mesh(BOX)
    W, tri = cut_surface(cm, DHAT)
    return cm, W, tri, W @ cm.points


def closed_and_free(tri: np.ndarray, V: np.ndarray) -> tuple[bool, bool]:
    """(closed and oriented: each directed edge's reverse is there; free of intersection)."""
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    directed = edges[:, 0] * len(V) + edges[:, 1]
    reverse = edges[:, 1] * len(V) + edges[:, 0]
    mesh = ipctk.CollisionMesh(np.asfortranarray(V), ipctk.edges(tri.astype(np.int32)), tri)
    return bool(np.isin(reverse, directed).all()), not ipctk.has_intersections(mesh, V)


def enclosed(tri: np.ndarray, V: np.ndarray) -> float:
    return np.einsum("ij,ij->i", V[tri[:, 0]], np.cross(V[tri[:, 1]], V[tri[:, 2]])).sum() / 6


def region_volume(cm) -> float:
    """The contact region's volume (area in 2D) counted part by part: each copy's measure
    times the fraction of it where every level (snapped as the surface snaps them) is >= gap."""
    g = GAP * DHAT
    levels = level_stack(cm)
    snap = (levels >= g - SNAP_OUT * DHAT) & (levels <= g + SNAP_IN * DHAT)
    levels = np.where(snap, g, levels) - g
    X = cm.points[cm.cells]
    if X.shape[2] == 2:
        e1, e2 = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]
        volume = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]) / 2
    else:
        volume = np.abs(np.einsum("ij,ij->i", X[:, 1] - X[:, 0],
                                  np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]))) / 6  # fmt: skip
    bounded = np.isfinite(levels).all(axis=2).any(axis=1)
    fraction = np.ones(len(volume))
    fraction[bounded] = region_fractions(levels[bounded])
    return float(fraction @ volume)


def test_three_cuts_across_the_box_enclose_it_less_three_slabs(monkeypatch):
    """Inclusion-exclusion: the block less 2 gap times each cut's area, plus the three prisms
    two slabs share, less the cube all three share."""
    monkeypatch.setattr(cut_surface_module, "MERGE", 0.0)
    cuts = [
        plane_cut((0.47, 0, 0), (1, 0, 0)),
        plane_cut((0, 0.23, 0), (0, 1, 0)),
        plane_cut((0, 0, 0.17), (0, 0, 1)),
    ]
    cm, W, tri, V = build(cuts)
    assert (np.isfinite(level_stack(cm)).all(axis=2).sum(axis=1) == 3).any()
    assert closed_and_free(tri, V) == (True, True)
    g = 2 * GAP * DHAT
    areas, lengths = 0.4 * 0.3 + 1.0 * 0.3 + 1.0 * 0.4, 0.3 + 0.4 + 1.0
    assert enclosed(tri, V) == pytest.approx(0.12 - g * areas + g**2 * lengths - g**3, rel=1e-12)


@pytest.mark.parametrize("count", [3, 4])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_cuts_through_one_cell_enclose_the_contact_region(seed, count, monkeypatch):
    """Three or four oblique cuts through about one point (two of the four about the same
    way round): a cell all of them cross; the surface is closed, oriented, free of intersection, and
    encloses the contact region's volume to round-off (short edges left unmerged)."""
    monkeypatch.setattr(cut_surface_module, "MERGE", 0.0)
    rng = np.random.default_rng(seed)
    point = np.array([0.5, 0.2, 0.15]) + 0.03 * rng.normal(size=3)
    axes = [0, 1, 2, 0][:count]
    cuts = [tilted(point + 0.01 * rng.normal(size=3), np.eye(3)[a] + 0.4 * rng.normal(size=3))
            for a in axes]  # fmt: skip
    cm, W, tri, V = build(cuts)
    assert (np.isfinite(level_stack(cm)).all(axis=2).sum(axis=1) == count).any()
    assert closed_and_free(tri, V) == (True, True)
    assert enclosed(tri, V) == pytest.approx(region_volume(cm), rel=1e-12)


def line(point, angle: float) -> PlanarCut:
    """The line through ``point`` (x, y) at ``angle`` (rad) across a 2D body (a blade swept
    through the plane z = 0)."""
    p = np.array([*point, 0.0])
    d = 3.0 * np.array([np.cos(angle), np.sin(angle), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    return PlanarCut.swept_segment(p - d + up, p + d + up, p - d - up, p + d - up)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_in_2d_three_cuts_through_one_cell_bound_the_contact_region(seed, monkeypatch):
    """A 1 x 0.4 strip of 10 x 4 squares cut by three lines at random angles through about
    one point: the boundary's loops are closed (each point as often a start as an end: two
    pieces may touch at a node), free of intersection, and enclose the contact region's area
    to round-off (short segments left unmerged)."""
    monkeypatch.setattr(cut_surface_2d_module, "MERGE", 0.0)
    strip = ts.rectangle((0.0, 0.0), (1.0, 0.4), (10, 4))
    rng = np.random.default_rng(seed)
    point = np.array([0.5, 0.2]) + 0.03 * rng.normal(size=2)
    cuts = [line(point + 0.01 * rng.normal(size=2), a) for a in rng.uniform(0, np.pi, 3)]
    cm = virtual_node_cut(strip.points, strip.cells, cuts).to_mesh(strip)
    assert (np.isfinite(level_stack(cm)).all(axis=2).sum(axis=1) == 3).any()
    W, edges = cut_surface_2d_module.cut_boundary(cm, DHAT)
    V = W @ cm.points
    starts, ends = (np.bincount(edges[:, i], minlength=len(V)) for i in (0, 1))
    np.testing.assert_array_equal(starts, ends)
    assert starts.min() >= 1
    mesh = ipctk.CollisionMesh(np.asfortranarray(V), edges)
    assert not ipctk.has_intersections(mesh, V)
    a, b = V[edges[:, 0]], V[edges[:, 1]]
    area = 0.5 * np.sum(a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1])
    assert area == pytest.approx(region_volume(cm), rel=1e-12)


def test_where_merging_folds_the_surface_it_merges_less():
    """FOLDED merged at MERGE dhat crosses itself; the surface built is the one merged less,
    closed and free of intersection (and still encloses the region to 1e-3)."""
    cuts = [tilted(p, n) for p, n in FOLDED]
    cm, W, tri, V = build(cuts)
    assert closed_and_free(tri, V) == (True, True)
    assert enclosed(tri, V) == pytest.approx(region_volume(cm), rel=1e-3)


def test_the_two_sides_of_a_collapsed_wedge_cancel(monkeypatch):
    """The wedge between two cuts 8 degrees apart is thinner than the slab near where they
    cross, and its two sides are the same polygons, opposite ways round: they are fanned
    alike and cancel, so merging never needs to be undone for it (the fallback is switched
    off here) and nothing comes within 0.2 dhat at rest."""
    monkeypatch.setattr(cut_surface_module, "_intersecting", lambda *args: False)
    cuts = [tilted(p, n) for p, n in WEDGE]
    cm, W, tri, V = build(cuts)
    assert closed_and_free(tri, V) == (True, True)
    mesh = ipctk.CollisionMesh(np.asfortranarray(V), ipctk.edges(tri.astype(np.int32)), tri)
    close = ipctk.NormalCollisions()
    close.build(mesh, V, 0.2 * DHAT)
    assert len(close) == 0


def test_eight_pieces_of_three_cuts_fall_onto_the_floor_and_onto_each_other():
    """A beam held at x = 0 is cut across at x = 0.47, along its length at z = 0.17 and at
    y = 0.13 (one cell all three cross): the four pieces beyond x = 0.47 fall 5 cm, the lower
    two onto the floor and the upper two onto them, and rest there; the floor carries all
    four, and no surface ever passes through another."""
    sim = block_on_floor()
    sim.step()
    mass = sim.system.bodies[0].mass.lumped.sum() / 3
    sim.cut_body(across(0.47), name="across")
    sim.cut_body(plane_cut((0, 0, 0.17), (0, 0, 1)), name="along")
    report = sim.cut_body(plane_cut((0, 0.13, 0), (0, 1, 0)), name="lengthwise")
    assert report["pieces"] == 8
    levels = level_stack(sim.bodies["body"].mesh)
    assert (np.isfinite(levels).all(axis=2).sum(axis=1) == 3).any()
    outer_pieces_fall_and_rest(sim, mass)
