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

A scene with a ``[frames]`` table is a meshless frame-based body instead (FrameSimulation): its
tables are read by ``tissuesim.scene.frames``, which shares [material], [simulation], [newton],
[gravity] and [run] with this module.

A scene with ``[[organs]]`` tables is a coupled scene instead (CoupledSimulation: organs joined
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
from tissuesim.scene.expressions import compile_vector

__all__ = ["Scene", "load_scene", "build_scene", "SCENE_KEYS"]

MESH_KEYS = {
    "generator": "rectangle or box",
    "file": "path of a mesh file (relative to the scene file)",
    "lower": "generator: lower corner",
    "upper": "generator: upper corner",
    "divisions": "generator: cells per axis",
    "pattern": "rectangle: triangle pattern",
}
SIMULATION_KEYS = (
    "density",
    "integrator",
    "time_step",
    "mass",
    "max_step_halvings",
    "start_time",
    "backend",
)
RUN_KEYS = ("steps", "every", "render")
SELECTORS = {
    "vertices": {"on_plane", "in_box", "tagged", "boundary"},
    "facets": {"on_plane", "in_box", "tagged", "boundary"},
}
SCENE_KEYS = {
    "mesh": set(MESH_KEYS),
    "material": None,  # checked by make_material
    "simulation": set(SIMULATION_KEYS),
    "newton": None,  # checked against NewtonOptions
    "dirichlet": {"vertices", "displacement", "components"},
    "traction": {"facets", "traction"},
    "gravity": {"acceleration"},
    "body_force": {"force_density"},
    "initial": {"velocity"},
    "run": set(RUN_KEYS),
}
# Tables of frame scenes ([frames], tissuesim.scene.frames) that mean nothing for a [mesh] body.
FRAME_ONLY_KEYS = ("region", "fixed_frames", "prescribed_frames", "springs", "point_forces")
# Tables of coupled scenes ([[organs]], tissuesim.scene.coupled) that mean nothing for one body.
COUPLED_ONLY_KEYS = ("graspers", "tissue", "cuts", "tearing")


@dataclass
class Scene:
    """A scene ready to run: the Simulation (or FrameSimulation, or CoupledSimulation) and the
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
    except (TissueSimError, ValueError, TypeError) as exc:
        raise SceneError(f"{where}: {exc}") from exc


def _table(data: dict, key: str, where: str, array: bool = False):
    value = data.get(key, [] if array else {})
    if array:
        if isinstance(value, dict):
            raise SceneError(f"{where}: [{key}] must be an array of tables: write [[{key}]]")
        return value
    if not isinstance(value, dict):
        raise SceneError(f"{where}: {key} must be a table ([{key}])")
    return value


def load_scene(path: str | Path) -> Scene:
    """Read a TOML scene file and build its Simulation."""
    path = Path(path)
    if not path.is_file():
        raise SceneError(f"scene file {str(path)!r} does not exist")
    try:
        data = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
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
    except (ValueError, TypeError) as exc:
        raise SceneError(f"{source}: {exc}") from exc


def _build(data: dict, base_dir: Path, source: str, name: str) -> Scene:
    from tissuesim.simulation import Simulation

    if "organs" in data:
        from tissuesim.scene.coupled import build_coupled_scene

        return build_coupled_scene(data, base_dir, source, name)
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
    # "frames" and "organs" are valid too (handled above): a misspelt [frame] or [[organ]]
    # then suggests them
    _unknown(data, [*SCENE_KEYS, "frames", "organs"], f"{source}: top level")
    with _context(f"{source} [mesh]"):
        mesh = _mesh(_table(data, "mesh", source), base_dir, f"{source} [mesh]")
    d = mesh.dim

    material = _material(data, source)
    newton = _newton(data, source)
    sim_table = _table(data, "simulation", source)
    _unknown(sim_table, SIMULATION_KEYS, f"{source} [simulation]")
    with _context(f"{source} [simulation]"):
        sim = Simulation(mesh, material, newton=newton, **sim_table)

    for i, item in enumerate(_table(data, "dirichlet", source, array=True)):
        where = f"{source} [[dirichlet]] #{i + 1}"
        _unknown(item, SCENE_KEYS["dirichlet"], where)
        if "vertices" not in item:
            raise SceneError(f"{where}: missing key 'vertices' (a selector table)")
        vertices = _select(mesh, "vertices", item["vertices"], where)
        disp = item.get("displacement")
        g = None if disp is None else compile_vector(disp, d, f"{where} displacement")
        components = item.get("components")
        if components is not None and not isinstance(components, list):
            raise SceneError(f"{where}: components must be a list of axes, e.g. [0]")
        with _context(where):
            sim.add_dirichlet(vertices, g, components)
    for i, item in enumerate(_table(data, "traction", source, array=True)):
        where = f"{source} [[traction]] #{i + 1}"
        _unknown(item, SCENE_KEYS["traction"], where)
        for key in ("facets", "traction"):
            if key not in item:
                raise SceneError(f"{where}: missing key {key!r}")
        facets = _select(mesh, "facets", item["facets"], where)
        with _context(where):
            sim.add_traction(facets, _field(item["traction"], d, f"{where} traction"))
    gravity = _table(data, "gravity", source)
    if gravity:
        _unknown(gravity, SCENE_KEYS["gravity"], f"{source} [gravity]")
        with _context(f"{source} [gravity]"):
            sim.add_gravity(gravity["acceleration"])
    for i, item in enumerate(_table(data, "body_force", source, array=True)):
        where = f"{source} [[body_force]] #{i + 1}"
        _unknown(item, SCENE_KEYS["body_force"], where)
        if "force_density" not in item:
            raise SceneError(f"{where}: missing key 'force_density'")
        with _context(where):
            sim.add_body_force(_field(item["force_density"], d, f"{where} force_density"))
    initial = _table(data, "initial", source)
    _unknown(initial, SCENE_KEYS["initial"], f"{source} [initial]")
    if "velocity" in initial:
        v = compile_vector(initial["velocity"], d, f"{source} [initial] velocity")
        sim.set_velocity(v(mesh.points, sim.time))
    return Scene(sim, name, source, _run_table(data, source))


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


def _mesh(table: dict, base_dir: Path, where: str):
    from tissuesim.mesh import box, read_mesh, rectangle

    _unknown(table, MESH_KEYS, where)
    if "file" in table:
        extra = set(table) - {"file"}
        if extra:
            raise SceneError(f"{where}: 'file' cannot be combined with {sorted(extra)}")
        path = Path(table["file"])
        return read_mesh(path if path.is_absolute() else base_dir / path)
    generator = table.get("generator")
    generators = {"rectangle": rectangle, "box": box}
    if generator not in generators:
        raise SceneError(
            f"{where}: give either file = 'mesh.msh' or generator = 'rectangle' | 'box' "
            f"(got generator = {generator!r})"
        )
    kwargs = {k: v for k, v in table.items() if k != "generator"}
    return generators[generator](**kwargs)


def _select(mesh, kind: str, selector, where: str) -> np.ndarray:
    from tissuesim.mesh import select

    if not isinstance(selector, dict) or len(selector) != 1:
        raise SceneError(
            f"{where}: {kind} must be a table with one selector out of "
            f"{sorted(SELECTORS[kind])}, e.g. {{ on_plane = {{ axis = 0, value = 0.0 }} }}"
        )
    ((how, args),) = selector.items()
    _unknown([how], SELECTORS[kind], f"{where} {kind}")
    prefix = "vertices" if kind == "vertices" else "facets"
    with _context(f"{where} {kind} {how}"):
        if how == "tagged":
            return getattr(select, f"{prefix}_tagged")(mesh, args)
        if how == "boundary":
            if args is not True:
                raise SceneError(f"{where}: write {kind} = {{ boundary = true }}")
            fn = select.boundary_vertices if kind == "vertices" else select.all_boundary_facets
            return fn(mesh)
        if not isinstance(args, dict):
            raise SceneError(f"{where}: {how} takes a table of arguments")
        fn = getattr(select, f"{prefix}_{how}")
        _unknown(args, list(inspect.signature(fn).parameters)[1:], f"{where} {kind} {how}")
        return fn(mesh, **args)
