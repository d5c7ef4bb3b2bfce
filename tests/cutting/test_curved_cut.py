"""A blade that leaves its plane cuts along the surface it sweeps (mesh/cutting/swept_cut.py): an
edge swept along a circular arc through a block cuts it along the cylinder, within 1 % of the local
edge length, into two pieces, with its mass kept; an instrument driven out of its first plane goes
on cutting along its new path."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tissuesim as ts

R, CENTRE = 0.2, np.array([-0.15, 0.05])  # the arc: x = -0.15 + sqrt(R^2 - (y - 0.05)^2)


def _arc(t: float) -> np.ndarray:
    """The blade at t in [0, 1]: a vertical edge on the cylinder, swept from y = -0.02 to
    y = 0.12 (through the block's whole width)."""
    y = -0.02 + 0.14 * t
    x = CENTRE[0] + math.sqrt(R * R - (y - CENTRE[1]) ** 2)
    return np.array([[x, y, -0.01], [x, y, 0.05]])


def _block(divisions: int = 12) -> ts.Simulation:
    mesh = ts.box((0, 0, 0), (0.1, 0.1, 0.04), (divisions, divisions, 4))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=3e3, poisson_ratio=0.3),
                        density=1000.0, integrator="quasistatic", time_step=0.125)  # fmt: skip
    sim.fix(ts.select.vertices_on_plane(mesh, axis=2, value=0.0))
    return sim


def _section_points(vn) -> tuple[np.ndarray, np.ndarray]:
    """The zero set's corners of every cut copy's level (rest positions) and their cells'
    longest edges."""
    cut = np.flatnonzero(vn.side != 0)
    x = vn.points[vn.cells[cut]]
    d = vn.level[cut]
    pts, size = [], []
    for i, j in ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)):
        cross = d[:, i] * d[:, j] < 0
        t = d[cross, i] / (d[cross, i] - d[cross, j])
        pts.append(x[cross, i] + t[:, None] * (x[cross, j] - x[cross, i]))
        edges = np.linalg.norm(x[cross][:, :, None] - x[cross][:, None, :], axis=3)
        size.append(edges.max(axis=(1, 2)))
    return np.concatenate(pts), np.concatenate(size)


def test_an_arc_cuts_the_block_along_its_cylinder():
    sim = _block()
    mass = sim.body().model.mass.matrix().sum() / 3
    sim.add_cut(_arc, 0.0, 1.0, body="body", name="arc")
    for _ in range(8):
        record = sim.step()
    body = sim.body()
    vn = body.cut_state.vn
    assert record.extra["cuts"]["arc"]["pieces"] == 2
    # the cut surface against the swept cylinder: within 1 % of the local edge
    q, h = _section_points(vn)
    off = np.abs(np.linalg.norm(q[:, :2] - CENTRE, axis=1) - R)
    assert len(q) > 100 and np.max(off / h) <= 0.01
    # the whole height and width cut: the area is the cylinder's inside the block
    y0, y1 = 0.0, 0.1
    arc_length = R * (math.asin((y1 - CENTRE[1]) / R) - math.asin((y0 - CENTRE[1]) / R))
    assert record.extra["cuts"]["arc"]["area_m2"] == pytest.approx(arc_length * 0.04, rel=1e-3)
    assert body.model.mass.matrix().sum() / 3 == pytest.approx(mass, rel=1e-9)


def test_a_curved_cut_in_contact_stays_closed_and_free_of_intersection(monkeypatch):
    """The same arc through a sagging block with contact on: every step intersection-free
    (exact), the two pieces apart, the embedded cut surface closed, oriented and free of
    intersection. On one contact thread: ipctk's parallel sums differ in the last bit from run
    to run, and the cut takes the cells where the body is."""
    ipctk = pytest.importorskip("ipctk")
    before = ipctk.get_num_threads()
    monkeypatch.setenv("TISSUESIM_CONTACT_THREADS", "1")
    from tissuesim.contact.cut.surface import cut_surface

    sim = _block(divisions=10)
    sim.add_gravity((0.0, 0.0, -9.81))
    sim.set_contact(dhat=2e-4)
    sim.add_cut(_arc, 0.0, 1.0, body="body", name="arc")
    for _ in range(8):
        record = sim.step()
        assert not sim.system.contact.intersecting(sim.state.x)
    assert record.extra["cuts"]["arc"]["pieces"] == 2
    cm = sim.body().mesh
    W, tri = cut_surface(cm, 2e-4)
    V = W @ cm.points
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    directed = edges[:, 0] * len(V) + edges[:, 1]
    assert np.unique(directed).size == directed.size  # a manifold
    assert np.isin(edges[:, 1] * len(V) + edges[:, 0], directed).all()  # closed, oriented
    mesh = ipctk.CollisionMesh(np.asfortranarray(V), ipctk.edges(tri.astype(np.int32)), tri)
    assert not ipctk.has_intersections(mesh, V)
    ipctk.set_num_threads(before)
