"""Coupled organs + tissue: force balance, limits of tissue stiffness, cutting, tearing,
Newton's convergence and errors."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.materials import make_material
from tissuesim.mesh import box
from tissuesim.simulation import Simulation
from tissuesim.solve.newton import NewtonOptions

GAP = 0.2


def _inside(p):
    return (p[:, 0] > 0) & (p[:, 0] < 1) & (p[:, 1] > 0) & (p[:, 1] < 1)


def two_boxes(
    integrator="quasistatic",
    gravity=9.81,
    tissue_E=300.0,
    fix_lower=True,
    time_step=0.25,
    lift=0.1,
    ramp=1.0,
    peel=False,
    tissue_density=10.0,
    grasper_stiffness=None,
):
    lower = box((0, 0, -0.5), (1, 1, 0), (3, 3, 2))
    upper = box((0, 0, GAP), (1, 1, GAP + 0.5), (3, 3, 2))
    mat = make_material("neo_hookean", youngs_modulus=1000.0, poisson_ratio=0.3)
    sim = Simulation(
        integrator=integrator,
        time_step=time_step,
        gravity=None if gravity is None else (0, 0, -gravity),
    )
    sim.add_body("lower", lower, mat, density=10.0)
    sim.add_body("upper", upper, mat, density=10.0)
    if fix_lower:
        sim.fix("lower", lower.point_sets["zmin"])
    held = upper.point_sets["zmax"]
    if peel:  # hold only the end x < 0.35 of the top: the tissue near it strains most
        held = held[upper.points[held, 0] < 0.35]
    sim.grasp(
        "upper", held, lambda t: (0, 0, lift * min(t / ramp, 1.0)), stiffness=grasper_stiffness
    )
    sim.add_tissue(
        make_material("stvk", youngs_modulus=tissue_E, poisson_ratio=0.3),
        thickness=GAP,
        spacing=0.1,
        frames=8,
        density=tissue_density,
        region=_inside,
    )
    return sim


def total_weight(sim, g=9.81):
    organs = sum(sim.bodies[n].model.mass.lumped.sum() / 3 for n in ("lower", "upper"))
    tissue = sim.tissue.model.masses.sum() if sim.tissue is not None else 0.0
    return (organs + tissue) * g


def test_quasistatic_force_balance():
    """Grasper + support reactions carry the total weight exactly at equilibrium."""
    sim = two_boxes()
    for _ in range(3):
        record = sim.step()
    f = record.extra["forces"]
    total = np.add(f["grasper"], f["lower.support"])
    W = total_weight(sim)
    assert f["lower.support"][2] < 0.5 * W  # the stretched tissue lifts the lower organ
    np.testing.assert_allclose(total, [0.0, 0.0, W], atol=1e-7 * W)
    assert record.extra["attachment_gap"] < 0.02 * 0.1  # penalty gap << the lift


def test_spring_grasper_force_balances_weight_and_lags_its_target():
    """A soft grip: springs to the moving targets. Its force (sum k (target - x)) and the
    support carry the weight; the held vertices lag behind the target by force / k."""
    k = 2000.0
    sim = two_boxes(grasper_stiffness=k)
    for _ in range(4):
        record = sim.step()
    f = record.extra["forces"]
    np.testing.assert_allclose(
        np.add(f["grasper"], f["lower.support"]), [0, 0, total_weight(sim)], atol=1e-6
    )
    held = sim.bodies["upper"].graspers[0].vertices
    lag = 0.1 - (sim.body_positions("upper")[held, 2] - sim.bodies["upper"].mesh.points[held, 2])
    assert lag.sum() * k == pytest.approx(f["grasper"][2], rel=1e-9)
    assert lag.mean() > 0


def test_retraction_force_balances_support_without_gravity():
    sim = two_boxes(gravity=None)
    record = sim.step()
    f = record.extra["forces"]
    assert f["grasper"][2] > 1.0
    np.testing.assert_allclose(f["grasper"], -np.asarray(f["lower.support"]), atol=1e-8)


@pytest.mark.parametrize("tissue_E, follows", [(1e-6, False), (1e5, True)])
def test_tissue_stiffness_limits(tissue_E, follows):
    """Pull the upper organ up; the lower one is free (no support, no gravity). Near-zero
    tissue stiffness: it stays (unconnected); large: it moves nearly with the upper one."""
    sim = two_boxes(
        "backward_euler",
        gravity=None,
        tissue_E=tissue_E,
        fix_lower=False,
        time_step=0.1,
        tissue_density=1e-3,  # a light layer: the coupling is its stiffness, not its inertia
    )
    # the free lower organ is held by nothing but inertia: solve tightly so that what moves
    # it is the tissue, not the Newton tolerance
    sim.newton = NewtonOptions(gradient_tolerance=1e-11, absolute_tolerance=1e-12)
    for _ in range(10):
        sim.step()
    up = sim.body_positions("upper").mean(axis=0) - sim.bodies["upper"].mesh.points.mean(0)
    low = sim.body_positions("lower").mean(axis=0) - sim.bodies["lower"].mesh.points.mean(0)
    assert up[2] == pytest.approx(0.1, rel=0.05)
    ratio = low[2] / up[2]
    if follows:
        assert ratio > 0.9
    else:
        # the drag scales with the tissue's modulus: 4e-4 of the retraction at 1e-3 Pa
        assert abs(ratio) < 1e-4


def _blade(z):
    def blade(t):
        x = -0.2 + 1.4 * (t - 1.0)
        return np.array([[x, -0.2, z], [x, 1.2, z]])

    return blade


@pytest.mark.parametrize("gravity", [9.81, None])
def test_full_cut_leaves_only_weight(gravity):
    """After cutting through the layer the grasper holds only its organ and the tissue left on
    it (with gravity), or nothing (without)."""
    sim = two_boxes(gravity=gravity)
    zc = 0.5 * GAP + 0.05  # middle of the stretched layer (the lift is 0.1)
    sim.add_cut(_blade(zc), 1.0, 2.0)
    records = [sim.step() for _ in range(10)]
    before = records[3].extra["forces"]["grasper"][2]
    after = records[-1].extra["forces"]["grasper"]
    cuts = [e for r in records for e in r.extra["events"] if e["kind"] == "cut"]
    assert sum(e["severed_pairs"] for e in cuts) > 0
    if gravity is None:
        assert np.linalg.norm(after) < 1e-6 * before
        return
    # what hangs on the grasper: the upper organ and the tissue points above the cut
    f = sim.tissue_fields()
    tissue_above = sim.tissue.model.masses[f["positions"][:, 2] > zc].sum()
    upper = sim.bodies["upper"].model.mass.lumped.sum() / 3
    expected = (upper + tissue_above) * gravity
    assert after[2] == pytest.approx(expected, rel=1e-6)
    assert before > 1.5 * expected


def test_newton_converges_quadratically():
    sim = two_boxes(gravity=9.81)
    record = sim.step()
    r = np.array(record.residual_norms[0])
    assert r[-1] < 1e-8 * r[0]
    # last ratios: log r_{k+1} / log r_k > 1.7 once in the fast phase
    rel = r / r[0]
    orders = np.log(rel[2:]) / np.log(rel[1:-1])
    assert orders[-1] > 1.7


def test_tearing_removes_overstretched_points_and_continues():
    """Peel the upper organ at one end: the tissue there passes the threshold and tears, the
    rest holds, and stepping goes on with the new topology."""
    sim = two_boxes(gravity=None, lift=0.3, peel=True)
    sim.set_tearing(0.3)
    rest_x = sim.tissue.samples.points[:, 0]
    records = [sim.step() for _ in range(4)]
    torn = [e for r in records for e in r.extra["events"] if e["kind"] == "tear"]
    assert torn, "nothing tore"
    alive = sim.tissue.dissection.alive
    assert 0 < alive.sum() < alive.size
    assert rest_x[~alive].mean() < rest_x[alive].mean()  # it tore at the peeled end
    assert all(r.converged for r in records)
    f = sim.tissue_fields()
    assert f["max_principal_strain"].max() < 1.0


def test_tearing_all_the_tissue_leaves_the_organs_going_on_alone():
    """A threshold every stretched point passes: the tissue tears away step by step and, once
    the last point is gone, the organs step on without it (it crashed: 'tissue' not in list)."""
    sim = two_boxes(gravity=None, lift=0.6, ramp=2.0, peel=True)  # still lifting at t = 1.25
    sim.set_tearing(1e-6)
    records = [sim.step() for _ in range(4)]
    assert sim.tissue.dissection.alive.sum() == 0
    assert sim.tissue.model is None and "tissue" not in sim.system.names
    assert all(r.converged for r in records)
    assert records[-1].extra["tissue_points"] == 0
    assert records[-1].extra["attachment_gap"] == 0.0
    before = sim.body_positions("upper").copy()
    record = sim.step()  # the organs alone: the lifted one follows its grasper
    assert record.converged and np.all(np.isfinite(sim.body_positions("upper")))
    assert not np.array_equal(before, sim.body_positions("upper"))


def test_errors_name_what_is_wrong():
    sim = Simulation()
    with pytest.raises(ValueError, match="add the organs"):
        sim.add_tissue(make_material("stvk", youngs_modulus=1.0, poisson_ratio=0.3))
    with pytest.raises(ValueError, match="unknown body 'liver'"):
        sim.fix("liver", [0])
    sim.add_body(
        "a",
        box((0, 0, 0), (1, 1, 1), (1, 1, 1)),
        make_material("stvk", youngs_modulus=1.0, poisson_ratio=0.3),
    )
    with pytest.raises(ValueError, match="out of range"):
        sim.fix("a", [100])
    with pytest.raises(ValueError, match="taken"):
        sim.add_body("a", box(), make_material("stvk", youngs_modulus=1.0, poisson_ratio=0.3))
    far = box((5, 5, 5), (6, 6, 6), (1, 1, 1))
    sim.add_body("b", far, make_material("stvk", youngs_modulus=1.0, poisson_ratio=0.3))
    with pytest.raises(ValueError, match="touches no organ|layer is empty|empty"):
        sim.add_tissue(
            make_material("stvk", youngs_modulus=1.0, poisson_ratio=0.3),
            thickness=0.1,
            spacing=0.05,
        )
    with pytest.raises(ValueError, match="call add_tissue first"):
        sim.add_cut(_blade(0.1), 0.0, 1.0)


def test_bad_cut_and_attachment_parameters_are_refused():
    sim = two_boxes()
    with pytest.raises(ValueError, match="kerf must be >= 0"):
        sim.add_cut(_blade(0.15), 1.0, 2.0, kerf=-0.01)
    with pytest.raises(ValueError, match="end .* must be after start"):
        sim.add_cut(_blade(0.15), 2.0, 1.0)
    with pytest.raises(ValueError, match="blade"):
        sim.add_cut(lambda t: np.zeros((1, 3)), 1.0, 2.0)
    lower = box((0, 0, -0.5), (1, 1, 0), (2, 2, 1))
    upper = box((0, 0, GAP), (1, 1, GAP + 0.5), (2, 2, 1))
    other = Simulation()
    mat = make_material("stvk", youngs_modulus=1.0, poisson_ratio=0.3)
    other.add_body("lower", lower, mat)
    other.add_body("upper", upper, mat)
    with pytest.raises(ValueError, match="attachment_stiffness must be > 0"):
        other.add_tissue(mat, thickness=GAP, spacing=0.1, attachment_stiffness=-1.0)


def test_two_tied_blocks_hang_together_and_forces_balance():
    """Two FEM blocks glued where they touch, the lower one supported: at equilibrium the
    support carries both weights and the tie carries the upper block's."""
    mat = make_material("neo_hookean", youngs_modulus=1000.0, poisson_ratio=0.3)
    sim = Simulation(
        integrator="quasistatic",
        time_step=1.0,
        gravity=(0, 0, -9.81),
        newton=NewtonOptions(gradient_tolerance=1e-11, absolute_tolerance=1e-12),
    )
    lower = box((0, 0, -0.5), (1, 1, 0), (2, 2, 2))
    sim.add_body("lower", lower, mat, density=10.0)
    sim.add_body("upper", box((0, 0, 0), (1, 1, 0.5), (3, 3, 2)), mat, density=10.0)
    sim.fix("lower", lower.point_sets["zmin"])
    tie = sim.attach("upper", "lower", name="glue")
    record = sim.step()
    weight = 10.0 * 0.5 * 9.81  # each block
    np.testing.assert_allclose(
        record.extra["forces"]["lower.support"], [0, 0, 2 * weight], atol=1e-6
    )
    np.testing.assert_allclose(record.extra["forces"]["glue"], [0, 0, weight], atol=1e-6)
    gap = max(float(np.abs(r).max()) for r in sim.system.tie_residuals(sim.state.x))
    assert gap < 1e-3 * 0.5 and tie.n > 0  # the penalty lets only a small gap open
    assert sim.body_positions("upper")[:, 2].min() > -0.05  # held by the tie, not fallen


def test_frame_body_attached_on_a_fem_block_and_forces_balance():
    """A meshless block resting on a FEM block it is attached to, the FEM block supported: at
    equilibrium the support carries both weights and the attachment the frame body's."""
    from tissuesim.frames.placement import grid_frames
    from tissuesim.frames.sampling import sample_box

    mat = make_material("neo_hookean", youngs_modulus=1000.0, poisson_ratio=0.3)
    sim = Simulation(
        integrator="quasistatic",
        time_step=1.0,
        gravity=(0, 0, -9.81),
        newton=NewtonOptions(gradient_tolerance=1e-11, absolute_tolerance=1e-12),
    )
    lower = box((0, 0, -0.5), (1, 1, 0), (3, 3, 2))
    sim.add_body("lower", lower, mat, density=10.0)
    samples = sample_box((0, 0, 0), (1, 1, 0.4), 0.1)
    sim.add_frame_body(
        "cap",
        grid_frames((0.25, 0.25, 0.1), (0.75, 0.75, 0.3), (2, 2, 2)),
        samples,
        make_material("stvk", youngs_modulus=500.0, poisson_ratio=0.3),
        density=10.0,
        frame_type="affine",
    )
    sim.fix("lower", lower.point_sets["zmin"])
    spec = sim.attach("cap", "lower", name="seat")
    assert spec.points.shape[0] > 0 and np.all(np.abs(spec.points[:, 2]) < 1e-9)
    record = sim.step()
    cap_weight = 10.0 * samples.volume * 9.81
    lower_weight = 10.0 * 0.5 * 9.81
    np.testing.assert_allclose(
        record.extra["forces"]["lower.support"], [0, 0, cap_weight + lower_weight], atol=1e-6
    )
    np.testing.assert_allclose(record.extra["forces"]["seat"], [0, 0, cap_weight], atol=1e-6)
    assert sim.attachment_gap() < 1e-3
    with pytest.raises(ValueError, match="cannot be attached to itself"):
        sim.attach("cap", "cap")


def _lower_attachment_positions(sim) -> np.ndarray:
    """Where the lower organ carries the tissue's attachment points now (S, 3)."""
    names = [b.name for b in sim._active()]
    mine = [a for a in sim.system.attachments if a.organ == names.index("lower")]
    cells = sim.bodies["lower"].mesh.cells
    x = sim.body_positions("lower").ravel()
    return np.concatenate([a.organ_positions(cells, x) for a in mine])


def test_cutting_an_organ_under_the_tissue_keeps_each_attachment_on_its_side():
    """The lower organ cut through at x = 0.53 (through its cells) with the tissue attached to
    its top: each attachment point moves to the copy of its cell on its side of the cut (in
    that copy's material, on the piece its side became), the organ carries every point where
    it was, and the coupled system stays in balance as the upper organ is lifted."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

    sim = two_boxes()
    sim.step()
    before = _lower_attachment_positions(sim)
    plane = np.array([[0.53, -1, -1], [0.53, 2, -1], [0.53, 2, 1], [0.53, -1, 1]], dtype=float)
    report = sim.cut_body(
        PlanarCut(np.array([0.53, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), plane), body="lower"
    )
    assert report["pieces"] == 2 and report["cells_cut"] > 0
    np.testing.assert_allclose(_lower_attachment_positions(sim), before, atol=1e-12)
    body = sim.bodies["lower"]
    vn = body.cut_state.vn
    (contact,) = [c for c in sim.tissue.contacts if c.organ == "lower"]
    copies = contact.cells
    cut = vn.side[copies] != 0
    assert np.any(cut)  # some points lie in cells the cut crossed
    level = np.einsum("sk,sk->s", contact.barycentric[cut], vn.level[copies[cut]])
    assert np.all(level >= -1e-12)  # in the material of their copy
    cells = body.mesh.cells
    n = body.mesh.n_points
    rows = np.repeat(np.arange(len(cells)), cells.shape[1])
    size = len(cells) + n  # cells and nodes, joined where a cell uses a node
    graph = csr_matrix((np.ones(rows.size), (rows, cells.ravel() + len(cells))), (size, size))
    _, label = connected_components(graph, directed=False)
    piece = label[copies]
    x = contact.points[:, 0]
    left, right = np.unique(piece[x < 0.5]), np.unique(piece[x > 0.56])
    assert len(left) == 1 and len(right) == 1 and left[0] != right[0]
    for _ in range(2):
        record = sim.step()
    f = record.extra["forces"]
    total = np.add(f["grasper"], f["lower.support"])
    np.testing.assert_allclose(total, [0.0, 0.0, total_weight(sim)], atol=1e-7 * total_weight(sim))
    assert record.extra["attachment_gap"] < 0.02 * 0.1
