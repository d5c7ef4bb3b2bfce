"""A piece of a cut body too thin for a contact surface, even one built at the thin pieces'
smallest scale (``contact/cut/thin_pieces.py``), is in contact by points
(``contact/cut/sliver_points.py``): it falls onto the floor and rests there with its weight on it
instead of passing through; its points start outside every barrier; their barrier's
derivatives match finite differences; the points cover a 2D sliver too. The slivers here would
get a surface of their own (``tests/cutting/test_thin_pieces.py``): every test takes that away
(no scale is tried), so the points are what holds them."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from test_cut_contact import G, across, block_on_floor

import tissuesim as ts
from tissuesim.contact.cut.sliver_points import LIFT, MERGE

DHAT = 1e-3  # block_on_floor's


@pytest.fixture(autouse=True)
def points_only(monkeypatch):
    """No thin piece gets a surface of its own: contact points are all it has."""
    import tissuesim.contact.cut.thin_pieces as thin_pieces

    monkeypatch.setattr(thin_pieces, "SCALES", ())


def sliver_on_floor(x0: float):
    """block_on_floor held rigid but for its last 5 cm, cut at x0 near its end: the sliver
    beyond x0 (1 - x0 thick) falls 5 cm onto the floor. (sim, its contact model, the
    warnings of the rebuild)."""
    sim = block_on_floor()
    sim.fix(np.flatnonzero(sim.mesh.points[:, 0] < 0.95), name="held")
    sim.cut_body(across(x0))  # at rest: the levels are distances at rest
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        contact = sim.system.contact
    return sim, contact, [str(w.message) for w in caught]


def _sliver_on_floor(x0: float):
    """sliver_on_floor with the contact surface and its points."""
    sim, contact, messages = sliver_on_floor(x0)
    surface = contact.surfaces[0]
    points = np.flatnonzero(np.isfinite(surface.point_areas))
    return sim, contact, surface, points, messages


def _point_positions(sim, contact, surface, points):
    return contact.vertices(sim.state.x)[contact.slices[surface.name][0]][points]


@pytest.mark.parametrize("x0", [0.9995, 0.9985])
def test_a_sliver_falls_onto_the_floor_and_rests_on_its_points(x0):
    sim, contact, surface, points, messages = _sliver_on_floor(x0)
    assert any(f"in contact by {len(points)} points" in m for m in messages)
    assert len(points) >= 20
    rest = surface.rest[points]
    # in the sliver, off its cut face by LIFT dhat or half its thickness, a dhat apart
    thickness = 1.0 - x0
    assert rest[:, 0].max() <= 1.0 + 1e-12
    assert rest[:, 0].min() >= x0 + min(LIFT * DHAT, thickness / 2) - 1e-12
    gaps = np.linalg.norm(rest[:, None] - rest[None], axis=2) + np.eye(len(rest))
    assert gaps.min() >= MERGE * DHAT * (1 - 1e-9)
    # their areas share the cut face's: 0.2 x 0.2
    assert surface.point_areas[points].sum() == pytest.approx(0.04, rel=1e-9)
    # nothing pushes at rest: the points start outside the barrier of the block's cut face
    assert contact.evaluate(sim.state.x, 0)[0] == 0.0
    weight = 1000.0 * 0.2 * 0.2 * thickness * G
    floor = []
    for _ in range(80):
        record = sim.step()
        z = _point_positions(sim, contact, surface, points)[:, 2]
        assert z.min() > 0.0  # never through the floor
        floor.append(record.extra["forces"]["floor"][2])
    assert floor[0] == 0.0  # 5 cm above the floor: not yet
    assert z.min() < DHAT  # on it
    assert np.median(floor[-10:]) == pytest.approx(weight, rel=1e-3)  # resting with its weight


def test_the_barrier_on_a_slivers_points_matches_finite_differences():
    """The points' barrier (their weights set to their areas) against central differences,
    the sliver resting on the floor: gradient and exact Hessian over the body's nodes."""
    sim, contact, surface, points, _ = _sliver_on_floor(0.9995)
    for _ in range(30):
        sim.step()
    x = sim.state.x
    value, grad, _ = contact.evaluate(x, 2)
    assert value > 0.0
    rng = np.random.default_rng(3)
    # small steps: the points rest where the barrier is steep (its differences converge as
    # h^2 with the error 1 % at h = 1e-7, 1e-6 at 1e-9)
    for _ in range(5):
        d = rng.standard_normal(x.size)
        h = 1e-10
        fd = (contact.evaluate(x + h * d, 0)[0] - contact.evaluate(x - h * d, 0)[0]) / (2 * h)
        assert fd == pytest.approx(grad @ d, rel=1e-6, abs=1e-9 * abs(value))
    exact = contact.evaluate(x, 2, project=False)[2]
    for _ in range(3):
        d = rng.standard_normal(x.size)
        h = 1e-10
        fd = (contact.evaluate(x + h * d, 1)[1] - contact.evaluate(x - h * d, 1)[1]) / (2 * h)
        assert np.linalg.norm(fd - exact @ d) <= 1e-5 * np.linalg.norm(exact @ d)


def test_a_2d_sliver_gets_points_along_its_cut_edge():
    """A 2D strip cut 0.5 mm from its end with dhat 1 mm: points in the sliver, a dhat apart,
    whose lengths share the cut's (the strip's height)."""
    mesh = ts.rectangle((0.0, 0.0), (1.0, 0.2), (10, 2))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=1e5, poisson_ratio=0.3),
                        density=1000.0, integrator="quasistatic")  # fmt: skip
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9))
    sim.set_contact(dhat=DHAT)
    sim.cut_body(across(0.9995))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        surface = sim.system.contact.surfaces[0]
    assert any("points" in str(w.message) for w in caught)
    points = np.flatnonzero(np.isfinite(surface.point_areas))
    rest = surface.rest[points]
    assert len(points) >= 2
    assert (rest[:, 0] >= 0.9995 + 0.25 * DHAT - 1e-12).all() and (rest[:, 0] <= 1.0).all()
    assert surface.point_areas[points].sum() == pytest.approx(0.2, rel=1e-9)


def strip_over_floor_2d() -> ts.Simulation:
    """A 2D strip held but for its last 5 cm, 5 cm above a floor body held along its bottom
    (dhat 1 mm, gravity along -y), cut 0.5 mm from its end: the slice is to fall."""
    material = ts.make_material("neo_hookean", youngs_modulus=1e6, poisson_ratio=0.3)
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01, gravity=(0.0, -G))
    strip = sim.add_body("strip", ts.rectangle((0, 0.05), (1, 0.25), (10, 2)), material,
                         density=1000.0)  # fmt: skip
    floor = sim.add_body("floor", ts.rectangle((-0.1, -0.1), (1.6, 0), (17, 1)), material,
                         density=1.0)  # fmt: skip
    sim.fix("strip", np.flatnonzero(strip.mesh.points[:, 0] < 0.95), name="held")
    sim.fix("floor", np.flatnonzero(floor.mesh.points[:, 1] < -0.1 + 1e-9), name="support")
    sim.set_contact(dhat=DHAT)
    sim.cut_body(across(0.9995), body="strip")
    return sim


def test_a_2d_sliver_falls_onto_a_floor_body_and_rests_on_its_points():
    """A 0.5 mm slice of a 2D strip (its last 5 cm held, dhat 1 mm) falls 5 cm onto a floor
    body, topples onto its side and rests there: the floor's support then carries its weight
    (per metre of thickness) to 1e-3, and no point goes below the floor."""
    sim = strip_over_floor_2d()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        contact = sim.system.contact
    surface = contact.surfaces[0]
    points = np.flatnonzero(np.isfinite(surface.point_areas))
    floor_weight = sim.bodies["floor"].model.mass.lumped.sum() / 2 * G
    support = []
    for _ in range(70):
        record = sim.step()
        assert _point_positions(sim, contact, surface, points)[:, 1].min() > 0.0
        support.append(record.extra["forces"]["support"][1] - floor_weight)
    weight = 1000.0 * 0.2 * 0.0005 * G
    assert abs(support[0]) < 1e-3 * weight  # 5 cm above the floor: not yet (its own settling)
    assert np.median(support[-20:]) == pytest.approx(weight, rel=1e-3)


def test_a_point_weighs_as_a_surface_vertex_of_its_area():
    """ipctk weighs a vertex without edges or faces as 1 m^2 (a surface vertex: its area,
    a third of its triangles', over 4 in a vertex-face collision); ``weigh_points`` makes a
    point of area A weigh as a surface vertex of area A, so the barrier's value scales by A."""
    import ipctk

    from tissuesim.contact.cut.sliver_points import weigh_points

    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0.004], [0.6, 0.1, 0.02],
                  [0.9, 0.1, 0.02], [0.6, 0.4, 0.02]], dtype=float)  # fmt: skip
    F = np.array([[0, 1, 2], [4, 5, 6]], dtype=np.int32)
    mesh = ipctk.CollisionMesh(V, ipctk.edges(F), F)
    assert list(mesh.codim_vertices) == [3] and mesh.vertex_areas[3] == 1.0

    def collisions():
        col = ipctk.NormalCollisions()
        col.use_area_weighting = True
        col.build(mesh, V, 0.01)
        return col

    plain, weighed = collisions(), collisions()
    (fv,) = [c for c in plain.fv_collisions if c.vertex_id == 3]
    assert fv.weight == pytest.approx(0.25)  # 1 m^2 / 4
    area = np.full(len(V), np.nan)
    area[3] = 2.5e-4
    weigh_points(weighed, area)
    (fv,) = [c for c in weighed.fv_collisions if c.vertex_id == 3]
    assert fv.weight == pytest.approx(2.5e-4 / 4)
    barrier = ipctk.BarrierPotential(0.01, 1.0)
    assert barrier(weighed, mesh, V) == pytest.approx(2.5e-4 * barrier(plain, mesh, V))


def slice_with_friction() -> ts.Simulation:
    """block_on_floor's beam held but for its last 5 cm, friction 0.5 on the floor, cut 0.5 mm
    from its end: the slice is to fall onto its edge."""
    from tissuesim.contact.obstacles import plane

    mesh = ts.box((0.0, 0.0, 0.05), (1.0, 0.2, 0.25), (10, 2, 2))
    sim = ts.Simulation(mesh, ts.make_material("neo_hookean", youngs_modulus=1e6,
                        poisson_ratio=0.3), density=1000.0, integrator="backward_euler",
                        time_step=0.01, gravity=(0.0, 0.0, -G))  # fmt: skip
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 0.95), name="held")
    sim.set_contact(dhat=DHAT, friction=0.5)
    sim.add_obstacle("floor", plane((0.5, 0.1, 0.0), (0, 0, 1), 3.0))
    sim.cut_body(across(0.9995))
    return sim


def test_a_sliver_with_friction_stands_on_its_edge_with_its_weight():
    """The 0.5 mm slice with friction 0.5 on the floor: the friction, built from the points'
    weighed collisions, keeps it standing on its edge; the floor carries its weight to 1e-3
    with a sideways force within the friction cone."""
    sim = slice_with_friction()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        contact = sim.system.contact
    surface = contact.surfaces[0]
    points = np.flatnonzero(np.isfinite(surface.point_areas))
    for _ in range(60):
        record = sim.step()
        assert _point_positions(sim, contact, surface, points)[:, 2].min() > 0.0
    floor = np.array(record.extra["forces"]["floor"])
    weight = 1000.0 * 0.2 * 0.2 * 0.0005 * G
    assert floor[2] == pytest.approx(weight, rel=1e-3)
    assert 0.0 < np.hypot(floor[0], floor[1]) <= 0.5 * floor[2]
    x = _point_positions(sim, contact, surface, points)[:, 0]
    assert np.ptp(x) < 1e-3  # still upright: its points in one vertical plane
