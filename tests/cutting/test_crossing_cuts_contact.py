"""Contact of a body two cuts cross in the same cells (contact/cut/surface.py with several
levels per copy): the surface is closed, oriented and free of intersection where the cuts
cross and where one ends at the other, its enclosed volume is the body's less both slabs
(their overlap counted once), and pieces cut apart by two cuts fall onto a floor and onto
each other and rest there."""

from __future__ import annotations

import ipctk
import numpy as np
import pytest
from test_cut_contact import block_on_floor  # pytest puts this folder on the path

import tissuesim as ts
from tissuesim.contact.cut.surface import GAP, cut_surface
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, virtual_node_cut

G = 9.81
DHAT = 0.01
BOX = ts.box((0.0, 0.0, 0.0), (1.0, 0.4, 0.3), (10, 4, 3))


def plane_cut(point, normal, lo=(-1.0, -1.0, -1.0), hi=(2.0, 2.0, 2.0)) -> PlanarCut:
    """The plane through ``point`` with ``normal`` (along x, y or z), bounded by a box."""
    normal = np.asarray(normal, dtype=float)
    axis = int(np.argmax(np.abs(normal)))
    u, w = [i for i in range(3) if i != axis]
    corners = []
    for a, b in ((lo[u], lo[w]), (hi[u], lo[w]), (hi[u], hi[w]), (lo[u], hi[w])):
        c = np.array(point, dtype=float)
        c[u], c[w] = a, b
        corners.append(c)
    return PlanarCut(np.asarray(point, dtype=float), normal, np.array(corners))


def tilted(point, normal) -> PlanarCut:
    """A plane through ``point`` with any ``normal``, bounded far outside the box."""
    n = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    u = np.cross(n, [0.3, 0.1, 1.0])
    u /= np.linalg.norm(u)
    w = np.cross(n, u)
    p0 = np.asarray(point, dtype=float)
    corners = [p0 + 3 * (a * u + b * w) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return PlanarCut(p0, n, np.array(corners))


def ending_at(point, normal, x_end: float) -> PlanarCut:
    """A plane through ``point`` with ``normal``, its polygon ending where x = ``x_end`` (a
    blade stopped there), far out on its other sides."""
    n = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    u = np.cross(n, [0.0, 0.0, 1.0])
    u /= np.linalg.norm(u)
    u = u if u[0] > 0 else -u
    w = np.cross(n, u)
    p0 = np.asarray(point, dtype=float)
    end = (x_end - p0[0]) / u[0]
    corners = [p0 + a * u + b * w for a, b in ((-3, -3), (end, -3), (end, 3), (-3, 3))]
    return PlanarCut(p0, n, np.array(corners))


def v_side(slope: float, x_apex=0.5, z_apex=0.15, toward=1.0, past=0.0) -> PlanarCut:
    """One side of a V: the plane through the line x = x_apex, z = z_apex (along y) rising
    by ``slope`` towards ``toward`` x (+1 or -1), from ``past`` (m) beyond that line on to
    beyond the box (a blade that stopped there)."""
    n = np.array([-slope, 0.0, toward]) / np.hypot(slope, 1.0)
    w = np.array([toward, 0.0, slope]) / np.hypot(slope, 1.0)
    u = np.array([0.0, 1.0, 0.0])
    p0 = np.array([x_apex, 0.2, z_apex])
    corners = [p0 + a * u + b * w for a, b in ((-3, -past), (3, -past), (3, 3), (-3, 3))]
    return PlanarCut(p0, n, np.array(corners))


CASES = {
    # two through cuts crossing: along the line x = 0.47, y = 0.23 (through cells)
    "cross": [plane_cut((0.47, 0, 0), (1, 0, 0)), plane_cut((0, 0.23, 0), (0, 1, 0))],
    # a T: the second cut from the first to the mesh plane x = 0.5 only
    "tee": [
        plane_cut((0.47, 0, 0), (1, 0, 0)),
        plane_cut((0, 0.23, 0), (0, 1, 0), hi=(0.5, 2.0, 2.0)),
    ],
    # a T at a slant: the second cut ends inside the cells the first crosses, so the sections
    # of the first meet the front of the second inside cell faces (points inserted there)
    "oblique-tee": [
        tilted((0.47, 0.2, 0.15), (1, 0.2, 0.1)),
        ending_at((0.3, 0.23, 0.15), (0.2, 1, 0.25), 0.48),
    ],
    # a V: two cuts end at the same line, so the faces of the cells beyond it meet parts that
    # two cuts bound, neither of which crosses those cells (their exposed parts are not convex)
    "vee": [v_side(0.4), v_side(-0.4)],
    "oblique-cross": [
        tilted((0.47, 0.2, 0.15), (1, 0.3, 0.2)),
        tilted((0.5, 0.23, 0.15), (0.2, 1, 0.4)),
    ],
}


def surface(name, dhat=DHAT):
    cut = virtual_node_cut(BOX.points, BOX.cells, CASES[name])
    if name == "vee":
        assert cut.n_pieces == 2  # the wedge comes out
    assert cut.extra is not None  # cells both cuts cross
    cm = cut.to_mesh(BOX)
    W, tri = cut_surface(cm, dhat)
    return cm, W, tri, W @ cm.points


@pytest.mark.parametrize("name", list(CASES))
def test_where_cuts_cross_the_surface_is_closed_oriented_and_free_of_intersection(name):
    cm, W, tri, V = surface(name)
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    directed = edges[:, 0] * len(V) + edges[:, 1]
    reverse = edges[:, 1] * len(V) + edges[:, 0]
    assert np.unique(directed).size == directed.size  # each directed edge once: a manifold
    assert np.isin(reverse, directed).all()  # and each has its reverse: closed, oriented
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-12)
    mesh = ipctk.CollisionMesh(np.asfortranarray(V), ipctk.edges(tri.astype(np.int32)), tri)
    assert not ipctk.has_intersections(mesh, V)
    if name.startswith("oblique"):  # near where cuts meet, points on the two cut faces can come
        return  # closer than 0.3 dhat (docs/organ-cutting.md: measured over random crossings)
    collisions = ipctk.NormalCollisions()
    collisions.build(mesh, V, 0.3 * DHAT)
    assert len(collisions) == 0


@pytest.mark.parametrize(
    ("name", "areas", "overlap"),
    [("cross", (0.4 * 0.3, 1.0 * 0.3), 0.3), ("tee", (0.4 * 0.3, 0.5 * 0.3), 0.3)],
)
def test_the_enclosed_volume_is_the_body_less_both_slabs(name, areas, overlap, monkeypatch):
    """Divergence theorem: the block less 2 gap times each cut's area, plus the prism both
    slabs share (2 gap x 2 gap x the crossing's length), counted twice; no node of this block
    is within the snapping band and short edges are left unmerged, so the level sets are
    exact."""
    import tissuesim.contact.cut.surface as module

    monkeypatch.setattr(module, "MERGE", 0.0)
    cm, W, tri, V = surface(name)
    volume = np.einsum("ij,ij->i", V[tri[:, 0]], np.cross(V[tri[:, 1]], V[tri[:, 2]])).sum() / 6
    g = GAP * DHAT
    expected = 0.12 - 2 * g * sum(areas) + (2 * g) ** 2 * overlap
    assert volume == pytest.approx(expected, rel=1e-12)


def test_four_pieces_of_two_cuts_fall_onto_the_floor_and_onto_each_other():
    """A beam held at x = 0 is cut across at x = 0.47 and along its length at z = 0.17: the
    two pieces beyond x = 0.47 fall 5 cm, the lower onto the floor and the upper onto it, and
    rest there; the floor carries both, and no surface ever passes through another."""
    sim = block_on_floor()
    sim.step()
    mass = sim.system.bodies[0].mass.lumped.sum() / 3
    sim.cut_body(plane_cut((0.47, 0, 0), (1, 0, 0)), name="across")
    report = sim.cut_body(plane_cut((0, 0, 0.17), (0, 0, 1)), name="along")
    assert report["pieces"] == 4
    outer_pieces_fall_and_rest(sim, mass)


def outer_pieces_fall_and_rest(sim, mass: float) -> None:
    """The beam of ``block_on_floor``, cut across at x = 0.47 (and more): its mass is kept,
    no step intersects over 40, the floor carries nothing at first and then the weight of
    everything beyond x = 0.47 to 1e-3."""
    assert sim.system.bodies[0].mass.lumped.sum() / 3 == pytest.approx(mass, rel=1e-12)
    contact = sim.system.contact
    floor = []
    for _ in range(40):
        record = sim.step()
        assert not contact.intersecting(sim.state.x)  # exact: the collision mesh now
        floor.append(record.extra["forces"]["floor"][2])
    pieces = 1000.0 * 0.2 * 0.2 * (1 - 0.47) * G
    assert floor[0] == 0.0
    assert np.median(floor[-10:]) == pytest.approx(pieces, rel=1e-3)


def test_a_wedge_cut_out_of_a_beam_rests_in_its_groove():
    """Two cuts from the top of a held beam cross 13 cm down (a V, each cut 5 cm past the
    other): the wedge between them is free and sinks into its groove under gravity, where the
    groove's two faces hold it (free, it would fall 20 cm in these 0.2 s); no surface passes
    through another."""
    mesh = ts.box((0.0, 0.0, 0.05), (1.0, 0.2, 0.25), (10, 2, 4))
    material = ts.make_material("neo_hookean", youngs_modulus=1e7, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="backward_euler",
                        time_step=0.01, gravity=(0.0, 0.0, -G))  # fmt: skip
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9), name="wall")
    sim.set_contact(dhat=1e-3)
    sim.step()
    sim.cut_body(v_side(1.0, 0.53, 0.12, toward=-1.0, past=0.05), name="left")
    report = sim.cut_body(v_side(1.0, 0.53, 0.12, past=0.05), name="right")
    assert report["pieces"] == 2
    body = sim.bodies["body"]
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    cells, n = body.mesh.cells, body.mesh.n_points
    graph = coo_matrix((np.ones(cells.size), (np.repeat(cells[:, 0], 4), cells.ravel())), (n, n))
    label = connected_components(graph, directed=False)[1]
    wedge = label != label[np.flatnonzero(body.mesh.points[:, 0] < 1e-9)[0]]
    beam = ~wedge
    contact = sim.system.contact
    start = sim.positions[:, 2].copy()
    for _ in range(20):
        record = sim.step()
        assert record.converged and not contact.intersecting(sim.state.x)
    sink = start - sim.positions[:, 2]
    around = beam & (np.abs(body.mesh.points[:, 0] - 0.53) < 0.15)
    # the wedge goes down with the beam around it (its sag there), not 20 cm
    assert np.mean(sink[wedge]) == pytest.approx(np.mean(sink[around]), abs=0.01)


ALONG_FACES = {
    # a cut along the mesh plane x = 0.5 (it parts nodes, copies no cell) crossed by one
    # through cells: the copies next to the first are shaved by it as whole cells are
    "along-faces-then-through": [
        plane_cut((0.5, 0, 0), (1, 0, 0)),
        plane_cut((0, 0.23, 0), (0, 1, 0)),
    ],
    "through-then-along-faces": [
        plane_cut((0, 0.23, 0), (0, 1, 0)),
        plane_cut((0.5, 0, 0), (1, 0, 0)),
    ],
    "both-along-faces": [plane_cut((0.5, 0, 0), (1, 0, 0)), plane_cut((0, 0.2, 0), (0, 1, 0))],
}


@pytest.mark.parametrize("name", list(ALONG_FACES))
def test_a_cut_along_faces_crossed_by_another_leaves_a_closed_surface(name, monkeypatch):
    """Closed, oriented, free of intersection, nothing within 0.3 dhat at rest, and the
    enclosed volume the block's less both slabs plus their shared prism (exact: no merging)."""
    import tissuesim.contact.cut.surface as module

    monkeypatch.setattr(module, "MERGE", 0.0)
    cm = virtual_node_cut(BOX.points, BOX.cells, ALONG_FACES[name]).to_mesh(BOX)
    W, tri = cut_surface(cm, DHAT)
    V = W @ cm.points
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    directed = edges[:, 0] * len(V) + edges[:, 1]
    reverse = edges[:, 1] * len(V) + edges[:, 0]
    assert np.unique(directed).size == directed.size
    assert np.isin(reverse, directed).all()
    mesh = ipctk.CollisionMesh(np.asfortranarray(V), ipctk.edges(tri.astype(np.int32)), tri)
    assert not ipctk.has_intersections(mesh, V)
    collisions = ipctk.NormalCollisions()
    collisions.build(mesh, V, 0.3 * DHAT)
    assert len(collisions) == 0
    volume = np.einsum("ij,ij->i", V[tri[:, 0]], np.cross(V[tri[:, 1]], V[tri[:, 2]])).sum() / 6
    g = GAP * DHAT
    expected = 0.12 - 2 * g * (0.4 * 0.3 + 1.0 * 0.3) + (2 * g) ** 2 * 0.3
    assert volume == pytest.approx(expected, rel=1e-12)
