"""Cutting a FEM body during a run (Simulation.cut_body): the state carries over, a piece cut
off falls with g, the support then carries only what stays attached, mass is kept."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

G = 9.81


def through(x0: float) -> PlanarCut:
    """The plane x = x0 across the whole beam (a blade swept down through it)."""
    return PlanarCut.swept_segment(
        (x0, -1.0, 1.0), (x0, 2.0, 1.0), (x0, -1.0, -1.0), (x0, 2.0, -1.0)
    )


def cantilever() -> ts.Simulation:
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.2, 0.2), (10, 2, 2))
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
    return sim


def pieces(cells: np.ndarray, n: int) -> np.ndarray:
    """The connected piece (a label) of every node."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    k = cells.shape[1]
    rows = np.repeat(cells[:, 0], k)
    graph = coo_matrix((np.ones(cells.size), (rows, cells.ravel())), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def test_the_cut_carries_positions_and_velocities_to_every_copy():
    sim = cantilever()
    for _ in range(3):
        sim.step()
    x, v = sim.positions.copy(), sim.velocity.copy()
    report = sim.cut_body(through(0.47))
    assert report["new_nodes"] > 0 and len(report["origin"]) == len(x) + report["new_nodes"]
    np.testing.assert_array_equal(sim.positions, x[report["origin"]])
    np.testing.assert_array_equal(sim.velocity, v[report["origin"]])
    assert sim.time == pytest.approx(0.03)


def test_a_piece_cut_off_falls_with_g_and_the_wall_then_carries_the_rest():
    sim = cantilever()
    for _ in range(5):
        sim.step()
    mass = sim.model.mass.lumped.sum() / 3
    report = sim.cut_body(through(0.47))
    assert report["pieces"] == 2 and report["cells_cut"] > 0
    body = sim.bodies["body"]
    assert body.model.mass.lumped.sum() / 3 == pytest.approx(mass, rel=1e-12)  # no gram lost
    label = pieces(body.mesh.cells, body.mesh.n_points)
    clamped = body.mesh.points[:, 0] < 1e-9
    free = label != label[np.flatnonzero(clamped)[0]]
    assert free.any() and not free[clamped].any()
    m = body.model.mass.lumped.reshape(-1, 3)[:, 0]
    # 0.47 of the mass, as the blade cut the sagged beam where it was now (to 1e-4: the sag)
    assert m[~free].sum() == pytest.approx(0.47 * mass, rel=1e-3)
    z = []
    for _ in range(5):
        sim.step()
        z.append((m[free] @ sim.positions[free, 2]) / m[free].sum())
    np.testing.assert_allclose(np.diff(z, 2) / sim.time_step**2, -G, rtol=1e-2)
    # the wall carries the part still attached to it, oscillating about its weight
    assert 0.0 < sim.forces()["wall"][2] < 3.0 * m[~free].sum() * G


def test_cut_body_refuses_what_it_cannot_do_yet():
    sim = cantilever()
    sim.cut_body(through(0.47))
    mass = sim.model.mass.lumped.sum()
    with pytest.raises(InputError, match="keeps its plane"):  # one name, one plane
        sim.cut_body(through(0.83))
    assert sim.model.mass.lumped.sum() == mass


def oblique() -> PlanarCut:
    """A plane through the beam from x = 0.3 at its top to 0.6 at its bottom."""
    return PlanarCut.swept_segment((0.3, -1, 0.2), (0.3, 2, 0.2), (0.6, -1, 0.0), (0.6, 2, 0.0))


def test_a_second_cut_across_cells_cut_before_splits_them_further():
    """A cut through x = 0.47, then an oblique one crossing it in the cells around it: the
    cells both cross are split into their parts, the mass is kept, and the beam is in four
    pieces (either side of each cut); the support holds the one below the oblique cut and
    left of x = 0.47."""
    sim = cantilever()
    mass = sim.model.mass.lumped.sum() / 3
    sim.cut_body(through(0.47))
    report = sim.cut_body(oblique(), name="oblique")
    body = sim.bodies["body"]
    assert body.cut_state.vn.extra is not None  # cells both cuts cross
    assert report["pieces"] == 4 and report["cells_cut"] > 0
    assert body.model.mass.lumped.sum() / 3 == pytest.approx(mass, rel=1e-12)
    m = body.model.mass.lumped.reshape(-1, 3)[:, 0]
    label = pieces(body.mesh.cells, body.mesh.n_points)
    held = label == label[np.flatnonzero(body.mesh.points[:, 0] < 1e-9)[0]]
    # held: x < 0.47 below the oblique plane z = 0.2 (0.6 - x) / 0.3, a trapezoid in x-z
    # (x from 0.3 to 0.47 the plane runs from z = 0.2 down to 0.0867) plus x < 0.3
    cross = 0.3 * 0.2 + 0.5 * (0.2 + 0.2 * 0.13 / 0.3) * 0.17
    assert m[held].sum() == pytest.approx(mass * cross / 0.2, rel=1e-9)
    z = []
    for _ in range(5):  # the three pieces cut off fall with g (Backward Euler)
        sim.step()
        z.append((m[~held] @ sim.positions[~held, 2]) / m[~held].sum())
    np.testing.assert_allclose(np.diff(z, 2) / sim.time_step**2, -G, rtol=1e-2)


def test_crossing_cuts_in_2d_with_contact_on_part_the_strip_in_four():
    """A 2D strip held at x = 0 cut across (x = 0.47) and along (y = 0.23) with contact on:
    four pieces, the mass kept, and the steps after the cuts keep every cut edge apart from
    every other (2D contact where cuts meet: contact/cut/boundary_several.py)."""
    mesh = ts.rectangle((0.0, 0.0), (1.0, 0.4), (10, 4))
    material = ts.make_material("neo_hookean", youngs_modulus=1e6, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="backward_euler",
                        time_step=0.01, gravity=(0.0, -G))  # fmt: skip
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9), name="wall")
    sim.set_contact(dhat=1e-3)
    sim.cut_body(through(0.47))
    mass = sim.model.mass.lumped.sum()
    along = PlanarCut.swept_segment((-1, 0.23, 1), (2, 0.23, 1), (-1, 0.23, -1), (2, 0.23, -1))
    report = sim.cut_body(along, name="along")
    assert report["pieces"] == 4
    assert sim.model.mass.lumped.sum() == pytest.approx(mass, rel=1e-12)
    for _ in range(5):
        record = sim.step()
        assert record.converged and not sim.system.contact.intersecting(sim.state.x)


def test_a_second_cut_and_a_blade_going_on_step_by_step():
    """Three pieces from two named cuts, mass kept; a blade going down through the beam in
    three calls cuts the same cells with the same fractions as the whole cut at once (the body
    at rest), each call only the cells it has newly crossed completely."""
    sim = cantilever()
    mass = sim.model.mass.lumped.sum()
    sim.cut_body(through(0.47))
    report = sim.cut_body(through(0.83), name="second")
    assert report["pieces"] == 3
    assert sim.model.mass.lumped.sum() == pytest.approx(mass, rel=1e-12)

    def notch(depth: float) -> PlanarCut:  # from the top down to z = 0.2 - depth
        z = 0.2 - depth
        return PlanarCut.swept_segment((0.47, -1, 1), (0.47, 2, 1), (0.47, -1, z), (0.47, 2, z))

    once = cantilever()
    whole = once.cut_body(notch(0.2))
    stepwise = cantilever()
    cut = [stepwise.cut_body(notch(depth))["cells_cut"] for depth in (0.1, 0.15, 0.2)]
    # the top layer once the blade is through it, then the cells of the next it has crossed
    assert sum(cut) == whole["cells_cut"] and cut[0] > 0 and cut[2] > 0
    a, b = once.bodies["body"].mesh, stepwise.bodies["body"].mesh
    assert np.allclose(np.sort(a.cell_fractions), np.sort(b.cell_fractions), atol=1e-12)
    assert a.n_points == b.n_points and b.cell_fractions.sum() == pytest.approx(240, rel=1e-12)
    assert stepwise.cut_body(notch(0.2))["cells_cut"] == 0  # nothing new: no change


def test_a_blade_going_on_while_the_beam_sags_cuts_each_cell_where_it_was():
    sim = cantilever()
    mass = sim.model.mass.lumped.sum()
    for depth in (0.07, 0.14, 0.21):
        sim.step()
        z = 0.2 - depth
        sim.cut_body(PlanarCut.swept_segment((0.47, -1, 1), (0.47, 2, 1), (0.47, -1, z),
                                             (0.47, 2, z)))  # fmt: skip
    assert sim.bodies["body"].cut_state.vn.n_pieces == 2
    assert sim.model.mass.lumped.sum() == pytest.approx(mass, rel=1e-12)
    for _ in range(3):
        assert sim.step().converged


def _section_offsets(vn, X: np.ndarray, copies: np.ndarray, x0: float) -> np.ndarray:
    """Per copy: the largest distance of its section's corners (where it is now) from the
    plane x = x0, over its longest edge."""
    worst = np.zeros(len(copies))
    for k, i in enumerate(copies):
        level, x = vn.level[i], X[vn.cells[i]]
        edge = max(np.linalg.norm(x[a] - x[b]) for a in range(4) for b in range(a + 1, 4))
        for a in range(4):
            for b in range(a + 1, 4):
                if level[a] * level[b] < 0:
                    p = x[a] + level[a] / (level[a] - level[b]) * (x[b] - x[a])
                    worst[k] = max(worst[k], abs(p[0] - x0) / edge)
    return worst


def test_the_cut_follows_the_blade_within_one_percent_of_the_edge_while_the_beam_sags():
    """A blade going down through the sagging beam at x = 0.47 in three calls, three steps
    apart (the tip sags 6, 24, 56 mm): the corners of each newly cut cell's section, where the
    body is when it is cut, lie within 1 % of the cell's longest edge of the blade's plane
    (measured 0, 0.10 %, 0.79 %: a node keeps its distance from the first cut of a cell around
    it, so a cell cut later next to it has its section off the plane by what the body turned in
    between; at rest it is exact)."""
    sim = cantilever()
    done = np.zeros(0, dtype=int)
    for depth in (0.11, 0.16, 0.35):
        for _ in range(3):
            sim.step()
        z = 0.2 - depth
        report = sim.cut_body(PlanarCut.swept_segment((0.47, -1, 1), (0.47, 2, 1),
                                                      (0.47, -1, z), (0.47, 2, z)))  # fmt: skip
        vn = sim.bodies["body"].cut_state.vn
        new = np.flatnonzero((vn.side > 0) & ~np.isin(vn.parent, done))
        assert len(new) == report["cells_cut"] > 0
        offsets = _section_offsets(vn, sim.body_positions("body"), new, 0.47)
        assert offsets.max() < 0.01
        done = np.concatenate([done, vn.parent[new]])
    assert vn.n_pieces == 2


def test_the_run_after_a_cut_writes_the_cut_mesh_with_its_material_fractions(tmp_path):
    import meshio

    sim = cantilever()
    sim.run(2, tmp_path / "before", progress=False, render=False)
    report = sim.cut_body(through(0.47))
    sim.run(2, tmp_path / "after", progress=False, render=False)
    frame = meshio.read(tmp_path / "after" / "body_00002.vtu")
    n = 99 + report["new_nodes"]  # the 10 x 2 x 2 box has 99 vertices
    assert frame.points.shape == (n, 3) and frame.point_data["displacement"].shape == (n, 3)
    fraction = np.concatenate(frame.cell_data["material_fraction"])
    body = sim.bodies["body"]
    np.testing.assert_array_equal(fraction, body.mesh.cell_fractions)
    assert fraction.min() > 0.0 and np.count_nonzero(fraction < 1.0) == 2 * report["cells_cut"]
    assert "material_fraction" not in meshio.read(tmp_path / "before" / "body_00002.vtu").cell_data


def test_a_blade_moving_through_the_beam_cuts_it_step_by_step_and_reports_its_force():
    """add_cut(body=...): a straight blade going down through the beam at x = 0.47 from t =
    0.01 to 0.04 s; after each step the cells it has swept are cut; the beam parts at 0.04 s,
    and every step reports the pieces and the mass (kg, kept); the cut's area grows to the
    beam's section (0.04 m^2, rest) and the blade's force is the toughness times the new area
    over its travel, upward (against its motion)."""
    sim = cantilever()
    mass = sim.model.mass.lumped.sum()
    G_c = 500.0  # J/m^2

    def blade(t):
        z = 0.25 - 10.0 * (t - 0.01)  # from 5 cm above the beam down to 5 cm below it
        return np.array([[0.47, -0.5, z], [0.47, 0.7, z]])

    sim.add_cut(blade, 0.01, 0.04, body="body", name="scalpel", toughness=G_c)
    records = [sim.step() for _ in range(8)]
    cuts = [r.extra["cuts"]["scalpel"] for r in records]
    assert [c["cells_cut"] for c in cuts][0] == 0  # t = 0.01: not started
    # every step reports the body's pieces and mass, after the blade has stopped too
    assert [c["pieces"] for c in cuts] == [1, 1, 1, 2, 2, 2, 2, 2]
    assert [c["mass_kg"] for c in cuts] == pytest.approx([mass / 3] * 8, rel=1e-12)
    # the section's rest area, cut where the sagging beam is (its plane a little tilted in rest)
    assert cuts[-1]["pieces"] == 2 and cuts[-1]["area_m2"] == pytest.approx(0.04, rel=2e-3)
    assert sum(c["new_area_m2"] for c in cuts) == pytest.approx(cuts[-1]["area_m2"], rel=1e-12)
    for r, c in zip(records[1:4], cuts[1:4], strict=True):
        force = r.extra["forces"]["scalpel"]
        assert force[2] == pytest.approx(G_c * c["new_area_m2"] / 0.1, rel=1e-9)  # 0.1 m/step
        assert force[0] == 0.0 and force[1] == 0.0
    assert sim.model.mass.lumped.sum() == pytest.approx(mass, rel=1e-12)


def test_a_triangular_blade_cuts_what_its_positions_cover():
    """A flat triangular blade (a scalpel's tip) pushed down into the beam at x = 0.53, its tip
    from 5 cm above the beam to 5 cm below it,
    cuts what the hull of its positions covers, itself included: the same cells and area as
    cut_body with that hull, drawn by hand; it stays one piece (the bottom corners are left)."""

    def corners(z: float) -> np.ndarray:  # the blade's plane is x = 0.53
        return np.array([[0.53, -0.1, z + 0.2], [0.53, 0.3, z + 0.2], [0.53, 0.1, z]])

    sim = cantilever()
    sim.add_cut(lambda t: corners(0.15 - 20.0 * t), 0.0, 0.01, body="body", name="tip")
    record = sim.step()
    cut = record.extra["cuts"]["tip"]
    hull = np.array([[0.53, -0.1, 0.15], [0.53, 0.1, -0.05], [0.53, 0.3, 0.15],
                     [0.53, 0.3, 0.35], [0.53, -0.1, 0.35]])  # fmt: skip
    by_hand = cantilever()
    by_hand.step()
    expected = by_hand.cut_body(
        PlanarCut(np.array([0.53, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), hull), name="tip"
    )
    assert cut["cells_cut"] == expected["cells_cut"] > 0 and cut["pieces"] == 1
    assert cut["area_m2"] == pytest.approx(expected["area_m2"], rel=1e-12)
    with pytest.raises(InputError, match="straight edge or a triangle"):
        sim.add_cut(lambda t: np.eye(4, 3), 0.0, 0.5, body="body", name="square")


def test_add_cut_on_a_body_follows_a_blade_that_leaves_its_plane():
    """A blade that twists as it goes sweeps no plane: its cut follows its swept surface
    (tests/cutting/test_curved_cut.py); the bad blades are refused in one line."""
    sim = cantilever()
    tool = sim.add_cut(
        lambda t: np.array([[0.47 + t, -0.5, 0.3 - t], [0.47 - t, 0.7, 0.3 - t]]),
        0.0, 0.5, body="body", name="twist",
    )  # fmt: skip
    assert tool.curved
    with pytest.raises(InputError, match="straight edge"):
        sim.add_cut(lambda t: np.zeros((2, 2)), 0.0, 0.5, body="body")
    with pytest.raises(InputError, match="leave kerf out"):  # not silently ignored
        sim.add_cut(lambda t: np.zeros((2, 3)), 0.0, 0.5, body="body", kerf=0.001)


def test_a_cut_along_mesh_faces_parts_the_body_without_copying_elements():
    """The plane x = 0.5 of a 10 x 2 x 2 beam runs along element faces: no element is crossed,
    but the nodes on it part (the cut of a body that only parts nodes is still a cut)."""
    sim = cantilever()
    report = sim.cut_body(through(0.5))
    assert report["cells_cut"] == 0 and report["new_nodes"] == 9 and report["pieces"] == 2
    assert report["area_m2"] == pytest.approx(0.2 * 0.2, rel=1e-12)  # the faces it parted
    again = sim.cut_body(through(0.5))  # nothing new: the same area, not counted twice
    assert again["cells_cut"] == 0 and again["area_m2"] == pytest.approx(0.04, rel=1e-12)


def test_a_notch_along_mesh_faces_reports_the_faces_it_opened():
    """From the top (z = 0.2) down to the layer of nodes at z = 0.1 along x = 0.5: the faces
    above are parted, the nodes at z = 0.1 stay joined (the notch's front), area 0.2 x 0.1."""
    sim = cantilever()
    notch = PlanarCut.swept_segment(
        (0.5, -1.0, 1.0), (0.5, 2.0, 1.0), (0.5, -1.0, 0.1), (0.5, 2.0, 0.1)
    )
    report = sim.cut_body(notch, name="notch")
    assert report["cells_cut"] == 0 and report["pieces"] == 1 and report["new_nodes"] == 3
    assert report["area_m2"] == pytest.approx(0.2 * 0.1, rel=1e-12)


def test_a_cut_body_keeps_its_rayleigh_damping():
    sim = cantilever()
    sim.set_damping(mass=2.0, stiffness=1e-3)
    sim.step()
    sim.cut_body(through(0.47))
    assert sim.bodies["body"].model.damping == (2.0, 1e-3)
