"""A study of a Python function that builds the Simulation: varied by its keyword arguments,
each run equal to calling the function and running it alone, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from sweep_builders import bar  # tests/sweep is on sys.path (pytest prepends it)

import tissuesim
from tissuesim.errors import InputError


def test_a_study_of_a_function_equals_calling_it(tmp_path):
    vary = {"youngs_modulus": [800.0, 1500.0], "pull": "0.05:0.1:2"}
    results = tissuesim.sweep(
        bar, vary, steps=2, out=tmp_path / "s", workers=2, fields=["displacement"]
    )
    data = tissuesim.sweep.load_dataset(tmp_path / "s")
    assert [r["params"] for r in results] == [
        {"youngs_modulus": e, "pull": p} for e in (800.0, 1500.0) for p in (0.05, 0.1)
    ]
    for i, r in enumerate(results):
        assert r["status"] == "completed", r["error"]
        sim = bar(**r["params"])
        sim.run(2, progress=False, render=False)
        assert r["forces"] == sim.forces()
        assert np.array_equal(data["bar/displacement"][i], sim.body_displacement("bar"))
    assert results[1]["forces"]["pull"][0] > results[0]["forces"]["pull"][0] > 0


def test_a_study_of_a_function_needs_steps_and_names(tmp_path):
    with pytest.raises(InputError, match="needs steps="):
        tissuesim.sweep(bar, {"youngs_modulus": [1.0]}, out=tmp_path / "a")
    with pytest.raises(InputError, match="varies its keyword arguments"):
        tissuesim.sweep(bar, {"material.youngs_modulus": [1.0]}, steps=1, out=tmp_path / "b")
    # a wrong argument name is the run's error, recorded: the others go on
    results = tissuesim.sweep(
        bar, {"youngs_modulus": [900.0], "pul": [0.1]}, steps=1, out=tmp_path / "c", workers=1
    )
    assert results[0]["status"] == "failed" and "pul" in results[0]["error"]
