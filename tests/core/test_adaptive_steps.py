"""Adaptive time steps as FEBio takes them (time/adaptive.py): the rule computed by hand, the
step times of a quasistatic stretch against it, must points hit exactly, failed steps cut
back and retried, dtmin and max_retries as one-line errors, the run's end, its frames and
its resumption."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import ConvergenceError, InputError
from tissuesim.scene.loader import build_scene
from tissuesim.time.adaptive import (
    AdaptiveStepping,
    TimeStepController,
    advance_adaptive,
    check_adaptive,
)
from tissuesim.time.phases import Phase
from tissuesim.time.state import State, StepOutcome


def _replay(settings: AdaptiveStepping, dt0: float, end: float, iterations: list[int]):
    """FEBio's AutoTimeStep written out again (FETimeStepController.cpp): the end times of
    the steps that take ``iterations`` Newton iterations, one after the other."""
    must = sorted(settings.all_must_points())
    t, dtp, ends = 0.0, dt0, []
    dtn = min(max(dtp, settings.dtmin), settings.dtmax_at(t))
    for n in [None, *iterations]:
        if n is not None:
            dtn = dtp
            dtmax = settings.dtmax_at(t)
            scale = math.sqrt(settings.opt_iter / n) if n else None
            if scale is None:
                dtn = min(max(dtn, settings.dtmin), dtmax)
            elif scale >= 1:
                dtn = min(dtn + (dtmax - dtn) * min(0.2, scale - 1), 5 * dtp, dtmax)
            else:
                dtn = min(max(dtn - (dtn - settings.dtmin) * (1 - scale), settings.dtmin), dtmax)
        dtp = dtn
        t1 = t + dtn
        ahead = [m for m in must if m > t + 1e-12]
        if ahead and ahead[0] < t1 + 1e-12:
            t1 = ahead[0]
        t1 = min(t1, end)
        if t >= end - 1e-12:
            break
        ends.append(t1)
        t = t1
    return ends


def test_the_controller_follows_febios_rule_computed_by_hand():
    """dt0 = 0.01, dtmax 0.3, opt_iter 11, a must point at 0.5, end 1: with 3 iterations the
    scale is sqrt(11/3) > 1.2, so each step grows by 0.2 (dtmax - dt), at most 5 dt_prev; with
    4, likewise; the step to the must point is shortened, the rule goes on from its own dt."""
    c = TimeStepController(AdaptiveStepping(dtmax=0.3, must_points=(0.5,)), 0.01, 0.0, 1.0)
    ends = []
    for n in [3, 3, 4, 4, 4, 3, 4, 4, 3]:
        ends.append(c.t_end)
        c.accepted(c.t_end, n)
    # 0.01; min(0.01 + 0.29 * 0.2, 5 * 0.01) = 0.05; 0.05 + 0.25 * 0.2 = 0.1; 0.1 + 0.04 = 0.14;
    # 0.14 + 0.032 = 0.172 (t = 0.472); 0.1976 would pass 0.5: 0.028; then from 0.1976:
    # 0.21808, 0.234464; the last step ends at the end
    assert ends == pytest.approx([0.01, 0.06, 0.16, 0.30, 0.472, 0.5, 0.71808, 0.952544, 1.0])
    assert ends[5] == 0.5 and ends[-1] == 1.0  # exactly
    assert c.finished(1.0)


def test_few_iterations_shrink_the_step_and_dtforce_takes_dtmax():
    c = TimeStepController(AdaptiveStepping(dtmax=0.5, dtmin=0.02, opt_iter=4), 0.2, 0.0, 10.0)
    c.accepted(c.t_end, 16)  # scale 1/2: dt - (dt - dtmin) / 2 = 0.11
    assert c.dt == pytest.approx(0.11)
    forced = AdaptiveStepping(dtmax_curve=((0.0, 1e-4), (1e-4, 1e-4), (1.0, 0.9999)),
                              dtmax_interpolation="step", dtforce=True)  # fmt: skip
    c = TimeStepController(forced, 4e-4, 0.0, 1.0)  # FEBio's mi35: two steps
    assert (c.t_end, c.must_point) == (1e-4, True)
    c.accepted(c.t_end, 5)
    assert (c.t_end, c.must_point) == (1.0, True)


def test_a_must_point_curve_of_zero_sets_no_bound():
    """FEBio's <dtmax lc="1">0</dtmax> with a STEP curve starting at 0 (co11, mi09): where the
    curve is 0 (at t = 0) there is no dtmax: the first step keeps its dt0; from then on the
    STEP curve's next value, 0.1, bounds it (FEBio's PointCurve: the next point's value)."""
    free = AdaptiveStepping(dtmax_curve=((0.0, 0.0), (1.0, 0.1), (4.0, 0.1)),
                            dtmax_interpolation="step", dtmin=0.01)  # fmt: skip
    c = TimeStepController(free, 0.5, 0.0, 4.0)
    assert (c.t_end, c.must_point) == (0.5, False)  # the first step unbounded: dt0 = 0.5
    c.accepted(c.t_end, 3)
    assert c.t_end == pytest.approx(0.6)  # 0.5 + (0.1 - 0.5) 0.2 = 0.42, at most dtmax 0.1
    with pytest.raises(Exception, match="dtmax must be >= 0"):
        check_adaptive({"dtmax_curve": [[0.0, -1.0], [1.0, 0.1]]})


def _block(**kw):
    mesh = ts.box((0, 0, 0), (1, 0.2, 0.2), (4, 1, 1))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3),
                        integrator="quasistatic", **kw)  # fmt: skip
    sim.fix(ts.select.vertices_on_plane(mesh, axis=0, value=0.0), name="wall")
    end = ts.select.vertices_on_plane(mesh, axis=0, value=1.0)
    sim.add_dirichlet(end, lambda X, t: np.tile([0.4 * t, 0, 0], (len(X), 1)), (0,), name="pull")
    return sim


def test_a_stretch_under_a_ramp_steps_as_the_rule_with_its_must_points():
    """A block pulled to 1.4 over 1 s, FEBio's step of 200 x 0.005 s with a must-point curve
    (LINEAR dtmax 0.1 -> 0.4, points at 0, 0.35, 0.6, 1): the step times are the rule's for
    the iterations Newton took, the must points are hit exactly, the run ends at 1 s."""
    settings = AdaptiveStepping(
        dtmin=0.001, opt_iter=10,
        dtmax_curve=((0.0, 0.1), (0.35, 0.2), (0.6, 0.3), (1.0, 0.4)),
    )  # fmt: skip
    sim = _block(phases=[Phase(200, 0.005, adaptive=settings)])
    records = []
    while not sim.finished:
        records.append(sim.step())
    times = [r.time for r in records]
    iterations = [r.newton_iterations for r in records]
    assert times == pytest.approx(_replay(settings, 0.005, 1.0, iterations[:-1]), abs=1e-12)
    assert {0.35, 0.6, 1.0} <= set(times)  # exactly, not to round-off
    must = [r.time for r in records if r.extra["adaptive"]["must_point"]]
    assert must == [0.35, 0.6, 1.0]
    assert len(records) < 20 and all(r.extra["adaptive"]["retries"] == 0 for r in records)
    fixed = _block(time_step=0.005)
    for _ in range(200):
        fixed.step()
    assert np.allclose(sim.positions, fixed.positions, atol=1e-8)  # quasistatic: the same end


def _fake(fails_above: float, calls: list):
    """A step function that converges (in 3 iterations) only for steps up to fails_above."""

    def step(model, state, dt, solver, options):
        calls.append(dt)
        if dt > fails_above:
            return StepOutcome(None, False, [], "too long")
        return StepOutcome(State(state.time + dt, state.x, state.v), True, [])

    return step


def test_a_failed_step_is_cut_back_and_retried():
    state = State(0.0, np.zeros(3), np.zeros(3))
    calls: list = []
    c = TimeStepController(AdaptiveStepping(dtmax=0.1, max_retries=5), 0.1, 0.0, 1.0)
    new, _, retries, _ = advance_adaptive(_fake(0.04, calls), None, state, c, None, None)
    # FEBio's linear cut back: dt - 0.1 / 6 per retry, down to 0.0333
    assert calls == pytest.approx([0.1, 0.1 * 5 / 6, 0.1 * 4 / 6, 0.1 * 3 / 6, 0.1 * 2 / 6])
    assert retries == 4 and new.time == pytest.approx(0.1 / 3)
    c.accepted(new.time, 0)  # the next step starts from the cut back one
    assert c.dt == pytest.approx(0.1 / 3)
    calls.clear()
    c = TimeStepController(
        AdaptiveStepping(dtmax=0.1, aggressiveness=1, cutback=0.5), 0.1, 0.0, 1.0
    )
    advance_adaptive(_fake(0.04, calls), None, state, c, None, None)
    assert calls == pytest.approx([0.1, 0.05, 0.025])  # aggressive: halved


def test_dtmin_and_max_retries_end_the_run_in_one_line():
    state = State(0.0, np.zeros(3), np.zeros(3))
    c = TimeStepController(AdaptiveStepping(dtmax=0.1, dtmin=0.05), 0.1, 0.0, 1.0)
    with pytest.raises(ConvergenceError, match=r"smallest time step, dtmin = 0\.05 s") as info:
        advance_adaptive(_fake(0.0, []), None, state, c, None, None)
    assert "\n" not in str(info.value)
    c = TimeStepController(AdaptiveStepping(dtmax=0.1, max_retries=2), 0.1, 0.0, 1.0)
    with pytest.raises(ConvergenceError, match=r"after 2 retries \(max_retries\)"):
        advance_adaptive(_fake(0.0, []), None, state, c, None, None)


def test_a_real_step_that_fails_is_retried_shorter():
    """Four Newton iterations cannot pull the block 40 % in one step of 1 s (it takes 5-7,
    by the linear solver: SuperLU's CG 5, PARDISO's 7): it is cut back (FEBio's rule) until
    Newton converges, and the run still lands on t = 1."""
    sim = _block(
        newton=ts.NewtonOptions(max_iterations=4),
        phases=[Phase(1, 1.0, adaptive={"dtmax": 1.0, "max_retries": 9})],
    )
    first = sim.step()
    assert first.extra["adaptive"]["retries"] >= 1
    assert first.time == pytest.approx(1.0 - first.extra["adaptive"]["retries"] * 0.1)
    while not sim.finished:
        sim.step()
    assert sim.time == 1.0


def test_settings_are_checked_in_one_line():
    with pytest.raises(InputError, match="needs dtmax"):
        check_adaptive({"dtmin": 0.1})
    with pytest.raises(InputError, match="unknown key 'dt_max'"):
        check_adaptive({"dt_max": 0.1})
    with pytest.raises(InputError, match="increasing"):
        check_adaptive({"dtmax_curve": [[0, 0.1], [0, 0.2]]})
    with pytest.raises(InputError, match="below dtmin"):
        check_adaptive({"dtmax": 0.1, "dtmin": 0.2})
    with pytest.raises(InputError, match="implicit"):
        ts.Simulation(integrator="explicit", adaptive={"dtmax": 0.1})


SCENE = {
    "mesh": {"generator": "box", "lower": [0, 0, 0], "upper": [1, 0.2, 0.2],
             "divisions": [4, 1, 1]},
    "material": {"model": "neo_hookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3},
    "simulation": {
        "integrator": "quasistatic",
        "phases": [{"steps": 100, "time_step": 0.01,
                    "adaptive": {"dtmax": 0.25, "must_points": [0.5], "frames": "must_points"}}],
    },
    "dirichlet": [
        {"vertices": {"on_plane": {"axis": 0, "value": 0.0}}, "name": "wall"},
        {"vertices": {"on_plane": {"axis": 0, "value": 1.0}}, "displacement": ["0.3 * t", 0, 0],
         "components": [0], "name": "pull"},
    ],
    "run": {"steps": 100, "render": False},
}  # fmt: skip


def test_a_scene_runs_to_its_end_writes_the_must_points_and_resumes(tmp_path):
    """[simulation] phases with adaptive: the run stops at the phase's end however many steps
    [run] allows, writes the first state, the must point and the end, and a resumed run ends
    bit for bit where an uninterrupted one does."""
    scene = build_scene(json.loads(json.dumps(SCENE)), source="s.toml")
    history = scene.simulation.run(output=tmp_path / "whole", progress=False, **scene.run)
    assert history[-1].time == 1.0 and len(history) < 20
    pvd = (tmp_path / "whole" / "body.pvd").read_text()
    assert pvd.count("<DataSet") == 3 and 'timestep="0.5"' in pvd
    whole = np.load(tmp_path / "whole" / "checkpoint.npz")["x"]
    part = build_scene(json.loads(json.dumps(SCENE)), source="s.toml")
    part.simulation.run(3, tmp_path / "part", progress=False, render=False, every=1)
    again = build_scene(json.loads(json.dumps(SCENE)), source="s.toml")
    rest = again.simulation.run(output=tmp_path / "part", progress=False, resume=True, **scene.run)
    assert np.array_equal(np.load(tmp_path / "part" / "checkpoint.npz")["x"], whole)
    assert [r.time for r in rest] == [r.time for r in history]
    bad = json.loads(json.dumps(SCENE))
    bad["simulation"]["adaptive"] = {"dtmax": -1}
    with pytest.raises(Exception, match=r"\[simulation\].*dtmax must be > 0"):
        build_scene(bad, source="s.toml")


def test_dynamic_steps_adapt_too_and_a_free_fall_stays_exact():
    """Newmark's trapezoidal rule integrates a constant acceleration exactly for any steps, so
    a free fall on adaptive steps (growing from 1 ms towards dtmax, a must point at 13 ms) is
    at -g t^2 / 2 at every step's time; Backward Euler takes the same steps' times."""
    for integrator in ("newmark", "backward_euler"):
        mesh = ts.box((0, 0, 0), (0.1, 0.1, 0.1), (1, 1, 1))
        sim = ts.Simulation(
            mesh, ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3), density=1000.0,
            integrator=integrator, gravity=(0.0, 0.0, -9.81),
            phases=[Phase(50, 0.001, adaptive={"dtmax": 0.01, "must_points": [0.013]})],
        )  # fmt: skip
        records = []
        while not sim.finished:
            records.append(sim.step())
        times = [r.time for r in records]
        assert 0.013 in times and times[-1] == 0.05 and len(times) < 20
        assert times[1] - times[0] > times[0]  # grown from the first step
        if integrator == "newmark":
            drop = sim.positions[:, 2] - mesh.points[:, 2]
            assert np.allclose(drop, -9.81 * 0.05**2 / 2, rtol=1e-9)
