"""TOML scene files -> the same objects the Python API builds.

Every key is the name of an argument of the Python API (see README, "Scene files"):

    [mesh]          rectangle(...) / box(...) via ``generator``, or read_mesh via ``file``
    [material]      make_material(model, **parameters)
    [simulation]    Simulation(...)
    [newton]        NewtonOptions(...)
    [[dirichlet]]   Simulation.add_dirichlet(vertices, displacement, components)
    [[traction]]    Simulation.add_traction(facets, traction)
    [gravity]       Simulation.add_gravity(acceleration)
    [[body_force]]  Simulation.add_body_force(force_density)
    [initial]       Simulation.set_velocity(velocity)
    [run]           Simulation.run(steps, every, render)

Vertex and facet sets are selector tables, e.g. ``{ on_plane = { axis = 0, value = -1.0 } }``,
naming a function of ``tissuesim.mesh.select``. Vectors may hold numbers or expressions in
x, y, z, t (``tissuesim.scene.expressions``). Unknown keys are errors that suggest the nearest
valid key; every error names the file and the table.

A scene with a ``[frames]`` table is a meshless frame-based body instead: its
tables are read by ``tissuesim.scene.frames``, which shares [material], [simulation], [newton],
[gravity] and [run] with this module.

A scene with ``[[bodies]]`` (or ``[[organs]]``) tables has many bodies (organs joined
by connective tissue, with [[graspers]], [tissue], [[cuts]] and [tearing]): its tables are read
by ``tissuesim.scene.coupled``, which shares [simulation], [newton], [gravity], [run], the
material tables and the vertex selectors with this module. ``[[organs]]`` decides even when
other tables are present (a [mesh] or [frames] table beside it is then an error).
"""

from __future__ import annotations

import difflib
import inspect
import tomllib
from contextlib import contextmanager
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import SceneError, TissueSimError
from tissuesim.render.scene import FIELDS
from tissuesim.scene.contact import CONTACT_KEYS, OBSTACLE_KEYS
from tissuesim.scene.expressions import compile_vector
from tissuesim.validate import short

__all__ = ["Scene", "load_scene", "build_scene", "SCENE_KEYS"]

MESH_KEYS = {
    "generator": "rectangle, box or ellipsoid",
    "center": "ellipsoid: centre",
    "radii": "ellipsoid: semi-axes",
    "file": "path of a mesh file (relative to the scene file)",
    "lower": "generator: lower corner",
    "upper": "generator: upper corner",
    "divisions": "generator: cells per axis",
    "pattern": "rectangle: triangle pattern; box: tetrahedral split (mirrored or uniform)",
    "grading": "box: per-axis grading exponents (1 uniform, p finer towards lower, -p upper)",
    "merge_coincident": "file: merge vertices that coincide (an unwelded seam) instead of refusing",
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
)
#: the FEM body options a [simulation] table (short form) or a [[bodies]] table may set
FEM_BODY_OPTIONS = ("density", "mass", "order", "formulation")
RUN_KEYS = ("steps", "every", "render", "field")
SELECTORS = {
    "vertices": {"on_plane", "in_box", "tagged", "boundary", "where"},
    "facets": {"on_plane", "in_box", "tagged", "boundary", "where"},
}
SCENE_KEYS = {
    "mesh": set(MESH_KEYS),
    "material": None,  # checked by make_material
    "simulation": set(SIMULATION_KEYS),
    "newton": None,  # checked against NewtonOptions
    "dirichlet": {"vertices", "displacement", "components", "name"},
    "traction": {"facets", "traction"},
    "gravity": {"acceleration"},
    "body_force": {"force_density"},
    "initial": {"velocity"},
    "nodal_forces": {"vertices", "force"},
    "run": set(RUN_KEYS),
    "contact": set(CONTACT_KEYS),
    "obstacles": set(OBSTACLE_KEYS),
}
#: what pictures can be coloured by
FIELD_CHOICES = tuple(FIELDS)
#: the tables of one FEM body (top level in a one-body scene, inside each [[bodies]] entry)
FEM_BODY_KEYS = ("mesh", "material", "dirichlet", "traction", "body_force", "nodal_forces")
FEM_BODY_KEYS += ("initial",)
# Tables of frame scenes ([frames], tissuesim.scene.frames) that mean nothing for a [mesh] body.
FRAME_ONLY_KEYS = ("region", "fixed_frames", "prescribed_frames", "springs", "point_forces")
# Tables of coupled scenes ([[organs]], tissuesim.scene.coupled) that mean nothing for one body.
COUPLED_ONLY_KEYS = ("graspers", "tissue", "cuts", "tearing")


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
        "README's scene keys, or rerun with --debug"
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


def load_scene(path: str | Path) -> Scene:
    """Read a TOML scene file and build its Simulation."""
    from tissuesim.validate import regular_file

    try:
        path = regular_file(path, "scene file")
        text = path.read_text(encoding="utf-8")
    except TissueSimError as exc:
        raise SceneError(str(exc)) from None
    except OSError as exc:
        raise SceneError(f"{path}: cannot read the scene file ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise SceneError(f"{path}: not a text file (not UTF-8); a scene is a TOML file") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from None
    return build_scene(data, base_dir=path.parent, source=str(path), name=path.stem)


def build_scene(
    data: dict, *, base_dir: Path = Path("."), source: str = "<scene>", name: str = "scene"
) -> Scene:
    """Build a Scene from parsed TOML ``data``; errors name ``source`` and the table."""
    try:
        return _build(data, Path(base_dir), source, name)
    except SceneError:
        raise
    except TissueSimError as exc:
        raise SceneError(f"{source}: {exc}") from exc
    except (ValueError, TypeError, KeyError, IndexError, AttributeError, ArithmeticError) as exc:
        raise SceneError(wrong_form(source)) from exc


def _build(data: dict, base_dir: Path, source: str, name: str) -> Scene:
    from tissuesim.simulation import Simulation

    if "organs" in data or "bodies" in data:
        from tissuesim.scene.coupled import build_bodies_scene

        return build_bodies_scene(data, base_dir, source, name)
    if "frames" in data:
        from tissuesim.scene.frames import build_frame_scene

        return build_frame_scene(data, base_dir, source, name)
    frame_only = [key for key in data if key in FRAME_ONLY_KEYS]
    if frame_only:
        raise SceneError(
            f"{source}: [{frame_only[0]}] belongs to meshless frame bodies: add a [frames] "
            f"table (and a [region]) to make this a frame scene, or use the [mesh] tables "
            f"{sorted(SCENE_KEYS)}"
        )
    coupled_only = [key for key in data if key in COUPLED_ONLY_KEYS]
    if coupled_only:
        raise SceneError(
            f"{source}: [{coupled_only[0]}] belongs to coupled scenes (organs joined by "
            f"connective tissue): give the organs as [[organs]] tables (name, mesh, material) "
            f"instead of [mesh] and [material]"
        )
    # "frames", "organs" and "bodies" are valid too (handled above): a misspelt [frame] or
    # [[organ]] then suggests them
    _unknown(data, [*SCENE_KEYS, "frames", "organs", "bodies"], f"{source}: top level")
    newton = _newton(data, source)
    sim_table = dict(_table(data, "simulation", source))
    _unknown(sim_table, SIMULATION_KEYS, f"{source} [simulation]")
    body = {k: sim_table.pop(k) for k in FEM_BODY_OPTIONS if k in sim_table}
    with _context(f"{source} [simulation]"):
        sim = Simulation(newton=newton, **sim_table)
    tables = {k: data[k] for k in FEM_BODY_KEYS if k in data}
    add_fem_body(
        sim,
        "body",
        {**tables, **body},
        base_dir,
        source,
        _short_label(source),
        f"{source} [simulation]",
    )
    gravity = _table(data, "gravity", source)
    if gravity:
        _unknown(gravity, SCENE_KEYS["gravity"], f"{source} [gravity]")
        with _context(f"{source} [gravity]"):
            sim.add_gravity(gravity["acceleration"])
    from tissuesim.scene.contact import add_contact_tables

    add_contact_tables(sim, data, base_dir, source)
    return Scene(sim, name, source, _run_table(data, source))


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


def add_fem_body(
    sim, name: str, item: dict, base_dir: Path, source: str, label, options_where=None
) -> None:
    """A FEM body from its tables: mesh, material (required), density, mass, order,
    formulation, fix (a vertex selector), dirichlet, traction, body_force, nodal_forces (arrays
    of tables), initial."""
    if "mesh" not in item:
        raise SceneError(f"{label('mesh')}: missing: give a mesh = {{ generator = ... }} table")
    with _context(label("mesh")):
        mesh = _mesh(_table(item, "mesh", source), base_dir, label("mesh"))
    d = mesh.dim
    material = _material(item, source, label("material"))
    options = {k: item[k] for k in FEM_BODY_OPTIONS if k in item}
    with _context(options_where or label()):
        sim.add_body(name, mesh, material, **options)
    mesh = sim.body(name).mesh  # order = 2 adds midside nodes: select on the body's mesh
    if "fix" in item:
        vertices = _select(mesh, "vertices", item["fix"], label("fix"))
        with _context(label("fix")):
            sim.fix(name, vertices)
    for i, entry in enumerate(_table(item, "dirichlet", source, array=True), start=1):
        where = label("dirichlet", i)
        _unknown(entry, SCENE_KEYS["dirichlet"], where)
        if "vertices" not in entry:
            raise SceneError(f"{where}: missing key 'vertices' (a selector table)")
        vertices = _select(mesh, "vertices", entry["vertices"], where)
        disp = entry.get("displacement")
        g = None if disp is None else compile_vector(disp, d, f"{where} displacement")
        components = entry.get("components")
        if components is not None and not isinstance(components, list):
            raise SceneError(f"{where}: components must be a list of axes, e.g. [0]")
        with _context(where):
            sim.add_dirichlet(vertices, g, components, body=name, name=entry.get("name"))
    for i, entry in enumerate(_table(item, "traction", source, array=True), start=1):
        where = label("traction", i)
        _unknown(entry, SCENE_KEYS["traction"], where)
        for key in ("facets", "traction"):
            if key not in entry:
                raise SceneError(f"{where}: missing key {key!r}")
        facets = _select(mesh, "facets", entry["facets"], where)
        with _context(where):
            sim.add_traction(facets, _field(entry["traction"], d, f"{where} traction"), body=name)
    for i, entry in enumerate(_table(item, "body_force", source, array=True), start=1):
        where = label("body_force", i)
        _unknown(entry, SCENE_KEYS["body_force"], where)
        if "force_density" not in entry:
            raise SceneError(f"{where}: missing key 'force_density'")
        with _context(where):
            sim.add_body_force(
                _field(entry["force_density"], d, f"{where} force_density"), body=name
            )
    for i, entry in enumerate(_table(item, "nodal_forces", source, array=True), start=1):
        where = label("nodal_forces", i)
        _unknown(entry, SCENE_KEYS["nodal_forces"], where)
        for key in ("vertices", "force"):
            if key not in entry:
                raise SceneError(f"{where}: missing key {key!r}")
        vertices = _select(mesh, "vertices", entry["vertices"], where)
        force = of_time(entry["force"], d, f"{where} force", "a nodal force")
        with _context(where):
            sim.add_nodal_forces(vertices, force, body=name)
    initial = _table(item, "initial", source)
    _unknown(initial, SCENE_KEYS["initial"], label("initial"))
    if "velocity" in initial:
        v = compile_vector(initial["velocity"], d, f"{label('initial')} velocity")
        with _context(label("initial")):
            sim.set_velocity(v(mesh.points, sim.time), body=name)


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


def _material(data: dict, source: str, where: str | None = None):
    """[material]: make_material(model, **parameters); shared by mesh and frame scenes, and by
    the inline ``material = {...}`` tables of coupled scenes (``where`` names those)."""
    from tissuesim.materials import make_material

    where = where or f"{source} [material]"
    material_table = dict(_table(data, "material", source))
    if "model" not in material_table:
        raise SceneError(f"{where}: missing key 'model' (e.g. 'course_neo_hookean')")
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


MESH_GENERATORS = {
    "rectangle": ("lower", "upper", "divisions", "pattern"),
    "box": ("lower", "upper", "divisions", "grading", "pattern"),
    "ellipsoid": ("center", "radii", "divisions"),
}


def _mesh(table: dict, base_dir: Path, where: str):
    """A generated mesh (rectangle, box, ellipsoid) or a file (relative to the scene)."""
    from tissuesim.mesh import box, ellipsoid, read_mesh, rectangle

    if not isinstance(table, dict):
        raise SceneError(f"{where}: must be a table, e.g. mesh = {{ generator = 'box', ... }}")
    _unknown(table, MESH_KEYS, where)
    if "file" in table:
        extra = set(table) - {"file", "merge_coincident"}
        if extra:
            raise SceneError(f"{where}: 'file' cannot be combined with {sorted(extra)}")
        if not isinstance(table["file"], str):
            raise SceneError(f"{where}: file must be a path (a string), not {short(table['file'])}")
        path = Path(table["file"])
        merge = table.get("merge_coincident", False)
        if not isinstance(merge, bool):
            raise SceneError(f"{where}: merge_coincident must be true or false, not {short(merge)}")
        return read_mesh(path if path.is_absolute() else base_dir / path, merge_coincident=merge)
    if "merge_coincident" in table:
        raise SceneError(
            f"{where}: merge_coincident applies to mesh files; generators never "
            "make coincident vertices"
        )
    generator = table.get("generator")
    if not isinstance(generator, str) or generator not in MESH_GENERATORS:
        close = difflib.get_close_matches(str(generator), list(MESH_GENERATORS), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise SceneError(
            f"{where}: give either file = 'mesh.msh' or generator = 'rectangle' | 'box' | "
            f"'ellipsoid' (got generator = {generator!r}){hint}"
        )
    kwargs = {k: v for k, v in table.items() if k != "generator"}
    for key in kwargs:
        if key not in MESH_GENERATORS[generator]:
            raise SceneError(
                f"{where}: {key!r} is not an argument of generator {generator!r}; it takes "
                f"{', '.join(MESH_GENERATORS[generator])}"
            )
    generators = {"rectangle": rectangle, "box": box, "ellipsoid": ellipsoid}
    return generators[generator](**kwargs)


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


def _select(mesh, kind: str, selector, where: str, key: str | None = None) -> np.ndarray:
    from tissuesim.mesh import select

    if not isinstance(selector, dict) or len(selector) != 1:
        raise SceneError(
            f"{where}: {kind} must be a table with one selector out of "
            f"{sorted(SELECTORS[kind])}, e.g. {{ on_plane = {{ axis = 0, value = 0.0 }} }}"
        )
    ((how, args),) = selector.items()
    _unknown([how], SELECTORS[kind], f"{where} {kind}")
    prefix = "vertices" if kind == "vertices" else "facets"
    key = key or kind
    if how == "where":  # vertices (facets: all of whose vertices) where a condition holds
        inside = condition(args, f"{where} {key} where")(mesh.points)
        if kind == "vertices":
            ids = np.flatnonzero(inside)
        else:
            facets = select.all_boundary_facets(mesh)
            ids = facets[inside[facets].all(axis=1)]
        if len(ids) == 0:
            lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
            what = "vertex" if kind == "vertices" else "boundary facet"
            box = " x ".join(f"[{a:.6g}, {b:.6g}]" for a, b in zip(lo, hi, strict=True))
            raise SceneError(
                f"{where} {key}: where = {args!r} selects no {what}; its rest vertices span {box}"
            )
        return ids
    with _context(f"{where} {key} {how}"):
        if how == "tagged":
            return getattr(select, f"{prefix}_tagged")(mesh, args)
        if how == "boundary":
            if args is not True:
                raise SceneError(f"{where}: write {key} = {{ boundary = true }}")
            fn = select.boundary_vertices if kind == "vertices" else select.all_boundary_facets
            return fn(mesh)
        if not isinstance(args, dict):
            raise SceneError(f"{where}: {how} takes a table of arguments")
        fn = getattr(select, f"{prefix}_{how}")
        _unknown(args, list(inspect.signature(fn).parameters)[1:], f"{where} {key} {how}")
        return fn(mesh, **args)
