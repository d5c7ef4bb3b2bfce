"""Issue 41: a body larger than a few metres or smaller than a millimetre (a surface in
millimetres run as metres: a 100 m, 4e9 kg organ) is warned of once, through Python's
warnings (the command line prints them as one "tissuesim: warning:" line)."""

from __future__ import annotations

import warnings

import pytest

import tissuesim as ts
from tissuesim.cli import main

MATERIAL = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)


def added(*meshes) -> list[str]:
    sim = ts.Simulation(integrator="quasistatic", time_step=0.1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for k, mesh in enumerate(meshes):
            sim.add_body(f"b{k}", mesh, MATERIAL)
    return [str(w.message) for w in caught if "SI units" in str(w.message)]


def test_a_body_in_millimetres_is_warned_of_once():
    big = ts.box((0, 0, 0), (100, 50, 50), (2, 1, 1))
    said = added(big, big)
    assert len(said) == 1  # once, not per body
    assert "body 'b0' is 100 m across (larger than 5 m)" in said[0]
    assert "millimetres" in said[0] and "1e-3" in said[0]


def test_a_tiny_body_is_warned_of():
    said = added(ts.rectangle((0, 0), (5e-4, 2e-4), (2, 1)))
    assert len(said) == 1 and "0.0005 m across (smaller than 1 mm)" in said[0]


def test_bodies_of_organ_size_are_not():
    assert added(ts.box((0, 0, 0), (0.1, 0.05, 0.05), (2, 1, 1)), ts.box(divisions=(2, 1, 1))) == []


def test_the_command_line_prints_it_once(tmp_path, capsys):
    scene = tmp_path / "big.toml"
    scene.write_text(
        '[mesh]\ngenerator = "box"\nlower = [0, 0, 0]\nupper = [100, 50, 50]\n'
        'divisions = [2, 1, 1]\n\n[material]\nmodel = "neo_hookean"\n'
        "youngs_modulus = 1e4\npoisson_ratio = 0.3\n\n[simulation]\n"
        'integrator = "quasistatic"\ntime_step = 0.1\n\n[[dirichlet]]\n'
        "vertices = { on_plane = { axis = 0, value = 0.0 } }\n"
    )
    out = tmp_path / "out"
    code = main(["run", str(scene), "--steps", "1", "--out", str(out), "--no-render", "--quiet"])
    assert code == 0
    err = capsys.readouterr().err
    lines = [s for s in err.splitlines() if "SI units" in s]
    assert len(lines) == 1 and lines[0].startswith("tissuesim: warning: body 'body' is 100 m")


@pytest.mark.parametrize("size", [1e-3, 5.0])
def test_the_range_is_inclusive(size):
    assert added(ts.box((0, 0, 0), (size, size / 2, size / 2), (2, 1, 1))) == []
