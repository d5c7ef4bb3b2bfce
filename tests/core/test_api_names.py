"""Issue 41: what a new user reaches for first is where they look: the obstacle shapes,
ContactPair and read_surface import from ``tissuesim``; ``add_obstacle`` takes a fixed place as
numbers, as scenes do; contact needs no extra; the command-line page covers every command."""

from __future__ import annotations

import importlib.util
import pickle
import re
from pathlib import Path

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.cli import main
from tissuesim.errors import InputError

DOCS = Path(__file__).resolve().parents[2] / "docs"


def test_contact_names_import_from_tissuesim():
    from tissuesim import ContactPair, capsule, cylinder, plane, read_surface, sphere
    from tissuesim.contact import obstacles, pairs
    from tissuesim.frames import sampling

    assert (sphere, plane, capsule, cylinder) == (
        obstacles.sphere,
        obstacles.plane,
        obstacles.capsule,
        obstacles.cylinder,
    )
    assert ContactPair is pairs.ContactPair and read_surface is sampling.read_surface
    for name in ("ContactPair", "sphere", "plane", "capsule", "cylinder", "read_surface"):
        assert name in ts.__all__


def test_add_obstacle_takes_a_fixed_translation_as_numbers(sim):
    probe = ts.sphere((0.05, 0.025, 0.07), 0.01)
    name = sim.add_obstacle("probe", probe, translation=[0.0, 0.0, 0.01], rotation=(0, 0, 0))
    ob = next(o for o in sim.obstacles if o.name == name)
    for t in (0.0, 1.0):
        np.testing.assert_allclose(ob.positions(t), probe.points + [0.0, 0.0, 0.01])
    assert pickle.loads(pickle.dumps(ob.translation))(2.0).tolist() == [0.0, 0.0, 0.01]
    ob.translation(0.0)[2] = 5.0  # a caller's change to the returned array is not kept
    assert ob.translation(0.0)[2] == 0.01


@pytest.mark.parametrize(
    ("value", "said"),
    [
        ([0.0, 0.01], r"^add_obstacle translation must be a list of 3 numbers \(m\)"),
        ([0.0, 0.0, float("nan")], r"^add_obstacle translation"),
        ("0 0 1", r"^add_obstacle: translation must be a function of t, three numbers \(m\)"),
        (0.01, r"^add_obstacle: translation must be a function of t, three numbers \(m\)"),
    ],
)
def test_a_bad_fixed_translation_is_one_line(sim, value, said):
    with pytest.raises(InputError, match=said):
        sim.add_obstacle("probe", ts.sphere((0.05, 0.025, 0.07), 0.01), translation=value)


def test_contact_is_not_said_to_need_an_extra(sim, monkeypatch):
    assert "extra" in ts.Simulation.set_contact.__doc__  # it says there is none
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "ipctk" else real(name, *a)
    )
    with pytest.raises(InputError) as info:
        sim.set_contact()
    said = str(info.value)
    assert "tissuesim[contact]" not in said and "pip install ipctk" in said


def test_the_command_line_page_covers_every_command(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    commands = re.search(r"\{([a-z,]+)\}", capsys.readouterr().out).group(1).split(",")
    assert "convert" in commands and "verify" in commands
    page = (DOCS / "guide" / "cli.md").read_text()
    overview = page.split("```text", 1)[1].split("```", 1)[0]
    for command in commands:
        assert f"## `tissuesim {command}`" in page, command
        assert f"tissuesim {command} " in overview, command
