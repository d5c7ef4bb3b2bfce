"""A run in phases (time/phases.py) and conditions with time windows: the step grid of each
phase, the integrator switch, conditions taken and let go at their window's ends, scenes,
resuming across phases, and one-line refusals."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.cli import main
from tissuesim.errors import InputError, SceneError
from tissuesim.scene.loader import build_scene
from tissuesim.time.phases import Phase, Schedule, in_window


def test_schedule_steps_on_each_phases_grid_and_continues_the_last():
    s = Schedule([Phase(3, 0.1), {"steps": 2, "time_step": 0.25, "integrator": "quasistatic"}],
                 1.0, explicit=False)  # fmt: skip
    ends, t = [], 1.0
    for _ in range(7):
        t = s.end_time(t)
        ends.append(t)
    # no running sum: the first phase ends at 1.3 exactly as 1.0 + 3 * 0.1, the second at 1.8
    assert ends == [1.1, 1.2, 1.0 + 3 * 0.1, 1.3 + 0.25, 1.3 + 2 * 0.25, 1.8 + 0.25, 1.8 + 0.5]
    assert s.steps == 5 and s.end == pytest.approx(1.8)
    assert s.at(1.25)[0].time_step == 0.1 and s.at(1.3)[0].integrator == "quasistatic"
    assert s.at(5.0)[2] == math.inf


def test_windows_hold_steps_that_end_after_the_start_and_by_the_end():
    assert in_window((0.0, 1.0), 1.0, 1e-12) and not in_window((0.0, 1.0), 1.1, 1e-12)
    assert not in_window((1.0, 2.0), 1.0, 1e-12) and in_window((1.0, 2.0), 1.1, 1e-12)
    assert in_window(None, 7.0, 0.0) and in_window((1.0, math.inf), 1e9, 0.0)


def _bar(**kw) -> tuple[ts.Simulation, np.ndarray, np.ndarray]:
    mesh = ts.box((0, 0, 0), (1, 0.2, 0.2), (6, 1, 1))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3),
                        density=1000.0, **kw)  # fmt: skip
    left = ts.select.vertices_on_plane(mesh, axis=0, value=0.0)
    right = ts.select.vertices_on_plane(mesh, axis=0, value=1.0)
    sim.fix(left, name="wall")
    return sim, left, right


def test_a_condition_is_taken_and_let_go_at_its_windows_ends():
    """Phase 1 (quasistatic) pulls the free end 0.1 m; phase 2 (Backward Euler) lets go:
    the end starts from where it was held and springs back; a second condition takes the end
    again from t = 1.1 and holds it at its prescribed place."""
    phases = [Phase(2, 0.5, "quasistatic"), Phase(20, 0.01, "backward_euler")]
    sim, _, right = _bar(phases=phases)
    sim.add_dirichlet(right, [0.1, 0.0, 0.0], (0,), name="pull", active=(0.0, 1.0))
    sim.add_dirichlet(right, [0.05, 0.0, 0.0], (0,), name="catch", active=(1.1, math.inf))
    records = [sim.step() for _ in range(2)]
    assert sim.integrator == "quasistatic"
    assert records[-1].extra["forces"]["pull"][0] > 0 and records[-1].extra["forces"]["catch"] == [
        0.0,
        0.0,
        0.0,
    ]
    held = sim.positions[right, 0].copy()
    assert np.allclose(held, 1.1)
    first = sim.step()
    assert sim.integrator == "backward_euler" and sim.time == pytest.approx(1.01)
    assert first.extra["forces"]["pull"] == [0.0, 0.0, 0.0]
    moved = sim.positions[right, 0]
    assert np.all(moved < held) and np.all(moved > 1.05)  # let go, from where it was
    for _ in range(9):
        record = sim.step()
    assert record.extra["forces"]["catch"] == [0.0, 0.0, 0.0]
    for _ in range(10):
        record = sim.step()
    assert np.allclose(sim.positions[right, 0], 1.05)
    assert record.extra["forces"]["catch"][0] != 0.0


def test_phases_and_windows_refuse_bad_input_in_one_line():
    with pytest.raises(InputError, match="explicit simulation cannot switch"):
        ts.Simulation(integrator="explicit", phases=[Phase(2, 0.1)])
    with pytest.raises(InputError, match="phase 2: needs steps and time_step"):
        ts.Simulation(phases=[Phase(2, 0.1), {"steps": 3}])
    with pytest.raises(InputError, match="unknown key 'dt'"):
        ts.Simulation(phases=[{"steps": 3, "time_step": 0.1, "dt": 1}])
    with pytest.raises(InputError, match="phase 1 integrator"):
        ts.Simulation(phases=[Phase(2, 0.1, "explicit")])
    with pytest.raises(InputError, match="phase 1 steps"):
        ts.Simulation(phases=[Phase(0, 0.1)])
    sim, left, _ = _bar()
    with pytest.raises(InputError, match=r"start < end"):
        sim.add_dirichlet(left, active=(1.0, 0.5))
    with pytest.raises(InputError, match="two times"):
        sim.add_dirichlet(left, active=(1.0,))


SCENE = {
    "mesh": {"generator": "box", "lower": [0, 0, 0], "upper": [1, 0.2, 0.2],
             "divisions": [6, 1, 1]},
    "material": {"model": "neo_hookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3},
    "simulation": {
        "density": 1000.0,
        "phases": [
            {"steps": 2, "time_step": 0.5, "integrator": "quasistatic"},
            {"steps": 3, "time_step": 0.01, "integrator": "backward_euler"},
        ],
    },
    "dirichlet": [
        {"vertices": {"on_plane": {"axis": 0, "value": 0.0}}, "name": "wall"},
        {"vertices": {"on_plane": {"axis": 0, "value": 1.0}}, "displacement": ["0.1 * t", 0, 0],
         "active": [0, 1.0], "name": "pull"},
    ],
}  # fmt: skip


def _write(tmp_path, data) -> str:
    lines = []

    def value(v):
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, str):
            return json.dumps(v)
        return repr(v)

    for key, table in data.items():
        if isinstance(table, list):
            for item in table:
                lines.append(f"[[{key}]]")
                lines += [f"{k} = {value(v)}" for k, v in item.items()]
        else:
            lines.append(f"[{key}]")
            lines += [f"{k} = {value(v)}" for k, v in table.items()]
    path = tmp_path / "phases.toml"
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_a_scene_in_phases_runs_them_all_and_resumes_across_them(tmp_path, capsys):
    scene = _write(tmp_path, SCENE)
    out = tmp_path / "out"
    assert main(["run", scene, "--out", str(out), "--no-render", "--quiet"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["steps"] == 5
    whole = np.load(out / "checkpoint.npz")["x"]
    part = tmp_path / "part"
    assert main(["run", scene, "--out", str(part), "--no-render", "--quiet", "--steps", "3"]) == 0
    assert main(["run", scene, "--out", str(part), "--no-render", "--quiet", "--resume"]) == 0
    assert np.array_equal(np.load(part / "checkpoint.npz")["x"], whole)
    bad = json.loads(json.dumps(SCENE))
    bad["dirichlet"][1]["active"] = [2.0, 1.0]
    with pytest.raises(SceneError, match=r"\[\[dirichlet\]\] #2.*start < end"):
        build_scene(bad, source="s.toml")
    bad = json.loads(json.dumps(SCENE))
    bad["simulation"]["phases"][1]["integrator"] = "verlet"
    with pytest.raises(SceneError, match=r"\[simulation\].*phase 2 integrator"):
        build_scene(bad, source="s.toml")


def test_save_and_load_across_phases_continue_bit_for_bit(tmp_path):
    """Saved in the Newmark phase after the condition let go, loaded into a fresh set-up (in
    its first phase): the same steps follow, bit for bit."""

    def set_up() -> ts.Simulation:
        phases = [Phase(2, 0.5, "quasistatic"), Phase(5, 0.01, "newmark")]
        sim, _, right = _bar(phases=phases)
        sim.add_dirichlet(right, [0.1, 0.0, 0.0], (0,), name="pull", active=(0.0, 1.0))
        return sim

    sim = set_up()
    for _ in range(4):
        sim.step()
    sim.save(tmp_path / "state.npz")
    for _ in range(3):
        sim.step()
    again = set_up().load(tmp_path / "state.npz")
    for _ in range(3):
        again.step()
    assert again.integrator == "newmark" and again.time == pytest.approx(1.05)
    assert np.array_equal(again.state.x, sim.state.x)
