"""FEBio models of several <step>s: each step is a phase (its own steps, step size and
analysis), the conditions and loads of a step hold during its time only, and the refusals
that remain name their element and line."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from tissuesim.febio import FebError, febio_scene, load_febio, read_feb

MODELS = Path(__file__).parent / "models"
FEB = MODELS / "three_steps_pull_hold_release.feb"
E, NU = 1e4, 0.3
MU, LAM = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))


def _uniaxial(stretch: float) -> float:
    """Nominal stress P_xx of FEBio's neo-Hookean in uniaxial tension, lateral faces free."""

    def lateral(t):
        return MU * (t - 1 / t) + LAM * np.log(stretch * t * t) / t

    t = brentq(lateral, 0.3, 1.0)
    return MU * (stretch - 1 / stretch) + LAM * np.log(stretch * t * t) / stretch


def test_each_step_becomes_a_phase_and_its_conditions_hold_in_its_window():
    model = read_feb(FEB)
    assert [(p["time_steps"], p["step_size"], p["analysis"]) for p in model.phases] == [
        (4, 0.25, "static"),
        (5, 0.2, "static"),
        (5, 0.002, "dynamic"),
    ]
    data, _ = febio_scene(model, "m")
    phases = data["simulation"]["phases"]
    assert [p["integrator"] for p in phases] == ["quasistatic", "quasistatic", "newmark"]
    assert data["simulation"]["newmark"] == [0.25, 0.5]
    assert data["run"]["steps"] == 14
    pull = next(d for d in data["dirichlet"] if d.get("name") == "pull")
    assert pull["active"] == [0.0, 1.0]
    assert "(t > 1.0) * (t <= 2.0)" in data["traction"][0]["traction"][0]
    assert all("active" not in d for d in data["dirichlet"] if d.get("name") != "pull")


def test_pull_then_hold_then_release_follow_the_closed_forms():
    """Step 1 pulls the face to a stretch of 1.2 (its reaction is the closed-form nominal
    stress); step 2 lets go of it and holds it with a 500 Pa dead traction instead (the
    block settles at the stretch where P_xx = 500 and the released condition reports no
    force); step 3 removes the traction and integrates dynamically (the face moves back)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the model's notes (its unused <Constants>)
        sim = load_febio(FEB).simulation
    X = sim.body("body").mesh.points
    face = np.isclose(X[:, 0], 1.0)
    records = [sim.step() for _ in range(4)]
    assert sim.integrator == "quasistatic" and sim.time_step == 0.25
    assert records[-1].extra["forces"]["pull"][0] == pytest.approx(_uniaxial(1.2), rel=1e-6)
    for _ in range(5):
        record = sim.step()
    assert sim.time == pytest.approx(2.0, abs=1e-12)
    assert record.extra["forces"]["pull"] == [0.0, 0.0, 0.0]
    stretch = brentq(lambda s: _uniaxial(s) - 500.0, 1.0, 1.2)
    x = sim.positions
    assert np.allclose(x[face, 0], stretch, atol=1e-7)
    assert record.extra["forces"]["symmetry_x"][0] == pytest.approx(-500.0, rel=1e-9)
    held = x[face, 0].mean()
    for _ in range(5):
        record = sim.step()
    assert sim.integrator == "newmark" and sim.time_step == 0.002
    assert sim.time == pytest.approx(2.01, abs=1e-12)
    assert sim.positions[face, 0].mean() < held - 1e-6  # the traction is gone: it springs back


STEP_REFUSALS = {
    "relative": (
        "<relative>0</relative>",
        "<relative>1</relative>",
        "relative = 1 in a step after the first",
    ),
    "contact": (
        '<step id="2" name="hold">',
        '<step id="2" name="hold">\n      <Contact/>',
        "contact given in one <step> of several",
    ),
}


@pytest.mark.parametrize("case", sorted(STEP_REFUSALS))
def test_step_refusals_name_the_element_and_line(case, tmp_path):
    old, new, message = STEP_REFUSALS[case]
    text = FEB.read_text()
    if case == "relative":  # move the pull into step 2, relative to where step 2 starts
        start, end = text.index("      <Boundary>\n        <bc"), text.index("    </step>")
        block = text[start:end].replace(old, new)
        text = text[:start] + text[end:]
        text = text.replace("      <Loads>", block + "      <Loads>")
    else:
        text = text.replace(old, new)
    feb = tmp_path / "bad.feb"
    feb.write_text(text)
    with pytest.raises(FebError) as info:
        read_feb(feb)
    said = str(info.value)
    assert "\n" not in said and message in said
    tag = "relative" if case == "relative" else "Contact"
    line = next(i for i, s in enumerate(text.splitlines(), 1) if f"<{tag}" in s and "1<" in s
                or (tag == "Contact" and "<Contact" in s))  # fmt: skip
    assert f"bad.feb:{line} <{tag}>" in said


def test_relative_in_the_first_step_is_the_same_as_absolute(tmp_path):
    text = FEB.read_text().replace("<relative>0</relative>", "<relative>1</relative>")
    feb = tmp_path / "rel.feb"
    feb.write_text(text)
    assert read_feb(feb).dirichlet[-1][2].value[0] == 0.2


def test_the_shipped_artery_strip_relaxes_under_its_hold():
    """The shipped FEBio example (HGO in an uncoupled Prony series, three steps): the pull of
    step 1 hands over to step 2's hold, under which the force relaxes."""
    from tissuesim.scene.examples import example_path

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = load_febio(example_path("artery_strip")).simulation
    forces = [sim.step().extra["forces"] for _ in range(13)]
    pulled, held = forces[9], forces[10:]
    assert pulled["hold"] == [0.0, 0.0, 0.0] and held[0]["pull"] == [0.0, 0.0, 0.0]
    assert pulled["pull"][0] == pytest.approx(0.110, abs=1e-3)
    relaxing = [f["hold"][0] for f in held]
    assert relaxing[0] < pulled["pull"][0] and np.all(np.diff(relaxing) < 0)
