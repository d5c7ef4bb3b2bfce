"""TOML scene files -> the same objects the Python API builds.

Every key is the name of an argument of the Python API (see docs/reference/scene-keys.md):

    [mesh]          rectangle(...) / box(...) via ``generator``, read_mesh via ``file``, or
                    mesh_surface via ``surface`` (a closed STL/OBJ/PLY, tetrahedralised)
    [material]      make_material(model, **parameters)
    [simulation]    Simulation(...)
    [newton]        NewtonOptions(...)
    [[dirichlet]]   Simulation.add_dirichlet(vertices, displacement, components)
    [[traction]]    Simulation.add_traction(facets, traction)
    [gravity]       Simulation.add_gravity(acceleration)
    [[body_force]]  Simulation.add_body_force(force_density)
    [initial]       Simulation.set_velocity(velocity)
    [[graspers]]    Simulation.grasp(vertices, displacement, stiffness, name, release)
    [[visual_surfaces]] Simulation.add_visual_surface(file, body, name, max_outside)
    [[logfiles]]    Simulation.add_logfile(kind, data, body, items, ids, file)
    [run]           Simulation.run(steps, every, render)

Vertex and facet sets are selector tables, e.g. ``{ on_plane = { axis = 0, value = -1.0 } }``,
naming a function of ``tissuesim.mesh.select``. Vectors may hold numbers or expressions in
x, y, z, t (``tissuesim.scene.expressions``). Unknown keys are errors that suggest the nearest
valid key; every error names the file and the table.

A scene with a ``[frames]`` table is a meshless frame-based body instead: its
tables are read by ``tissuesim.scene.tables.frames``, which shares [material], [simulation],
[newton], [gravity] and [run] with this module.

A scene with ``[[bodies]]`` (or ``[[organs]]``) tables has many bodies (organs joined
by connective tissue, with [tissue], [[cuts]] and [tearing]): its tables are read
by ``tissuesim.scene.tables.coupled``, which shares [simulation], [newton], [gravity], [run], the
material tables and the vertex selectors with this module. ``[[organs]]`` decides even when
other tables are present (a [mesh] or [frames] table beside it is then an error).
"""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

from tissuesim.errors import InputError, SceneError, TissueSimError
from tissuesim.scene.common import (  # re-exported: the readers' shared names
    RUN_KEYS,
    SIMULATION_KEYS,
    Scene,
    _context,
    _newton,
    _run_table,
    _short_label,
    _table,
    _unknown,
    wrong_form,
)
from tissuesim.scene.tables.contact import CONTACT_KEYS, OBSTACLE_KEYS
from tissuesim.scene.tables.coupled import GRASPER_KEYS
from tissuesim.scene.tables.fem_body import (
    FEM_BODY_KEYS,
    FEM_BODY_OPTIONS,
    FEM_TABLE_KEYS,
    MESH_KEYS,
    add_fem_body,
)
from tissuesim.scene.tables.logfiles import LOGFILE_KEYS, add_logfiles
from tissuesim.scene.tables.penalty_contact import PENALTY_KEYS, add_penalty_contacts
from tissuesim.scene.tables.rigid_wall import RIGID_WALL_KEYS, add_rigid_walls
from tissuesim.scene.tables.visual import VISUAL_KEYS, add_visual_surfaces

__all__ = ["Scene", "load_scene", "build_scene", "SCENE_KEYS"]

SCENE_KEYS = {
    "mesh": set(MESH_KEYS),
    "material": None,  # checked by make_material
    "simulation": {*SIMULATION_KEYS, "damping"},
    "newton": None,  # checked against NewtonOptions
    **FEM_TABLE_KEYS,
    "gravity": {"acceleration"},
    "run": set(RUN_KEYS),
    "contact": set(CONTACT_KEYS),
    "obstacles": set(OBSTACLE_KEYS),
    "graspers": set(GRASPER_KEYS),
    "visual_surfaces": set(VISUAL_KEYS),
    "logfiles": set(LOGFILE_KEYS),
    "penalty_contact": set(PENALTY_KEYS),
    "rigid_wall": set(RIGID_WALL_KEYS),
    "identify": None,  # read by ``tissuesim identify`` (identification/scene.py); a run ignores it
}
# Tables of frame scenes ([frames], scene/tables/frames.py) that mean nothing for a [mesh] body.
FRAME_ONLY_KEYS = ("region", "fixed_frames", "prescribed_frames", "springs", "point_forces")
# Tables of coupled scenes ([[organs]], scene/tables/coupled.py) that mean nothing for one body.
# [[graspers]] is not one of them: a grasper is the most basic interaction, on any FEM body.
COUPLED_ONLY_KEYS = ("tissue", "cuts", "tearing")


def load_scene(path: str | Path) -> Scene:
    """Read a TOML scene file and build its Simulation (a FEBio model, ``.feb``, is read as
    its converted scene: ``load_febio``)."""
    from tissuesim.validate import regular_file

    if Path(path).suffix.lower() == ".feb":
        return load_febio(path)

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


def load_febio(path: str | Path, febio_solver: bool = False) -> Scene:
    """The Scene of a FEBio model, built as its converted scene is (the scene and mesh files
    written to a temporary directory and loaded), so both run identically. The model's
    notes (accepted settings tissuesim does not use) are printed as warnings.
    ``febio_solver``: solved by FEBio's quasi-Newton with its <solver> settings
    (``convert_febio``'s, solve/quasin.py)."""
    import tempfile
    import warnings

    from tissuesim.febio.convert import convert_febio
    from tissuesim.febio.reader import read_feb

    path = Path(path)
    with tempfile.TemporaryDirectory(prefix="tissuesim-febio-") as tmp:
        scene_path = Path(tmp) / f"{path.stem}.toml"
        convert_febio(path, scene_path, febio_solver=febio_solver)
        model = read_feb(path)
        notes = list(model.notes)
        if febio_solver and model.febio_solver_note is not None:
            del notes[model.febio_solver_note]  # the settings are used
        for note in notes:
            warnings.warn(f"not used: {note}", UserWarning, stacklevel=2)
        try:
            scene = load_scene(scene_path)
        except InputError as exc:  # name the model, never the temporary scene (deleted now)
            if tmp not in str(exc):
                raise
            text = str(exc).replace(str(scene_path), f"{path} (its converted scene)")
            raise SceneError(text.replace(f"{tmp}{os.sep}", "")) from None
    scene.source = str(path)
    return scene


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
        from tissuesim.scene.tables.coupled import build_bodies_scene

        return build_bodies_scene(data, base_dir, source, name)
    if "frames" in data:
        from tissuesim.scene.tables.frames import build_frame_scene

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
    _unknown(sim_table, SCENE_KEYS["simulation"], f"{source} [simulation]")
    body = {k: sim_table.pop(k) for k in FEM_BODY_OPTIONS if k in sim_table}
    damping = sim_table.pop("damping", None)
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
    if damping is not None:  # Rayleigh damping: { mass = alpha (1/s), stiffness = beta (s) }
        where = f"{source} [simulation] damping"
        if not isinstance(damping, dict):
            raise SceneError(f"{where} must be a table {{ mass = ..., stiffness = ... }}")
        _unknown(damping, ("mass", "stiffness"), where)
        with _context(where):
            sim.set_damping(**damping)
    gravity = _table(data, "gravity", source)
    if gravity:
        _unknown(gravity, SCENE_KEYS["gravity"], f"{source} [gravity]")
        with _context(f"{source} [gravity]"):
            sim.add_gravity(gravity["acceleration"])
    from tissuesim.scene.tables.coupled import _grasper

    for i, item in enumerate(_table(data, "graspers", source, array=True), start=1):
        if "body" not in item and "organ" not in item:  # the scene's one body, "body"
            item = {**item, "body": "body"}
        _grasper(sim, item, f"{source} [[graspers]] #{i}")
    from tissuesim.scene.tables.contact import add_contact_tables

    add_contact_tables(sim, data, base_dir, source)
    add_penalty_contacts(sim, data, source)
    add_rigid_walls(sim, data, source)
    add_visual_surfaces(sim, data, base_dir, source, "body")
    add_logfiles(sim, data, source, "body")
    return Scene(sim, name, source, _run_table(data, source))
