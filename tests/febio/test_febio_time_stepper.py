"""FEBio's <time_stepper> read as tissuesim's adaptive steps (febio/time_stepper.py,
time/adaptive.py): a model written in the test (the block of uniaxial_neo_hookean.feb with a
time stepper and a must-point curve) steps as FEBio's rule says, lands on its must points,
writes them only under PLOT_MUST_POINTS, and the settings tissuesim does not run are refused
with their line."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

from tissuesim.febio import FebError, febio_scene, load_febio, read_feb

MODELS = Path(__file__).parent / "models"
BASE = (MODELS / "uniaxial_neo_hookean.feb").read_text()

STEPPER = """
    <time_stepper type="default">
      <max_retries>5</max_retries>
      <opt_iter>10</opt_iter>
      <dtmin>0.01</dtmin>
      <dtmax lc="2">0</dtmax>
    </time_stepper>
    <plot_level>{plot}</plot_level>"""

MUST_CURVE = """
    <load_controller id="2" name="must" type="loadcurve">
      <interpolate>STEP</interpolate>
      <extend>CONSTANT</extend>
      <points>
        <pt>0,0.1</pt>
        <pt>0.3,0.2</pt>
        <pt>0.55,0.5</pt>
        <pt>1,0.5</pt>
      </points>
    </load_controller>
  </LoadData>"""


def _model(tmp_path: Path, plot: str = "PLOT_MAJOR_ITRS", stepper: str = STEPPER) -> Path:
    text = BASE.replace("<time_steps>4</time_steps>", "<time_steps>100</time_steps>")
    text = text.replace("<step_size>0.25</step_size>", "<step_size>0.01</step_size>")
    text = text.replace("    <solver", stepper.format(plot=plot) + "\n    <solver", 1)
    text = text.replace("  </LoadData>", MUST_CURVE, 1)
    path = tmp_path / "stepped.feb"
    path.write_text(text)
    return path


def _load(path: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the model's other notes (<Constants>, <solver>)
        return load_febio(path)


def test_a_time_stepper_becomes_adaptive_steps_over_the_step(tmp_path):
    path = _model(tmp_path)
    model = read_feb(path)
    assert not any("<time_stepper>" in n or "<plot_level>" in n for n in model.notes)
    data, _ = febio_scene(model, "m")
    (phase,) = data["simulation"]["phases"]
    assert phase["steps"] == 100 and phase["time_step"] == 0.01
    assert phase["adaptive"] == {
        "dtmin": 0.01, "max_retries": 5, "opt_iter": 10,
        "dtmax_curve": [[0.0, 0.1], [0.3, 0.2], [0.55, 0.5], [1.0, 0.5]],
        "dtmax_interpolation": "step",
    }  # fmt: skip
    assert data["run"]["steps"] >= 100  # an upper bound: the run ends at t = 1
    scene = _load(path)
    history = scene.simulation.run(progress=False, **scene.run)
    times = [r.time for r in history]
    assert times[-1] == 1.0 and len(times) < 15
    assert {0.3, 0.55} <= set(times)  # the curve's points, hit exactly
    # FEBio's first step: step_size 0.01 clamped to [dtmin, dtmax(0)] -> 0.01
    assert times[0] == pytest.approx(0.01)
    # the pull at the end is the fixed-step model's (quasistatic: the path does not matter)
    fixed = _load(MODELS / "uniaxial_neo_hookean.feb").simulation
    for _ in range(4):
        record = fixed.step()
    assert history[-1].extra["forces"]["pull"][0] == pytest.approx(
        record.extra["forces"]["pull"][0], rel=1e-7
    )


def test_plot_must_points_writes_the_must_points(tmp_path):
    scene = _load(_model(tmp_path, plot="PLOT_MUST_POINTS"))
    assert scene.simulation.schedule.phases[0].adaptive.frames == "must_points"
    scene.simulation.run(output=tmp_path / "out", progress=False, **scene.run, render=False)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "completed"
    pvd = (tmp_path / "out" / "body.pvd").read_text()
    # the first state, the must points 0.3 and 0.55, and the end (also a must point)
    assert [t for t in ("0.3", "0.55", "1.0") if f'timestep="{t}"' in pvd] == ["0.3", "0.55", "1.0"]
    assert pvd.count("<DataSet") == 4


def test_a_model_without_a_time_stepper_keeps_its_fixed_steps(tmp_path):
    data, _ = febio_scene(read_feb(MODELS / "uniaxial_neo_hookean.feb"), "m")
    assert "phases" not in data["simulation"] and data["run"]["steps"] == 4


@pytest.mark.parametrize(
    ("stepper", "message"),
    [
        ("<time_stepper><dtmin>0</dtmin><dtmax_curve>1</dtmax_curve></time_stepper>",
         r"stepped\.feb:\d+ <dtmax_curve>: this time_stepper setting is not supported"),
        ('<time_stepper type="adaptive"><dtmax>0.1</dtmax></time_stepper>',
         r"stepped\.feb:\d+ <time_stepper>: time_stepper type 'adaptive'"),
        ('<time_stepper><dtmax lc="7">0</dtmax></time_stepper>',
         r"stepped\.feb:\d+ <dtmax>: load curve 7 is used but not defined"),
        ("<time_stepper><opt_iter>-1</opt_iter></time_stepper>",
         r"<opt_iter>: opt_iter must be one integer >= 0"),
    ],
)  # fmt: skip
def test_time_stepper_settings_tissuesim_does_not_run_are_refused(tmp_path, stepper, message):
    with pytest.raises(FebError, match=message):
        read_feb(_model(tmp_path, stepper=stepper))


def test_tissuesim_run_stops_at_the_models_end(tmp_path, capsys):
    from tissuesim.cli import main

    feb = _model(tmp_path)
    assert main(["run", str(feb), "--out", str(tmp_path / "out"), "--no-render", "--quiet"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["end_time"] == 1.0 and report["steps"] < 15


def test_each_step_of_several_keeps_its_own_time_stepper_or_fixed_steps(tmp_path):
    """three_steps_pull_hold_release.feb with a time stepper in its first step only: that
    step's phase steps adaptively to t = 1 exactly, the two others keep their fixed steps."""
    text = (MODELS / "three_steps_pull_hold_release.feb").read_text()
    stepper = "<step_size>0.25</step_size>\n        <time_stepper><dtmax>0.5</dtmax></time_stepper>"
    feb = tmp_path / "steps.feb"
    feb.write_text(text.replace("<step_size>0.25</step_size>", stepper, 1))
    data, _ = febio_scene(read_feb(feb), "m")
    phases = data["simulation"]["phases"]
    assert phases[0]["adaptive"] == {"dtmin": 0.0, "dtmax": 0.5}
    assert "adaptive" not in phases[1] and "adaptive" not in phases[2]
    sim = _load(feb).simulation
    records = []
    while not sim.finished:
        records.append(sim.step())
    times = [r.time for r in records]
    # 0.25, then 0.2 of the way to dtmax (Newton takes fewer than opt_iter = 11 / 1.44): 0.3,
    # 0.34, and the step that would pass the phase's end lands on t = 1 exactly
    assert times[:4] == pytest.approx([0.25, 0.55, 0.89, 1.0]) and times[3] == 1.0
    assert times[4:] == pytest.approx([1.2, 1.4, 1.6, 1.8, 2.0] + [
        2.0 + 0.002 * k for k in range(1, 6)])  # fmt: skip
