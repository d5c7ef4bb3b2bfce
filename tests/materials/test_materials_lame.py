"""Elastic-constant conversion and parameter validation."""

from __future__ import annotations

import math

import pytest

from tissuesim.errors import MaterialError
from tissuesim.materials import lame_parameters


def test_course_example_conversion():
    mu, lam = lame_parameters(youngs_modulus=1000.0, poisson_ratio=0.3)
    assert mu == pytest.approx(384.6153846153846, rel=1e-14)
    assert lam == pytest.approx(576.9230769230769, rel=1e-14)


def test_lame_pair_passes_through():
    assert lame_parameters(shear_modulus=2.0, lame_lambda=-1.0) == (2.0, -1.0)


@pytest.mark.parametrize(
    ("params", "key"),
    [
        (dict(youngs_modulus=0.0, poisson_ratio=0.3), "youngs_modulus"),
        (dict(youngs_modulus=-5.0, poisson_ratio=0.3), "youngs_modulus"),
        (dict(youngs_modulus=1e3, poisson_ratio=0.5), "poisson_ratio"),
        (dict(youngs_modulus=1e3, poisson_ratio=-1.0), "poisson_ratio"),
        (dict(youngs_modulus=math.inf, poisson_ratio=0.3), "youngs_modulus"),
        (dict(youngs_modulus=1e3, poisson_ratio=math.nan), "poisson_ratio"),
        (dict(shear_modulus=0.0, lame_lambda=1.0), "shear_modulus"),
        (dict(shear_modulus=3.0, lame_lambda=-2.0), "lame_lambda"),
        (dict(shear_modulus="soft", lame_lambda=1.0), "shear_modulus"),
    ],
)
def test_invalid_values_name_the_key(params, key):
    with pytest.raises(MaterialError, match=key):
        lame_parameters(**params)


@pytest.mark.parametrize(
    "params",
    [
        {},
        dict(youngs_modulus=1e3),
        dict(youngs_modulus=1e3, shear_modulus=300.0),
        dict(youngs_modulus=1e3, poisson_ratio=0.3, lame_lambda=5.0),
    ],
)
def test_mixed_or_missing_pairs(params):
    with pytest.raises(MaterialError, match="youngs_modulus, poisson_ratio") as info:
        lame_parameters(**params)
    assert "shear_modulus, lame_lambda" in str(info.value)
