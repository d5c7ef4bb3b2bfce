"""A cut body in contact (contact/cut/surface.py): its contact surface is closed, oriented and
free of intersection, the two sides of a cut start apart and never pass through each other, and
a piece cut off falls onto a floor and rests there with its weight on it."""

from __future__ import annotations

import warnings

import ipctk
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.cut.surface import GAP, SNAP_OUT, cut_surface
from tissuesim.contact.obstacles import plane
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, virtual_node_cut

G = 9.81


def across(x0: float) -> PlanarCut:
    """The plane x = x0 across everything (a blade swept down through it)."""
    return PlanarCut.swept_segment(
        (x0, -1.0, 1.0), (x0, 2.0, 1.0), (x0, -1.0, -1.0), (x0, 2.0, -1.0)
    )


def notch(x0: float, z0: float) -> PlanarCut:
    """The plane x = x0 above z = z0 only."""
    return PlanarCut.swept_segment((x0, -1.0, 2.0), (x0, 2.0, 2.0), (x0, -1.0, z0), (x0, 2.0, z0))


def oblique() -> PlanarCut:
    n = np.array([1.0, 0.3, 0.2]) / np.linalg.norm([1.0, 0.3, 0.2])
    p0 = np.array([0.5, 0.2, 0.15])
    u = np.cross(n, [0.0, 0.0, 1.0])
    u /= np.linalg.norm(u)
    w = np.cross(n, u)
    corners = [p0 + 3 * (a * u + b * w) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return PlanarCut(p0, n, np.array(corners))


BOX = ts.box((0.0, 0.0, 0.0), (1.0, 0.4, 0.3), (10, 4, 3))
ORGAN = ts.ellipsoid((0.0, 0.0, 0.03), (0.06, 0.04, 0.03), 8)
CASES = {
    "box-through": (BOX, across(0.47), 0.01),
    "box-notch": (BOX, notch(0.47, 0.15), 0.01),
    "box-oblique": (BOX, oblique(), 0.005),
    "organ-through": (ORGAN, across(0.011), 1e-4),
    "organ-along-faces": (ORGAN, across(0.0), 1e-4),  # the plane through a layer of nodes
    "organ-near-nodes": (ORGAN, across(-0.02137), 1e-4),
}


def surface(name):
    mesh, cut, dhat = CASES[name]
    cm = virtual_node_cut(mesh.points, mesh.cells, [cut]).to_mesh(mesh)
    W, tri = cut_surface(cm, dhat)
    return cm, W, tri, W @ cm.points, cut, dhat


@pytest.mark.parametrize("name", list(CASES))
def test_the_surface_is_closed_oriented_and_free_of_intersection(name):
    cm, W, tri, V, cut, dhat = surface(name)
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    directed = edges[:, 0] * len(V) + edges[:, 1]
    reverse = edges[:, 1] * len(V) + edges[:, 0]
    assert np.unique(directed).size == directed.size  # each directed edge once: a manifold
    assert np.isin(reverse, directed).all()  # and each has its reverse: closed, oriented
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-12)  # points are affine weightings
    mesh = ipctk.CollisionMesh(np.asfortranarray(V), ipctk.edges(tri.astype(np.int32)), tri)
    assert not ipctk.has_intersections(mesh, V)
    # the two sides' surfaces keep at least 2 (GAP - SNAP_OUT) dhat from each other
    side = (V - cut.point) @ cut.normal
    assert np.abs(side).min() >= (GAP - SNAP_OUT) * dhat * (1 - 1e-9) or name == "box-notch"
    # no surface point closer than 0.3 dhat to a primitive it does not belong to
    collisions = ipctk.NormalCollisions()
    collisions.build(mesh, V, 0.3 * dhat)
    assert len(collisions) == 0


@pytest.mark.parametrize(("name", "slab"), [("box-through", 0.4 * 0.3), ("box-notch", 0.4 * 0.1)])
def test_the_enclosed_volume_is_the_body_less_the_slab_at_the_cut(name, slab, monkeypatch):
    """Divergence theorem over the closed surface: the block, less 2 gap times the cut's area
    (no node of this block is within the snapping band, and short edges are left unmerged, so
    the level set is exact)."""
    import tissuesim.contact.cut.surface as module

    monkeypatch.setattr(module, "MERGE", 0.0)
    cm, W, tri, V, cut, dhat = surface(name)
    volume = np.einsum("ij,ij->i", V[tri[:, 0]], np.cross(V[tri[:, 1]], V[tri[:, 2]])).sum() / 6
    assert volume == pytest.approx(0.12 - 2 * GAP * dhat * slab, rel=1e-12)


def block_on_floor() -> ts.Simulation:
    mesh = ts.box((0.0, 0.0, 0.05), (1.0, 0.2, 0.25), (10, 2, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e6, poisson_ratio=0.3)
    sim = ts.Simulation(
        mesh,
        material,
        density=1000.0,
        integrator="backward_euler",
        time_step=0.01,
        gravity=(0.0, 0.0, -G),
    )
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9), name="wall")
    sim.set_contact(dhat=1e-3)
    sim.add_obstacle("floor", plane((0.5, 0.1, 0.0), (0, 0, 1), 3.0))
    return sim


def test_a_piece_cut_off_falls_onto_the_floor_and_rests_with_its_weight_on_it():
    sim = block_on_floor()
    sim.step()
    mass = sim.system.bodies[0].mass.lumped.sum() / 3
    report = sim.cut_body(across(0.47))
    assert report["pieces"] == 2
    assert sim.system.bodies[0].mass.lumped.sum() / 3 == pytest.approx(mass, rel=1e-12)
    contact = sim.system.contact
    floor = []
    for _ in range(40):
        record = sim.step()
        assert record.substeps == 1
        assert not contact.intersecting(sim.state.x)  # exact: the collision mesh now
        floor.append(record.extra["forces"]["floor"][2])
    piece = 1000.0 * 0.2 * 0.2 * (1 - 0.47) * G
    assert floor[0] == 0.0  # 5 cm above the floor: not yet
    assert np.median(floor[-10:]) == pytest.approx(piece, rel=1e-4)


def test_the_two_sides_of_a_cut_push_back_when_pressed_together():
    """A bar clamped at both ends is cut across, then one end is pushed toward the other:
    50 um leaves the sides apart (their contact surfaces start 2 GAP dhat = 0.2 mm apart), 1 and
    2 mm press them together: the contact carries the push to the other clamp, more for more,
    and no surface passes through another."""
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.2, 0.2), (10, 2, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="quasistatic", time_step=1.0)
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9), name="left")
    right = np.flatnonzero(mesh.points[:, 0] > 1 - 1e-9)
    push = [0.0, 5e-5, 1e-3, 2e-3]
    sim.grasp(right, lambda t: (-push[round(t)], 0.0, 0.0), name="right")
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
    assert 0.5 < left[1] < left[2]  # pressed: the left clamp holds the bar against the push
    np.testing.assert_allclose(left, -np.array(right_force), rtol=1e-6, atol=1e-9)


def test_contact_energy_of_a_cut_body_matches_finite_differences():
    """The chain rule through the embedded surface (V = W x, CutFemSurface): the barrier's
    gradient and exact Hessian over the cut body's nodes against central differences, with the
    two sides of a cut pushed to within dhat of each other."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.2, 0.2), (5, 2, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="quasistatic")
    sim.set_contact(dhat=0.01)
    sim.cut_body(across(0.47))
    s, body = sim.system, sim.bodies["body"]
    cells, n = body.mesh.cells, body.mesh.n_points
    graph = coo_matrix((np.ones(cells.size), (np.repeat(cells[:, 0], 4), cells.ravel())), (n, n))
    label = connected_components(graph, directed=False)[1]
    x = sim.state.x.reshape(-1, 3).copy()
    x[label != label[0], 0] -= 1.5 * GAP * 0.01  # the sides' surfaces 0.5 dhat apart
    rng = np.random.default_rng(7)
    x = x.ravel() + 1e-5 * rng.standard_normal(x.size)
    value, grad, _ = s.contact.evaluate(x, 2)
    assert value > 0 and np.count_nonzero(grad) > 0
    # small steps: near the cut's small surface features the closest-point type of a pair
    # (point-triangle, point-edge, ...) changes within 1e-7 of x, where the barrier's second
    # derivatives jump; the differences converge to the derivatives as h -> 0 (measured: the
    # Hessian's error 1e-2 at h = 1e-6, 1e-8 at h = 1e-9)
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


def test_a_sliver_thinner_than_the_gap_is_reported_as_in_contact_by_points():
    """A cut 0.1 mm from the end of a bar with dhat = 10 mm leaves a sliver whose contact
    region is empty even at dhat / 16 (contact/cut/thin_pieces.py): the rebuild warns that it has
    no contact surface and is in contact by points (tests/cutting/test_sliver_contact.py); a
    cut 5 mm from the end leaves one that gets a surface of its own (empty at the gap, 1
    dhat), and one 30 mm from the end a plain one."""
    for x0, bare in ((0.9999, True), (0.995, False), (0.97, False)):
        sim = ts.Simulation(BOX, ts.NeoHookean(youngs_modulus=1e5, poisson_ratio=0.3),
                            density=1000.0, integrator="quasistatic", time_step=1.0)  # fmt: skip
        sim.fix(np.flatnonzero(BOX.points[:, 0] < 1e-9))
        sim.set_contact(dhat=0.01)
        sim.cut_body(across(x0))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            _ = sim.system
        messages = [str(w.message) for w in caught]
        warned = any("too thin for a contact surface" in m and "points" in m for m in messages)
        assert warned == bare
