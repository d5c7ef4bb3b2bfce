"""Scene-file expressions: vectorised values against NumPy, and every forbidden construct
refused with a SceneError that names the offending piece."""

from __future__ import annotations

import time

import numpy as np
import pytest

from tissuesim.errors import SceneError
from tissuesim.scene.expressions import compile_expression, compile_vector

X2 = np.array([[-1.0, 2.0], [0.5, -0.3], [0.0, 0.0], [2.0, 1.5]])
X3 = np.column_stack([X2, [0.1, -0.2, 0.3, 0.0]])


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("x*sin(t)", lambda x, y, z, t: x * np.sin(t)),
        ("sin(abs(x)*t)", lambda x, y, z, t: np.sin(np.abs(x) * t)),
        ("where(x > 0, 1, -1)", lambda x, y, z, t: np.where(x > 0, 1.0, -1.0)),
        ("2**3", lambda x, y, z, t: np.full_like(x, 8.0)),
        ("7 // 2 + 7 % 2", lambda x, y, z, t: np.full_like(x, 4.0)),
        ("-x + y*z - 1/2", lambda x, y, z, t: -x + y * z - 0.5),
        ("max(x, y) + min(x, 0)", lambda x, y, z, t: np.maximum(x, y) + np.minimum(x, 0)),
        ("clip(y, 0, 1) * pi", lambda x, y, z, t: np.clip(y, 0, 1) * np.pi),
        ("e**(x*t) + sqrt(abs(y))", lambda x, y, z, t: np.exp(x * t) + np.sqrt(np.abs(y))),
        ("(x < 1) * (y >= 0)", lambda x, y, z, t: ((x < 1) & (y >= 0)).astype(float)),
        (
            "arctan2(y, x) + heaviside(x, 0.5)",
            lambda x, y, z, t: np.arctan2(y, x) + np.heaviside(x, 0.5),
        ),
    ],
)
def test_expression_matches_numpy(text, expected):
    t = 0.7
    f = compile_expression(text, "test")
    x, y, z = X3.T
    np.testing.assert_allclose(f(X3, t), expected(x, y, z, t), rtol=0, atol=1e-15)
    out = f(X3, t)
    assert out.shape == (len(X3),)
    assert out.dtype == float


def test_z_is_zero_on_2d_points_and_numbers_are_constant():
    np.testing.assert_array_equal(compile_expression("z + 1", "w")(X2, 0.0), np.ones(len(X2)))
    np.testing.assert_array_equal(compile_expression(2.5, "w")(X2, 3.0), np.full(len(X2), 2.5))
    np.testing.assert_array_equal(compile_expression(3, "w")(X2, 3.0), np.full(len(X2), 3.0))


def test_vector_of_expressions_matches_numpy():
    f = compile_vector(["x*sin(t)", "sin(abs(x)*t)", "where(x > 0, 1, -1)"], 3, "v")
    t = 1.3
    x = X3[:, 0]
    expected = np.column_stack([x * np.sin(t), np.sin(np.abs(x) * t), np.where(x > 0, 1, -1)])
    got = f(X3, t)
    assert got.shape == (len(X3), 3)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-15)
    # Numbers and strings may be mixed.
    g = compile_vector([0, "2**3"], 2, "v")
    np.testing.assert_array_equal(g(X2, 0.0), np.column_stack([np.zeros(4), np.full(4, 8.0)]))


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("__import__('os')", "__import__"),
        ("x.real", "Attribute"),
        ("x.__class__", "Attribute"),
        ("foo(x)", "foo"),
        ("q", "'q'"),
        ("x + q", "'q'"),
        ("lambda: 1", "Lambda"),
        ("(lambda: 1)()", "lambda"),
        ("x[0]", "Subscript"),
        ("'a'", "numeric constants"),
        ("sin('a')", "numeric constants"),
        ("clip(x, a_min=0, a_max=1)", "a_min"),
        ("sin(x, out=y)", "out"),
        ("sin(x, y)", "sin() takes 1 argument"),
        ("clip(x, 0, 1, x)", "clip() takes 3 argument"),
        ("where(x > 0, 1)", "where() takes 3 argument"),
        ("sin", "'sin' is a function"),
        ("x + cos", "'cos' is a function"),
        ("sin.__call__(x)", "sin.__call__"),
        ("1 < x < 2", "chained comparison"),
        ("x if y else 1", "IfExp"),
        ("[x, y]", "List"),
        ("x is y", "Is"),
        ("f'{x}'", "JoinedStr"),
        ("sin(*[x])", "Starred"),
        ("__builtins__", "__builtins__"),
        ("1j", "numeric constants"),
        ("None", "numeric constants"),
        ("x +", "cannot parse"),
        ("", "cannot parse"),
    ],
)
def test_forbidden_construct_names_the_offender(text, named):
    with pytest.raises(SceneError) as info:
        compile_expression(text, "[[dirichlet]] #1 displacement[0]")
    message = str(info.value)
    assert named in message
    assert "[[dirichlet]] #1 displacement[0]" in message


@pytest.mark.parametrize("value", [None, True, [1.0], {"a": 1}])
def test_non_expression_values_are_refused(value):
    with pytest.raises(SceneError, match="expected a number or an expression string"):
        compile_expression(value, "w")


def test_nothing_is_written_into_the_callers_points():
    # A ufunc's second positional argument is ``out``; it is refused at compile time, and the
    # evaluation works on a copy in any case.
    X = X2.copy()
    f = compile_vector(["x*2", "-y"], 2, "v")
    f(X, 0.5)
    np.testing.assert_array_equal(X, X2)
    with pytest.raises(SceneError):
        compile_expression("sin(x, y)", "w")


def test_huge_power_does_not_hang():
    start = time.perf_counter()
    try:
        value = compile_expression("9**9**9", "w")(X2, 0.0)
    except SceneError as exc:
        assert "9**9**9" in str(exc)
    else:
        assert np.all(np.isinf(value))
    assert time.perf_counter() - start < 1.0


def test_pathologically_long_expression_is_a_scene_error():
    start = time.perf_counter()
    for text in ("-" * 100_000 + "x", "x+" * 20_000 + "x", "x+" * 1000 + "x"):
        with pytest.raises(SceneError, match="too"):
            compile_expression(text, "w")
    assert time.perf_counter() - start < 5.0


def test_runtime_failures_are_scene_errors():
    with pytest.raises(SceneError, match="evaluating '1/0' failed"):
        compile_expression("1/0", "w")(X2, 0.0)
    # Invalid values of NumPy functions give nan silently (no warnings, no exception).
    assert np.isnan(compile_expression("log(-1)", "w")(X2, 0.0)).all()


@pytest.mark.parametrize("items", [["x"], ["x", "y", "z"], "x", 3, ("x",)])
def test_wrong_vector_length(items):
    with pytest.raises(SceneError, match="expected a list of 2 numbers or expressions") as info:
        compile_vector(items, 2, "[initial] velocity")
    assert "[initial] velocity" in str(info.value)


def test_vector_entry_errors_name_the_component():
    with pytest.raises(SceneError, match=r"traction\[1\]: unknown name 'q'"):
        compile_vector(["sin(t)", "q"], 2, "traction")
