"""What every scene reader shares (``loader.py`` for one body, ``fem_body.py``, ``frames.py``,
``coupled.py``, ``cuts.py``, ``contact.py``): the Scene it returns, the error helpers that name
the file and the table (unknown keys with a suggestion, library errors re-raised as
SceneErrors), the [simulation], [newton], [run] and [material] tables, numbers, body names,
expressions of time and conditions."""

from __future__ import annotations

import difflib
import numbers
from contextlib import contextmanager
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from tissuesim.errors import SceneError, TissueSimError
from tissuesim.render.scene import FIELDS
from tissuesim.scene.expressions import compile_vector
from tissuesim.validate import short

__all__ = ["Scene", "RUN_KEYS", "SELECTORS", "SIMULATION_KEYS", "condition", "of_time"]

RUN_KEYS = ("steps", "every", "render", "field")

SELECTORS = {
    "vertices": {"on_plane", "in_box", "tagged", "boundary", "where"},
    "facets": {"on_plane", "in_box", "tagged", "boundary", "where"},
}

SIMULATION_KEYS = (
    "density",
    "integrator",
    "time_step",
    "mass",
    "max_step_halvings",
    "start_time",
    "backend",
    "order",
    "formulation",
    "phases",
    "newmark",
    "generalized_alpha",
    "adaptive",
)

#: what pictures can be coloured by
FIELD_CHOICES = tuple(FIELDS)


@dataclass
class Scene:
    """A scene ready to run: the Simulation and the
    arguments of its ``run``."""

    simulation: Any
    name: str
    source: str
    run: dict[str, Any] = field(default_factory=dict)


def _unknown(keys, valid, where: str) -> None:
    for key in keys:
        if key not in valid:
            close = difflib.get_close_matches(key, sorted(valid), n=1)
            hint = f"did you mean {close[0]!r}?" if close else f"valid keys: {sorted(valid)}"
            raise SceneError(f"{where}: unknown key {key!r}; {hint}")


@contextmanager
def _context(where: str):
    """Re-raise library errors (bad values found by the API) as SceneErrors naming ``where``."""
    try:
        yield
    except SceneError:
        raise
    except TissueSimError as exc:
        raise SceneError(f"{where}: {exc}") from exc
    except (ValueError, TypeError, KeyError, IndexError, AttributeError, ArithmeticError) as exc:
        raise SceneError(wrong_form(where)) from exc


def wrong_form(where: str) -> str:
    """The message for a value that no validator caught (numpy or Python refused it): the
    place, not Python's wording; ``--debug`` shows the traceback."""
    return (
        f"{where}: a value has the wrong type or shape for its key (a string where a number "
        "or list belongs, a list of the wrong length, a table where a value belongs); see the "
        "scene-key reference (docs/reference/scene-keys.md), or rerun with --debug"
    )


def _table(data: dict, key: str, where: str, array: bool = False):
    value = data.get(key, [] if array else {})
    if array:
        if isinstance(value, dict):
            raise SceneError(f"{where}: [{key}] must be an array of tables: write [[{key}]]")
        if not isinstance(value, list):
            raise SceneError(f"{where}: {key} must be an array of tables ([[{key}]])")
        for i, item in enumerate(value, start=1):
            if not isinstance(item, dict):
                raise SceneError(
                    f"{where}: [[{key}]] #{i} must be a table (key = value lines under "
                    f"[[{key}]]), not {short(item)}"
                )
        return value
    if not isinstance(value, dict):
        raise SceneError(f"{where}: {key} must be a table ([{key}])")
    return value


def _short_label(source: str):
    """Where a table of a one-body scene is: "scene.toml [[dirichlet]] #2", "[mesh]"."""

    def label(key: str | None = None, i: int | None = None) -> str:
        if key is None:
            return source
        return f"{source} [{key}]" if i is None else f"{source} [[{key}]] #{i}"

    return label


def body_label(source: str, array: str, n: int):
    """Where a table of the n-th [[bodies]] (or [[organs]]) entry is: "bodies[2]",
    "bodies[2].dirichlet[1]" (counting from 1)."""

    def label(key: str | None = None, i: int | None = None) -> str:
        head = f"{source} {array}[{n}]"
        if key is None:
            return head
        return f"{head}.{key}" if i is None else f"{head}.{key}[{i}]"

    return label


def of_time(value, d: int, where: str, what: str = "this value"):
    """t -> (d,) from d numbers or expressions of t only: a value that is the same for every
    point (a force on a vertex set, a grasper's motion), so x, y, z are refused rather than
    evaluated at some point."""
    f = compile_vector(value, d, where)
    for i, item in enumerate(value):
        used = _variables(item) & set("xyz")
        if used:
            raise SceneError(
                f"{where}[{i}]: {what} depends on t only; {sorted(used)[0]!r} has no meaning "
                f"here (in {item!r})"
            )
    origin = np.zeros((1, d))

    def at(t: float) -> np.ndarray:
        return f(origin, t)[0]

    return at


def _material(data: dict, source: str, where: str | None = None, mesh=None):
    """[material]: make_material(model, **parameters); shared by mesh and frame scenes, and by
    the inline ``material = {...}`` tables of coupled scenes (``where`` names those). A FEM
    body passes its ``mesh``, on which fibre directions given as cell data or expressions are
    evaluated (``scene/tables/fibre_fields.py``)."""
    from tissuesim.materials import make_material
    from tissuesim.scene.tables.fibre_fields import resolve_directions

    where = where or f"{source} [material]"
    material_table = dict(_table(data, "material", source))
    if "model" not in material_table:
        raise SceneError(f"{where}: missing key 'model' (e.g. 'course_neo_hookean')")
    material_table = resolve_directions(material_table, mesh, where)
    with _context(where):
        return make_material(material_table.pop("model"), **material_table)


def _newton(data: dict, source: str):
    """[newton]: NewtonOptions(**table), unknown options suggest the nearest field."""
    from tissuesim.solve.newton import NewtonOptions

    newton_table = _table(data, "newton", source)
    _unknown(newton_table, {f.name for f in fields(NewtonOptions)}, f"{source} [newton]")
    with _context(f"{source} [newton]"):
        return NewtonOptions(**newton_table)


def _run_table(data: dict, source: str) -> dict[str, Any]:
    """[run]: the arguments of ``run`` (steps, every, render), checked before anything runs."""
    run = _table(data, "run", source)
    _unknown(run, RUN_KEYS, f"{source} [run]")
    for key, ok, want in (
        ("steps", lambda v: type(v) is int and v >= 0, "an integer >= 0"),
        ("every", lambda v: type(v) is int and v >= 1, "an integer >= 1"),
        ("render", lambda v: isinstance(v, bool), "true or false"),
        ("field", lambda v: v in FIELD_CHOICES, f"one of {list(FIELD_CHOICES)}"),
    ):
        if key in run and not ok(run[key]):
            raise SceneError(f"{source} [run]: {key} must be {want}, not {run[key]!r}")
    return dict(run)


def _field(value, d: int, where: str):
    """A constant vector stays an array; any expression makes a callable (X, t)."""
    if isinstance(value, list) and all(isinstance(v, (int, float)) for v in value):
        if len(value) != d:
            raise SceneError(f"{where}: expected {d} components, got {len(value)}")
        return np.asarray(value, dtype=float)
    return compile_vector(value, d, where)


def _variables(text) -> set[str]:
    """Names an expression uses (none for a number, or text that does not parse: the
    expression compiler reports that)."""
    import ast

    if not isinstance(text, str):
        return set()
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, RecursionError, MemoryError, ValueError):
        return set()
    return {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}


def condition(text, where: str):
    """points (k, d) -> (k,) bool from a condition on the rest coordinates x, y, z (no t)."""
    from tissuesim.scene.expressions import compile_expression

    if not isinstance(text, str):
        raise SceneError(
            f"{where}: expected a condition on the rest coordinates as a string, e.g. "
            f'where = "z < -0.032", got {short(text)}'
        )
    if "t" in _variables(text):
        raise SceneError(
            f"{where}: {text!r} uses t; a selection is made once, on the rest coordinates x, y, z"
        )
    f = compile_expression(text, where)

    def mask(points: np.ndarray) -> np.ndarray:
        values = f(points, 0.0)
        if not np.all(np.isfinite(values)):
            raise SceneError(f"{where}: {text!r} is not finite at every point")
        return values != 0

    return mask


def _is_number(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _body_name(sim, value, where: str) -> str:
    """``value`` as the name of one of the scene's bodies (``where``'s body key)."""
    if not isinstance(value, str) or value not in sim.bodies:
        raise SceneError(
            f"{where} body: {short(value)} is not a body of this scene; bodies: "
            f"{', '.join(sim.bodies)}"
        )
    return value


def _number(value, where: str, want: str, positive: bool = True) -> float:
    """A finite number, > 0 unless ``positive`` is False (``want`` says what, for the error)."""
    if not (_is_number(value) and np.isfinite(value) and (value > 0 or not positive)):
        raise SceneError(f"{where}: must be {want}, not {short(value)}")
    return float(value)


def _required(table: dict, key: str, where: str):
    if key not in table:
        raise SceneError(f"{where}: missing key {key!r}")
    return table[key]


def _vector3(value, where: str) -> np.ndarray:
    """Three finite numbers (a TOML array), e.g. an acceleration or a corner."""
    if not (isinstance(value, list) and len(value) == 3 and all(_is_number(v) for v in value)):
        raise SceneError(f"{where}: expected 3 numbers [x, y, z], got {short(value)}")
    v = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(v)):
        raise SceneError(f"{where}: expected 3 finite numbers, got {short(value)}")
    return v


def _point_list(value, where: str) -> np.ndarray:
    """A non-empty list of [x, y, z] points as a (k, 3) array."""
    ok = isinstance(value, list) and value and all(isinstance(p, list) for p in value)
    if not ok:
        raise SceneError(f"{where}: expected a list of points [[x, y, z], ...], got {short(value)}")
    return np.array([_vector3(p, f"{where}[{i}]") for i, p in enumerate(value)])
