"""Surface pairs of one piece of a cut body that lie within dhat of each other at rest (where
cuts meet) do not collide (contact/cut/rest_proximity.py): a body cut where cuts cross feels no
contact force at rest, while pairs of different pieces, and bodies that are not cut, keep
theirs."""

from __future__ import annotations

import ipctk
import numpy as np
from test_crossing_cuts_contact import BOX, CASES, DHAT

import tissuesim as ts
from tissuesim.contact.cut.rest_proximity import rest_proximity_filter
from tissuesim.contact.cut.surface import cut_surface
from tissuesim.mesh.cutting.virtual_nodes import virtual_node_cut


def test_a_body_cut_where_cuts_cross_feels_no_contact_force_at_rest():
    """Two oblique cuts crossing in a box (dhat 1 cm): its cut surface has pairs of one piece
    within dhat at rest, which the barrier would push apart; in the simulation none of them
    collides, the contact energy and force at rest are zero, and a step without load takes
    no Newton iteration (nothing moves)."""
    vn = virtual_node_cut(BOX.points, BOX.cells, CASES["oblique-cross"])
    W, tri = cut_surface(vn.to_mesh(BOX), DHAT)
    V = np.asfortranarray(W @ vn.points)
    plain = ipctk.CollisionMesh(V, ipctk.edges(tri.astype(np.int32)), tri)
    close = ipctk.NormalCollisions()
    close.build(plain, V, DHAT)
    assert len(close) > 0  # without the filter the barrier acts at rest

    material = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(BOX, material, density=1000.0, integrator="backward_euler",
                        time_step=0.01)  # fmt: skip
    sim.set_contact(dhat=DHAT)
    for k, cut in enumerate(CASES["oblique-cross"]):
        sim.cut_body(cut, name=f"cut{k}")
    contact = sim.system.contact
    x = sim.state.x
    assert len(contact._collisions(contact.vertices(x))) == 0
    value, gradient, _ = contact.evaluate(x, 1)
    assert value == 0.0 and not np.any(gradient)
    record = sim.step()
    assert record.newton_iterations == 0
    np.testing.assert_array_equal(sim.state.x, x)


def _surface():
    """Vertices and triangles: a strip of three triangles whose last vertex (6) lies 1e-4
    above the first triangle (one piece folded onto itself), and a separate triangle whose
    vertex 9 lies 1e-4 above it too (another piece)."""
    V = np.array(
        [
            [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],  # T0
            [1.0, 1.0, 0.5], [0.6, 1.2, 1.0],  # T1 = (2, 3, 4) up and over
            [0.2, 0.6, 1.0], [0.2, 0.2, 1e-4],  # T2 = (4, 5, 6) back down onto T0
            [0.5, -1.0, 1.0], [0.8, -1.0, 1.0], [0.5, 0.3, 1e-4],  # T3 = (7, 8, 9)
        ]
    )  # fmt: skip
    F = np.array([[0, 1, 2], [2, 3, 4], [4, 5, 6], [7, 8, 9]], dtype=np.int32)
    return np.asfortranarray(V), F


def _pairs(mesh, V) -> set[tuple[int, ...]]:
    collisions = ipctk.NormalCollisions()
    collisions.build(mesh, V, 1e-3)
    E, F = mesh.edges, mesh.faces
    return {tuple(sorted(i for i in c.vertex_ids(E, F) if i >= 0)) for c in collisions}


def test_only_pairs_of_one_piece_of_a_cut_surface_are_left_out():
    V, F = _surface()
    mesh = ipctk.CollisionMesh(V, ipctk.edges(F), F)
    before = _pairs(mesh, V)
    assert (0, 1, 2, 6) in before and (0, 1, 2, 9) in before
    assert rest_proximity_filter(ipctk, mesh, V, np.zeros(len(V), bool), 1e-3) is None
    mesh.can_collide = rest_proximity_filter(ipctk, mesh, V, np.ones(len(V), bool), 1e-3)
    after = _pairs(mesh, V)
    assert (0, 1, 2, 9) in after  # another piece: still in contact
    assert not any(6 in p and set(p) & {0, 1, 2} for p in after)  # its own fold: left out
