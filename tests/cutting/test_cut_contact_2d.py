"""A cut 2D body in contact (contact/cut/surface_2d.py): its boundary polylines are closed,
oriented and free of intersection, enclose the body less the strip at the cut, the two sides of
a cut start apart and push back when pressed together, and a piece cut off falls onto a floor
and rests there with its weight on it."""

from __future__ import annotations

import ipctk
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.cut.surface import GAP, SNAP_OUT
from tissuesim.contact.cut.surface_2d import cut_boundary
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, virtual_node_cut

G = 9.81


def across(x0: float) -> PlanarCut:
    """The line x = x0 across everything (a blade swept down through the plane z = 0)."""
    return PlanarCut.swept_segment(
        (x0, -1.0, 1.0), (x0, 2.0, 1.0), (x0, -1.0, -1.0), (x0, 2.0, -1.0)
    )


def notch(x0: float, y0: float) -> PlanarCut:
    """The line x = x0 above y = y0 only."""
    return PlanarCut.swept_segment((x0, y0, 1.0), (x0, 2.0, 1.0), (x0, y0, -1.0), (x0, 2.0, -1.0))


def oblique() -> PlanarCut:
    n = np.array([1.0, 0.3, 0.0]) / np.linalg.norm([1.0, 0.3])
    p0, u = np.array([0.5, 0.2, 0.0]), np.array([-n[1], n[0], 0.0])
    z = np.array([0.0, 0.0, 1.0])
    square = ((-1, -1), (1, -1), (1, 1), (-1, 1))
    return PlanarCut(p0, n, np.array([p0 + 2 * (a * u + b * z) for a, b in square]))


STRIP = ts.rectangle((0.0, 0.0), (1.0, 0.4), (10, 4))
CASES = {
    "through": (across(0.47), 0.01),
    "notch": (notch(0.47, 0.15), 0.01),
    "oblique": (oblique(), 0.005),
    "along-edges": (across(0.5), 0.01),  # the line through a column of nodes
    "near-nodes": (across(0.403), 0.01),  # 0.3 dhat from a column of nodes: merged points
    "nodes-snapped": (across(0.388), 0.01),  # the level set within SNAP_IN of nodes
}


def boundary(name):
    cut, dhat = CASES[name]
    cm = virtual_node_cut(STRIP.points, STRIP.cells, [cut]).to_mesh(STRIP)
    W, edges = cut_boundary(cm, dhat)
    return W, edges, W @ cm.points, cut, dhat


def area(V: np.ndarray, edges: np.ndarray) -> float:
    """The enclosed area by the shoelace formula (positive for counter-clockwise loops)."""
    a, b = V[edges[:, 0]], V[edges[:, 1]]
    return float(np.sum(a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1]) / 2)


@pytest.mark.parametrize("name", list(CASES))
def test_the_boundary_is_closed_oriented_and_free_of_intersection(name):
    W, edges, V, cut, dhat = boundary(name)
    k = len(V)
    # every point starts one segment and ends one: closed polylines, consistently oriented
    np.testing.assert_array_equal(np.bincount(edges[:, 0], minlength=k), 1)
    np.testing.assert_array_equal(np.bincount(edges[:, 1], minlength=k), 1)
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-12)  # points are affine weightings
    assert 0.4 - 0.01 < area(V, edges) < 0.4  # counter-clockwise: the outward normal (dy, -dx)
    mesh = ipctk.CollisionMesh(np.asfortranarray(V), edges.astype(np.int32), np.zeros((0, 3)))
    assert not ipctk.has_intersections(mesh, V)
    # the two sides' boundaries keep at least 2 (GAP - SNAP_OUT) dhat from each other
    side = (V - cut.point[:2]) @ cut.normal[:2]
    assert np.abs(side).min() >= (GAP - SNAP_OUT) * dhat * (1 - 1e-9) or name == "notch"
    # no point closer than 0.3 dhat to a segment it is not an end of
    collisions = ipctk.NormalCollisions()
    collisions.build(mesh, V, 0.3 * dhat)
    assert len(collisions) == 0


@pytest.mark.parametrize(
    ("name", "strip"), [("through", 0.4), ("notch", 0.2), ("along-edges", 0.4), ("oblique", None)]
)
def test_the_enclosed_area_is_the_body_less_the_strip_at_the_cut(name, strip, monkeypatch):
    """The strip less 2 gap times the cut's length (no node of these cuts is within the
    snapping band, and short segments are left unmerged, so the level set is exact); the notch
    is cut through the cells it crosses completely, y 0.2..0.4."""
    import tissuesim.contact.cut.surface_2d as module

    monkeypatch.setattr(module, "MERGE", 0.0)
    W, edges, V, cut, dhat = boundary(name)
    if strip is None:  # the oblique line's length across the strip
        strip = 0.4 / abs(cut.normal[0])
    assert area(V, edges) == pytest.approx(0.4 - 2 * GAP * dhat * strip, rel=1e-12, abs=0)


def strip_over_floor() -> ts.Simulation:
    """A strip clamped at x = 0, 5 cm above a floor (a 2D body held along its bottom)."""
    material = ts.make_material("neo_hookean", youngs_modulus=1e6, poisson_ratio=0.3)
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01, gravity=(0.0, -G))
    strip = sim.add_body(
        "strip", ts.rectangle((0, 0.05), (1, 0.25), (10, 2)), material, density=1000.0
    )
    floor = sim.add_body(
        "floor", ts.rectangle((-0.1, -0.1), (1.2, 0), (13, 1)), material, density=1.0
    )
    sim.fix("strip", np.flatnonzero(strip.mesh.points[:, 0] < 1e-9), name="wall")
    sim.fix("floor", np.flatnonzero(floor.mesh.points[:, 1] < -0.1 + 1e-9), name="support")
    sim.set_contact(dhat=1e-3)
    return sim


def test_a_piece_cut_off_falls_onto_the_floor_and_rests_with_its_weight_on_it():
    sim = strip_over_floor()
    sim.step()
    mass = sim.bodies["strip"].model.mass.lumped.sum() / 2
    report = sim.cut_body(across(0.47), body="strip")
    assert report["pieces"] == 2
    assert sim.bodies["strip"].model.mass.lumped.sum() / 2 == pytest.approx(mass, rel=1e-12)
    floor_weight = sim.bodies["floor"].model.mass.lumped.sum() / 2 * G
    contact, support = sim.system.contact, []
    for _ in range(40):
        record = sim.step()
        assert not contact.intersecting(sim.state.x)
        support.append(record.extra["forces"]["support"][1] - floor_weight)
    piece = 1000.0 * 0.2 * (1 - 0.47) * G  # N per metre of thickness
    assert abs(support[0]) < 1e-6 * piece  # 5 cm above the floor: not yet
    assert np.median(support[-10:]) == pytest.approx(piece, rel=1e-4)


def test_the_two_sides_of_a_cut_push_back_when_pressed_together():
    """A strip clamped at both ends is cut across, then one end is pushed toward the other:
    50 um leaves the sides apart (their boundaries start 2 GAP dhat = 0.2 mm apart), 1 and
    2 mm press them together: the contact carries the push to the other clamp, more for more,
    and no segment passes through another."""
    mesh = ts.rectangle((0.0, 0.0), (1.0, 0.2), (10, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="quasistatic", time_step=1.0)
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9), name="left")
    right = np.flatnonzero(mesh.points[:, 0] > 1 - 1e-9)
    push = [0.0, 5e-5, 1e-3, 2e-3]
    sim.grasp(right, lambda t: (-push[round(t)], 0.0), name="right")
    sim.set_contact(dhat=1e-4)
    sim.cut_body(across(0.47))
    contact = sim.system.contact
    left, right_force = [], []
    for _ in range(3):
        record = sim.step()
        assert not contact.intersecting(sim.state.x)
        left.append(record.extra["forces"]["left"][0])
        right_force.append(record.extra["forces"]["right"][0])
    assert left[0] == pytest.approx(0.0, abs=1e-9)  # still apart: nothing reaches the left
    assert 0.5 < left[1] < left[2]  # pressed: the left clamp holds the strip against the push
    # (to Newton's tolerance: the free piece's residual at the first step is 1e-9 N)
    np.testing.assert_allclose(left, -np.array(right_force), rtol=1e-6, atol=1e-8)


def test_contact_energy_of_a_cut_2d_body_matches_finite_differences():
    """The chain rule through the embedded boundary (V = W x, CutFemSurface in 2D): the
    barrier's gradient and exact Hessian over the cut body's nodes against central
    differences, with the two sides of a cut pushed to within dhat of each other."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    mesh = ts.rectangle((0.0, 0.0), (1.0, 0.2), (5, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="quasistatic")
    sim.set_contact(dhat=0.01)
    sim.cut_body(across(0.47))
    s, body = sim.system, sim.bodies["body"]
    assert s.contact.dim == 2
    cells, n = body.mesh.cells, body.mesh.n_points
    graph = coo_matrix((np.ones(cells.size), (np.repeat(cells[:, 0], 3), cells.ravel())), (n, n))
    label = connected_components(graph, directed=False)[1]
    x = sim.state.x.reshape(-1, 2).copy()
    x[label != label[0], 0] -= 1.5 * GAP * 0.01  # the sides' boundaries 0.5 dhat apart
    rng = np.random.default_rng(7)
    x = x.ravel() + 1e-5 * rng.standard_normal(x.size)
    value, grad, _ = s.contact.evaluate(x, 2)
    assert value > 0 and np.count_nonzero(grad) > 0
    for _ in range(5):
        d = rng.standard_normal(x.size)
        h = 1e-8
        fd = (s.contact.evaluate(x + h * d, 0)[0] - s.contact.evaluate(x - h * d, 0)[0]) / (2 * h)
        assert fd == pytest.approx(grad @ d, rel=1e-6, abs=1e-9 * abs(value))
    exact = s.contact.evaluate(x, 2, project=False)[2]
    for _ in range(3):
        d = rng.standard_normal(x.size)
        h = 1e-9
        fd = (s.contact.evaluate(x + h * d, 1)[1] - s.contact.evaluate(x - h * d, 1)[1]) / (2 * h)
        assert np.linalg.norm(fd - exact @ d) <= 1e-6 * np.linalg.norm(exact @ d)


def along(y0: float, x1: float = 2.0) -> PlanarCut:
    """The line y = y0 from x = -1 to x1 (a blade that stopped there)."""
    return PlanarCut.swept_segment((-1, y0, 1.0), (x1, y0, 1.0), (-1, y0, -1.0), (x1, y0, -1.0))


@pytest.mark.parametrize(
    ("cuts", "pieces", "lengths"),
    [
        ([across(0.47), along(0.23)], 4, (0.4, 1.0)),  # crossing
        ([across(0.47), along(0.23, 0.5)], 3, (0.4, 0.5)),  # a T ending at a column of nodes
        ([along(0.23, 0.53), along(0.27, 0.53)], 1, None),  # two notches 4 cm apart in one row
    ],
    ids=["cross", "tee", "parallel"],
)
def test_where_cuts_meet_the_boundary_is_closed_and_free_of_intersection(cuts, pieces, lengths):
    """Where two cuts cross a cell, its copies are bounded by both levels: the boundary is
    closed and oriented, free of intersection, and encloses the strip less both strips of
    width 2 gap (their square of overlap counted once)."""
    vn = virtual_node_cut(STRIP.points, STRIP.cells, cuts)
    assert vn.extra is not None and vn.n_pieces == pieces
    W, edges = cut_boundary(vn.to_mesh(STRIP), 0.01)
    V = W @ vn.points
    k = len(V)
    np.testing.assert_array_equal(np.bincount(edges[:, 0], minlength=k), 1)
    np.testing.assert_array_equal(np.bincount(edges[:, 1], minlength=k), 1)
    mesh = ipctk.CollisionMesh(np.asfortranarray(V), edges)
    assert not ipctk.has_intersections(mesh, V)
    if lengths is not None:
        g = GAP * 0.01
        expected = 0.4 - 2 * g * sum(lengths) + (2 * g) ** 2
        assert area(V, edges) == pytest.approx(expected, rel=1e-12)
