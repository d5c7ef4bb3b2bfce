"""Issue 41: ``fit_material`` with fewer data points than parameters is an error, a fit whose
data cannot tell the parameters apart is not ``success=True``, and bounds that are inverted
or exclude the start name the parameter (not SciPy's raw message)."""

from __future__ import annotations

import pytest

from tissuesim import fit_material
from tissuesim.errors import InputError

START = {"c1": 1e3, "c2": 1e2}


def test_fewer_points_than_parameters_is_refused():
    with pytest.raises(InputError) as info:
        fit_material("mooney_rivlin", {"uniaxial": ([1.2], [1000.0])}, initial=START)
    said = str(info.value)
    assert "1 data point for 2 fitted parameters (c1, c2)" in said
    assert "underdetermined" in said and "fixed" in said


def test_points_at_one_stretch_are_flagged_underdetermined():
    data = {"uniaxial": ([1.2, 1.2, 1.2], [1000.0, 1000.0, 1000.0])}
    result = fit_material("mooney_rivlin", data, initial=START)
    assert result.success is False
    assert result.message.startswith("underdetermined: the data determine only 1 combination")
    held = fit_material("mooney_rivlin", data, initial={"c1": 1e3}, fixed={"c2": 0.0})
    assert held.success and held.rms < 1e-8


@pytest.mark.parametrize(
    ("bounds", "message"),
    [
        ({"c2": (10.0, -10.0)}, "bounds for c2: low 10 must be below high -10 (swap them)"),
        ({"c2": (0.0, 50.0)}, "initial c2 = 100 is outside its bounds (0, 50)"),
        ({"c1": 5.0}, "bounds for c1: expected (low, high)"),
    ],
)
def test_bad_bounds_name_the_parameter(bounds, message):
    data = {"uniaxial": ([1.1, 1.2, 1.3], [500.0, 1000.0, 1600.0])}
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        fit_material("mooney_rivlin", data, initial=START, bounds=bounds)
