"""A study's parameters and samples: key paths into the scene's tables, value lists, ranges,
grids and seeded Sobol / Latin hypercube / random samples over intervals."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.errors import InputError
from tissuesim.sweep.keypaths import parse_key_path
from tissuesim.sweep.samples import Interval, coerce, make_samples, parameters, parse_values

DATA = {
    "material": {"model": "neo_hookean", "youngs_modulus": 1000.0, "poisson_ratio": 0.3},
    "mesh": {"generator": "box", "divisions": [4, 1, 1]},
    "obstacles": [
        {"name": "table", "translation": [0.0, 0.0, 0.0]},
        {"name": "probe", "translation": [0.0, 0.0, 0.02]},
    ],
    "bodies": [{"name": "a", "material": {"youngs_modulus": 5.0}}],
}


def test_a_grid_is_the_product_of_the_lists_first_key_slowest():
    params = parameters(
        {"material.youngs_modulus": "1e3:3e3:3", "material.poisson_ratio": [0.3, 0.45]}, DATA
    )
    runs = make_samples(params, None, "grid", 0)
    assert runs == [
        {"material.youngs_modulus": e, "material.poisson_ratio": nu}
        for e in (1000.0, 2000.0, 3000.0)
        for nu in (0.3, 0.45)
    ]


def test_value_syntax_lists_ranges_log_and_arrays():
    assert parse_values("1e3,2000, 5e3", "k") == (1000.0, 2000, 5000.0)
    assert parse_values("1:2:3", "k") == (1.0, 1.5, 2.0)
    assert parse_values("5:5:1", "k") == (5.0,)
    np.testing.assert_allclose(parse_values("1e2:1e4:3:log", "k"), (1e2, 1e3, 1e4), rtol=1e-14)
    assert parse_values("1e3:5e3", "k") == Interval(1e3, 5e3)
    assert parse_values("1e3:5e3:log", "k") == Interval(1e3, 5e3, log=True)
    assert parse_values("[[0, 0, 0.01], [0, 0, 0.02]]", "k") == ([0, 0, 0.01], [0, 0, 0.02])
    assert parse_values("neo_hookean,yeoh", "k") == ("neo_hookean", "yeoh")
    assert parse_values("true", "k") == (True,)


@pytest.mark.parametrize(
    "text, says",
    [
        ("1e3:5e3:x", "the count N must be an integer >= 1"),
        ("1e3:5e3:0", "the count N must be an integer >= 1"),
        ("1e3::5", "malformed range"),
        ("1:2:3:4", "malformed range"),
        ("5e3:1e3", "LOW < HIGH"),
        ("-1:10:log", "a log range needs ends > 0"),
        ("1e3;2e3", "is not a number or a word"),
        ("1,,2", "an empty value"),
        ("[1, 2", "not a TOML array"),
        ("nan,1", "not a finite number"),
    ],
)
def test_a_malformed_value_is_one_error_naming_the_key_and_the_syntax(text, says):
    with pytest.raises(InputError, match=says) as info:
        parse_values(text, "material.youngs_modulus")
    message = str(info.value)
    assert message.startswith("--vary material.youngs_modulus=")
    assert "\n" not in message


def test_key_paths_by_key_index_name_and_component():
    assert parse_key_path("bodies[0].material.youngs_modulus").get(DATA) == 5.0
    assert parse_key_path("obstacles[probe].translation").get(DATA) == [0.0, 0.0, 0.02]
    path = parse_key_path("obstacles[probe].translation[2]")
    data = {
        **DATA,
        "obstacles": [dict(o, translation=list(o["translation"])) for o in DATA["obstacles"]],
    }
    path.set(data, 0.05)
    assert data["obstacles"][1]["translation"] == [0.0, 0.0, 0.05]
    assert data["obstacles"][0]["translation"] == [0.0, 0.0, 0.0]
    assert DATA["obstacles"][1]["translation"][2] == 0.02  # the scene's data is not changed


@pytest.mark.parametrize(
    "key, says",
    [
        ("material.youngs_modulu", "did you mean 'youngs_modulus'"),
        ("materal.youngs_modulus", "did you mean 'material'"),
        ("obstacles[prbe].translation", "did you mean 'probe'"),
        ("obstacles[5].translation", "out of range"),
        ("obstacles.translation", "pick one entry first"),
        ("material..model", "not a key path"),
        ("material.density", "must be written in the scene"),
    ],
)
def test_an_unknown_key_path_names_the_key_and_the_fix(key, says):
    with pytest.raises(InputError, match=says) as info:
        parameters([f"{key}=1,2"], DATA)
    assert str(info.value).startswith(f"--vary {key}")


def test_sobol_samples_fill_the_intervals_the_same_for_the_same_seed():
    vary = {"material.youngs_modulus": "1e3:1e5:log", "material.poisson_ratio": "0.3:0.45"}
    params = parameters(vary, DATA)
    runs = make_samples(params, 8, "sobol", 7)
    assert len(runs) == 8
    e = np.array([r["material.youngs_modulus"] for r in runs])
    nu = np.array([r["material.poisson_ratio"] for r in runs])
    assert ((1e3 <= e) & (e <= 1e5)).all() and ((0.3 <= nu) & (nu <= 0.45)).all()
    # Sobol's balance in log: 8 points, one in each eighth of [log 1e3, log 1e5]
    eighths = np.floor((np.log(e) - np.log(1e3)) / (np.log(1e5) - np.log(1e3)) * 8)
    assert sorted(eighths) == list(range(8))
    assert make_samples(params, 8, "sobol", 7) == runs
    assert make_samples(params, 8, "sobol", 8) != runs


def test_latin_hypercube_has_one_point_per_stratum_and_lists_cross_the_samples():
    params = parameters(
        {"material.model": ["neo_hookean", "yeoh"], "material.youngs_modulus": "0:1"}, DATA
    )
    runs = make_samples(params, 5, "lhs", 3)
    assert [r["material.model"] for r in runs] == ["neo_hookean"] * 5 + ["yeoh"] * 5
    e = np.array([r["material.youngs_modulus"] for r in runs[:5]])
    assert sorted(np.floor(e * 5)) == [0, 1, 2, 3, 4]
    assert [r["material.youngs_modulus"] for r in runs[5:]] == list(e)  # the same points


@pytest.mark.parametrize(
    "vary, samples, sampler, says",
    [
        ({"material.youngs_modulus": "1:2"}, None, "grid", "needs a sampler"),
        ({"material.youngs_modulus": "1:2"}, None, "sobol", "--samples N"),
        ({"material.youngs_modulus": "1,2"}, 4, "grid", "--samples N applies to intervals"),
        ({"material.youngs_modulus": "1,2"}, None, "sobol", "no interval to sample"),
        ({"material.youngs_modulus": "1:2"}, 4, "halton", "choose one of"),
    ],
)
def test_sampler_misuse_is_refused(vary, samples, sampler, says):
    with pytest.raises(InputError, match=says):
        make_samples(parameters(vary, DATA), samples, sampler, 0)


def test_values_take_the_type_of_the_scene_value():
    assert coerce(3.6, 4) == 4 and type(coerce(3.6, 4)) is int  # divisions stay integers
    assert type(coerce(2, 1000.0)) is float
    assert coerce(np.float64(0.5), 1.0) == 0.5 and type(coerce(np.float64(0.5), 1.0)) is float
    assert coerce("yeoh", "neo_hookean") == "yeoh"


def test_python_values_lists_arrays_and_intervals():
    params = parameters(
        {
            "material.youngs_modulus": Interval(1e3, 1e5, log=True),
            "material.poisson_ratio": np.array([0.3, 0.4]),
        },
        DATA,
    )
    assert params[0].interval == Interval(1e3, 1e5, log=True)
    assert params[1].values == (0.3, 0.4) and type(params[1].values[0]) is float
    runs = make_samples(params, 4, "random", 2)
    assert len(runs) == 8 and all(1e3 <= r["material.youngs_modulus"] <= 1e5 for r in runs)
    with pytest.raises(InputError, match="give a non-empty list of values"):
        parameters({"material.youngs_modulus": []}, DATA)
    with pytest.raises(InputError, match="given twice"):
        parameters(["material.youngs_modulus=1,2", "material.youngs_modulus=3"], DATA)
