"""Interactive contact (issue 21): the reused factorisation, the physical stopping criterion,
the per-step candidate set, the live-driven instrument, step budgets and the live window."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import tissuesim as ts
from tissuesim.solve.linear import NotPositiveDefiniteError, SuperLUSolver
from tissuesim.solve.reuse import ReusedFactorSolver

pytest.importorskip("ipctk")

from tissuesim.contact.obstacles import sphere  # noqa: E402

TOP = 0.01


def pressed_block(newton: ts.NewtonOptions | None = None, friction: float = 0.0):
    """A soft block fixed at its base, a sphere probe 0.2 mm above its top, driven live."""
    mesh = ts.box((0, 0, 0), (0.02, 0.02, TOP), (5, 5, 3))
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(
        mesh, material, density=1000.0, integrator="backward_euler", time_step=0.02, newton=newton
    )
    sim.fix("body", ts.select.vertices_on_plane(mesh, axis=2, value=0.0), name="base")
    sim.set_contact(dhat=1e-4, friction=friction)
    probe = sphere((0.01, 0.01, TOP + 0.005 + 2e-4), 0.005, refinement=3)
    sim.add_obstacle("probe", probe)
    return sim


def _spd(n: int, seed: int) -> sp.csr_matrix:
    rng = np.random.default_rng(seed)
    A = sp.random(n, n, density=0.05, random_state=rng)
    return (A @ A.T + sp.eye(n) * n * 0.1).tocsr()


def test_cg_on_a_stale_factor_solves_the_current_matrix_as_a_fresh_factorisation_does():
    A0 = _spd(200, 1)
    A1 = (A0 + 0.05 * sp.diags(np.linspace(1.0, 3.0, 200)) @ A0).tocsr()  # a nearby matrix
    A1 = ((A1 + A1.T) * 0.5).tocsr()
    b = np.random.default_rng(2).standard_normal(200)
    reuse = ReusedFactorSolver(SuperLUSolver(), max_cg=20, rtol=1e-10)
    reuse.factorize(A0)
    reuse.solve(b)  # factorises A0
    reuse.factorize(A1)
    x = reuse.solve(b)  # CG on A1 with A0's factor
    fresh = SuperLUSolver()
    fresh.factorize(A1)
    expected = fresh.solve(b)
    assert np.linalg.norm(x - expected) <= 1e-8 * np.linalg.norm(expected)
    stats = reuse.take_stats()
    assert stats["factorizations"] == 1
    assert 1 <= stats["cg_iterations"] <= 20


def test_a_stale_factor_that_no_longer_fits_is_refactorised():
    A0 = _spd(100, 3)
    A1 = (A0 * 50.0 + sp.diags(np.arange(100.0) ** 2)).tocsr()  # far from A0
    b = np.ones(100)
    reuse = ReusedFactorSolver(SuperLUSolver(), max_cg=2, rtol=1e-12)
    reuse.factorize(A0)
    reuse.solve(b)
    reuse.factorize(A1)
    x = reuse.solve(b)
    assert np.allclose(A1 @ x, b, rtol=0, atol=1e-9 * np.linalg.norm(b))
    assert reuse.take_stats()["factorizations"] == 2


def test_an_indefinite_matrix_goes_to_a_fresh_factorisation_not_to_cg():
    """CG on the stale factor meets negative curvature: the direct solver then answers (a
    Cholesky solver raises NotPositiveDefiniteError; SuperLU solves the system exactly)."""
    A0 = _spd(50, 4)
    reuse = ReusedFactorSolver(SuperLUSolver(), max_cg=50)
    reuse.factorize(A0)
    reuse.solve(np.ones(50))
    shift = 2.0 * float(sp.linalg.eigsh(A0, k=1)[0][0])
    indefinite = (A0 - shift * sp.eye(50)).tocsr()
    reuse.factorize(indefinite)
    try:
        x = reuse.solve(np.ones(50))
    except NotPositiveDefiniteError:
        return
    assert np.allclose(indefinite @ x, 1.0, atol=1e-9)
    assert reuse.take_stats()["factorizations"] == 2


def _press(sim: ts.Simulation, depths) -> list:
    records = []
    for depth in depths:
        sim.drive_obstacle("probe", translation=(0.0, 0.0, -depth))
        records.append(sim.step())
        assert not sim.system.contact.intersecting(sim.state.x)
    return records


def test_a_driven_probe_presses_the_block_and_its_force_grows_with_depth():
    sim = pressed_block()
    records = _press(sim, [2e-4, 4e-4, 6e-4, 8e-4])
    forces = [-r.extra["forces"]["probe"][2] for r in records]  # the probe pushes down: -z
    assert forces[0] >= 0.0 and forces[-1] > 0.0
    assert all(b > a for a, b in zip(forces[1:], forces[2:], strict=False))
    assert records[-1].extra["forces"]["probe"][2] < 0.0
    ob = sim.obstacles[0]
    assert np.allclose(ob.translation(sim.time), [0.0, 0.0, -8e-4])
    assert "linear" in records[-1].extra  # factorisations, back-solves, CG iterations


def test_the_physical_stopping_criterion_is_within_its_bound_of_a_tight_solve():
    """Positions within 1e-3 of the largest displacement and the probe's force within 1 % of
    the same run with every tolerance 1e4 times tighter."""
    depths = [3e-4, 6e-4, 9e-4]
    loose = pressed_block(ts.NewtonOptions(criterion="physical"), friction=0.2)
    _press(loose, depths)
    tight = pressed_block(ts.NewtonOptions(criterion="physical").tighter(1e4), friction=0.2)
    _press(tight, depths)
    u = tight.state.x - tight.system.bodies[0].rest_config()
    largest = np.max(np.linalg.norm(u.reshape(-1, 3), axis=1))
    error = np.max(np.linalg.norm((loose.state.x - tight.state.x).reshape(-1, 3), axis=1))
    assert error <= 1e-3 * largest
    f_loose = np.asarray(loose.history[-1].extra["forces"]["probe"])
    f_tight = np.asarray(tight.history[-1].extra["forces"]["probe"])
    assert np.linalg.norm(f_loose - f_tight) <= 0.01 * np.linalg.norm(f_tight)
    reasons = {reason for r in loose.history for reason in r.newton_reasons}
    assert "physical" in reasons


def test_a_step_budget_stops_early_accepts_the_state_and_never_intersects():
    sim = pressed_block()
    _press(sim, [2e-4])
    sim.drive_obstacle("probe", translation=(0.0, 0.0, -1.2e-3))
    record = sim.step(budget_iterations=1)
    assert record.extra["early_stop"] is True
    assert record.newton_iterations == 1
    assert not sim.system.contact.intersecting(sim.state.x)
    # the next step, unbudgeted, converges from there
    record = sim.step()
    assert record.extra["early_stop"] is False
    assert not sim.system.contact.intersecting(sim.state.x)


def test_drive_obstacle_names_the_obstacles_when_the_name_is_wrong():
    sim = pressed_block()
    with pytest.raises(ts.InputError, match="no obstacle 'knife'.*probe"):
        sim.drive_obstacle("knife", translation=(0, 0, 0))


def test_the_step_candidate_set_gives_the_barrier_of_a_fresh_build():
    sim = pressed_block()
    _press(sim, [4e-4])
    contact = sim.system.contact
    x = sim.state.x
    contact.begin_step()
    rng = np.random.default_rng(5)
    cache = contact.candidates
    for scale in (0.0, 0.3 * cache.margin, 3.0 * cache.margin):  # the last rebuilds
        y = x + scale * rng.uniform(-1, 1, x.size)
        builds = contact.stats.candidate_builds
        cached = contact.evaluate(y, 1)
        margin = cache.margin
        cache.margin = None  # off: a fresh broad phase for each evaluation
        fresh = contact.evaluate(y, 1)
        cache.margin = margin
        assert cached[0] == pytest.approx(fresh[0], rel=1e-12, abs=1e-300)
        if fresh[1] is not None:
            assert np.allclose(cached[1], fresh[1], rtol=1e-12, atol=0)
        if scale > cache.margin:
            assert contact.stats.candidate_builds == builds + 1


def test_a_sweep_from_its_own_broad_phase_finds_the_step_of_the_step_set(monkeypatch):
    """CCD sweeps take their pairs from the step's candidate set or, where that set is dense,
    from a broad phase over the sweep's own boxes (contact/barrier/ccd_queries.py): both give the
    same collision-free fraction, for moves that hit the probe and moves that do not."""
    from tissuesim.contact.barrier import ccd_queries

    sim = pressed_block()
    _press(sim, [4e-4])
    contact = sim.system.contact
    x = sim.state.x
    contact.begin_step()
    rng = np.random.default_rng(3)
    top = np.zeros_like(x).reshape(-1, 3)
    top[:, 2] = 1.0  # every node up: the top surface runs into the probe
    fractions = []
    for move in (1e-3 * top.ravel(), 2e-4 * rng.uniform(-1, 1, x.size)):
        got = []
        for pairs in (float("inf"), 0.0):  # the step's set; the sweep's own
            monkeypatch.setattr(ccd_queries, "SWEEP_PAIRS_PER_VERTEX", pairs)
            got.append(contact.max_step(x, x + move))
        assert got[0] == pytest.approx(got[1], rel=1e-12)
        fractions.append(got[0])
    assert fractions[0] < 0.5  # the upward move is cut short by the probe


def test_the_live_session_moves_the_instrument_with_keys_and_the_mouse_headless():
    pytest.importorskip("pyvista")
    from tissuesim.render.live import LiveSession

    sim = pressed_block()
    session = LiveSession(sim, off_screen=True, key_step=3e-4, window_size=(320, 240))
    session.press("Next")  # down by one key step
    first = session.advance()
    session.press("Next")
    session.press("Next")
    second = session.advance()
    assert np.allclose(session.offset, [0.0, 0.0, -9e-4])
    assert np.linalg.norm(second.extra["forces"]["probe"]) > np.linalg.norm(
        first.extra["forces"]["probe"]
    )
    text = session.status()
    assert "probe force" in text and "real-time factor" in text
    session.press("m")
    session.mouse_move(100, 100)
    session.mouse_move(110, 100)  # 10 pixels to the right: in the screen's plane
    assert not np.allclose(session.offset, [0.0, 0.0, -9e-4])
    session.plotter.render()
    image = session.plotter.screenshot(return_img=True)
    assert image.shape[:2] == (240, 320) and image.std() > 0  # something was drawn
    session.plotter.close()
