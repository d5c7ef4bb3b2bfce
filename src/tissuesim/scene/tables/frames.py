"""Frame scenes: a ``[frames]`` table makes a scene a meshless frame-based body.

``tissuesim.scene.loader`` sends every scene with a ``[frames]`` table here. The tables map onto
the Python API of ``tissuesim.frames`` the way [mesh] scenes map onto Simulation's:

    [frames]               frame origins from grid_frames(lower, upper, counts) (grid = {...}),
                           farthest_point_frames(integration points, count) (count = N) or
                           positions = [[x, y, z], ...]; type, shape, radius, radius_factor and
                           min_frames are add_frame_body's frame_type, shape, radius, ...
    [region]               the integration points: exactly one of box = {lower, upper},
                           ellipsoid = {center, semi_axes}, surface = "closed.stl",
                           mesh = "tets.msh" (files relative to the scene file), with spacing
                           (and subsamples for ellipsoid / surface); display = true (default)
                           embeds the body's surface, which output files and pictures show
    [material] [simulation] [newton] [gravity] [run]      as for [mesh] scenes
    [[fixed_frames]]       fix_frames(frames)
    [[prescribed_frames]]  prescribe_frames(frames, motion): displacement and rotation vector
                           (rad), expressions of t and of the frame's rest position x, y, z
    [[springs]]            add_spring(points, stiffness, target): target expressions of t and
                           of each point's rest position x, y, z (default: rest positions)
    [[point_forces]]       add_point_forces(points, force): force (N per point), numbers or
                           expressions of t, x, y, z
    [initial]              set_velocity(velocity, angular)

Frame selectors pick frames by their rest origins: ``{ on_plane = { axis, value } }``,
``{ in_box = { lower, upper } }`` (optional tolerance, default 1e-6 times the body's
bounding-box diagonal, as ``tissuesim.mesh.select`` does for mesh vertices),
``{ where = "z < 0.1" }`` (a condition on the rest origins) or ``{ indices = [0, 1] }``.
Points (springs, point forces) are a list ``[[x, y, z], ...]`` or
display-surface vertices picked by ``{ surface_on_plane = {...} }`` or
``{ surface_in_box = {...} }`` (same arguments).
Errors are SceneErrors naming the file, the table (``[[fixed_frames]] #2``) and the key.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import SceneError
from tissuesim.scene.common import (
    RUN_KEYS,
    SIMULATION_KEYS,
    Scene,
    _context,
    _is_number,
    _material,
    _newton,
    _required,
    _run_table,
    _table,
    _unknown,
    _vector3,
)
from tissuesim.scene.expressions import compile_vector
from tissuesim.scene.tables.contact import CONTACT_KEYS, OBSTACLE_KEYS
from tissuesim.scene.tables.frame_regions import (
    REGION_KEYS,
    _frame_positions,
    _points,
    _region,
    _scale,
    _select_frames,
)
from tissuesim.validate import short

__all__ = ["build_frame_scene", "FRAME_SCENE_KEYS"]

#: element order and formulation are FEM options: a frame body has neither
FRAME_SIMULATION_KEYS = tuple(
    k
    for k in SIMULATION_KEYS
    if k not in ("order", "formulation", "phases", "newmark", "generalized_alpha")
)

FRAMES_KEYS = {
    "type": "rigid (6 DOF per frame) or affine (12 DOF)",
    "shape": "wendland (compact support) or shepard (global)",
    "grid": "{ lower, upper, counts }: frames on a regular grid",
    "count": "N frames by farthest-point sampling of the integration points",
    "positions": "[[x, y, z], ...]: explicit frame origins",
    "radius": "support radius of every frame (default: automatic)",
    "radius_factor": "scales the automatic radii",
    "min_frames": "frames each integration point must see",
}
FRAME_SCENE_KEYS: dict[str, Any] = {
    "frames": set(FRAMES_KEYS),
    "region": set(REGION_KEYS),
    "material": None,  # checked by make_material
    "simulation": set(FRAME_SIMULATION_KEYS),
    "newton": None,  # checked against NewtonOptions
    "gravity": {"acceleration"},
    "fixed_frames": {"frames", "name"},
    "prescribed_frames": {"frames", "displacement", "rotation", "name"},
    "springs": {"points", "stiffness", "target", "name"},
    "point_forces": {"points", "force"},
    "initial": {"velocity", "angular"},
    "contact": set(CONTACT_KEYS),
    "obstacles": set(OBSTACLE_KEYS),
    "run": set(RUN_KEYS),
}
#: the tables of one frame body (top level in a one-body scene, inside each [[bodies]] entry)
FRAME_BODY_KEYS = ("frames", "region", "material", "fixed_frames", "prescribed_frames")
FRAME_BODY_KEYS += ("springs", "point_forces", "initial")
# Tables of [mesh] scenes, and what a frame scene writes instead.
MESH_ONLY = {
    "dirichlet": "clamp or move frames with [[fixed_frames]] / [[prescribed_frames]]",
    "traction": "load display-surface points with [[point_forces]]",
    "body_force": "use [gravity] or [[point_forces]]",
}
FRAME_INTEGRATORS = ("backward_euler", "quasistatic", "explicit", "symplectic_euler")


def build_frame_scene(data: dict, base_dir: Path, source: str, name: str) -> Scene:
    """Build a Scene whose simulation holds one frame body ("body") from parsed TOML
    ``data`` (the short form: the body's tables at the top level)."""
    from tissuesim.scene.common import _short_label
    from tissuesim.simulation import Simulation

    if "mesh" in data:
        raise SceneError(
            f"{source}: the scene has both [mesh] (a finite-element body) and [frames] (a "
            f"meshless frame body); choose one, or list both in [[bodies]]. To sample a frame "
            f"body from a mesh file, drop [mesh] and write [region] mesh = 'file.msh'"
        )
    for key, instead in MESH_ONLY.items():
        if key in data:
            raise SceneError(
                f"{source}: [[{key}]] is for [mesh] scenes; in a [frames] scene {instead}"
            )
    _unknown(data, FRAME_SCENE_KEYS, f"{source}: top level")
    newton = _newton(data, source)
    sim_where = f"{source} [simulation]"
    sim_table = dict(_table(data, "simulation", source))
    _unknown(sim_table, FRAME_SIMULATION_KEYS, sim_where)
    _check_simulation(sim_table, sim_where)
    body = {k: sim_table.pop(k) for k in ("density", "mass") if k in sim_table}
    with _context(sim_where):
        sim = Simulation(newton=newton, **sim_table)
    tables = {k: data[k] for k in FRAME_BODY_KEYS if k in data}
    add_frame_body_tables(
        sim, "body", {**tables, **body}, base_dir, source, _short_label(source), sim_where
    )
    gravity = _table(data, "gravity", source)
    if gravity:
        where = f"{source} [gravity]"
        _unknown(gravity, FRAME_SCENE_KEYS["gravity"], where)
        with _context(where):
            sim.add_gravity(_vector3(gravity["acceleration"], f"{where} acceleration"))
    from tissuesim.scene.tables.contact import add_contact_tables

    add_contact_tables(sim, data, base_dir, source)
    return Scene(sim, name, source, _run_table(data, source))


def add_frame_body_tables(
    sim, name: str, item: dict, base_dir: Path, source: str, label, options_where=None
) -> None:
    """A frame body from its tables: frames and region (required), material, density, mass,
    fixed_frames, prescribed_frames, springs, point_forces (arrays of tables), initial."""
    frames_table = _table(item, "frames", source)
    _unknown(frames_table, FRAMES_KEYS, label("frames"))
    if "region" not in item:
        raise SceneError(
            f"{label('frames')}: a frame body needs a [region] table saying where the body is, "
            f"e.g. [region] box = {{ lower = [0, 0, 0], upper = [1, 1, 1] }}, spacing = 0.1 "
            f"(or ellipsoid, surface, mesh)"
        )
    region_where = label("region")
    samples, surface = _region(_table(item, "region", source), base_dir, region_where)
    positions = _frame_positions(frames_table, samples, label("frames"))
    material = _material(item, source, label("material"))
    body_options = {k: item[k] for k in ("density", "mass") if k in item}
    if "mass" in body_options and body_options["mass"] not in ("full", "lumped"):
        raise SceneError(
            f"{options_where or label()}: mass must be 'full' or 'lumped' for frame bodies, "
            f"not {body_options['mass']!r}"
        )
    options = {
        ("frame_type" if key == "type" else key): frames_table[key]
        for key in ("type", "shape", "radius", "radius_factor", "min_frames")
        if key in frames_table
    }
    density = body_options.get("density", 1.0)
    if not (_is_number(density) and np.isfinite(density) and density > 0):
        raise SceneError(
            f"{options_where or label()}: density must be a number > 0 (kg/m^3), "
            f"not {short(density)}"
        )
    with _context(label("frames")):
        sim.add_frame_body(name, positions, samples, material, **body_options, **options)
    body = sim.bodies[name]
    if surface is not None:
        with _context(f"{region_where} display"):
            body.embed_surface(surface)
    scale = _scale(samples.points, positions, surface)
    for i, entry in enumerate(_table(item, "fixed_frames", source, array=True), start=1):
        where = label("fixed_frames", i)
        _unknown(entry, FRAME_SCENE_KEYS["fixed_frames"], where)
        frames = _select_frames(body, _required(entry, "frames", where), scale, where)
        with _context(where):
            body.fix_frames(frames, entry.get("name"))
    for i, entry in enumerate(_table(item, "prescribed_frames", source, array=True), start=1):
        where = label("prescribed_frames", i)
        _unknown(entry, FRAME_SCENE_KEYS["prescribed_frames"], where)
        frames = _select_frames(body, _required(entry, "frames", where), scale, where)
        if "displacement" not in entry and "rotation" not in entry:
            raise SceneError(
                f"{where}: give displacement = [...] and/or rotation = [...] (expressions of "
                f"t); to hold frames at rest use [[fixed_frames]]"
            )
        with _context(where):
            body.prescribe_frames(
                frames, _motion(entry, body.rest_frames[frames], where), name=entry.get("name")
            )
    for i, entry in enumerate(_table(item, "springs", source, array=True), start=1):
        where = label("springs", i)
        _unknown(entry, FRAME_SCENE_KEYS["springs"], where)
        points = _points(body, _required(entry, "points", where), scale, where)
        stiffness = _stiffness(_required(entry, "stiffness", where), len(points), where)
        target = None
        if "target" in entry:
            f = compile_vector(entry["target"], 3, f"{where} target")
            target = _of_time(f, points)
        with _context(where):
            body.add_spring(points, stiffness, target, name=entry.get("name"))
    for i, entry in enumerate(_table(item, "point_forces", source, array=True), start=1):
        where = label("point_forces", i)
        _unknown(entry, FRAME_SCENE_KEYS["point_forces"], where)
        points = _points(body, _required(entry, "points", where), scale, where)
        force = _required(entry, "force", where)
        if isinstance(force, list) and all(_is_number(v) for v in force):
            force = _vector3(force, f"{where} force")
        else:
            force = _of_time(compile_vector(force, 3, f"{where} force"), points)
        with _context(where):
            body.add_point_forces(points, force)
    initial = _table(item, "initial", source)
    where = label("initial")
    _unknown(initial, FRAME_SCENE_KEYS["initial"], where)
    if initial:
        linear = _vector3(initial.get("velocity", [0, 0, 0]), f"{where} velocity")
        angular = _vector3(initial.get("angular", [0, 0, 0]), f"{where} angular")
        with _context(where):
            body.set_velocity(linear, angular)


# -- values -------------------------------------------------------------------------------------


def _of_time(f, points: np.ndarray):
    """t -> f(points, t): an expression vector evaluated at fixed rest points."""
    points = np.array(points, dtype=float)

    def at(t: float) -> np.ndarray:
        return f(points, t)

    return at


def _motion(item: dict, rest: np.ndarray, where: str):
    """motion(t) -> (displacement (k, 3), rotation vector (k, 3)) of prescribed frames."""
    zero = [0.0, 0.0, 0.0]
    u = compile_vector(item.get("displacement", zero), 3, f"{where} displacement")
    r = compile_vector(item.get("rotation", zero), 3, f"{where} rotation")
    rest = np.array(rest, dtype=float)

    def motion(t: float) -> tuple[np.ndarray, np.ndarray]:
        return u(rest, t), r(rest, t)

    return motion


def _stiffness(value, k: int, where: str) -> float | np.ndarray:
    if _is_number(value):
        values = np.array([float(value)])
    elif isinstance(value, list) and len(value) == k and all(_is_number(v) for v in value):
        values = np.asarray(value, dtype=float)
    else:
        raise SceneError(
            f"{where}: stiffness must be a number (N/m per point) or a list of {k} numbers, "
            f"one per point, got {short(value)}"
        )
    if not np.all(np.isfinite(values) & (values > 0)):
        raise SceneError(f"{where}: stiffness must be finite and > 0 (N/m), got {short(value)}")
    return float(values[0]) if _is_number(value) else values


def _check_simulation(table: dict, where: str) -> None:
    """[simulation] values a frame body refuses, caught here so the error names this table
    (the Simulation checks them too, but among the [frames] options); the shared validators
    of ``validate.py``, as in the API."""
    from tissuesim import validate
    from tissuesim.backend import resolve_backend
    from tissuesim.time.attempts.retry import validate_stepping

    with _context(where):
        validate.choice(table.get("integrator", "backward_euler"), "integrator", FRAME_INTEGRATORS)
        validate_stepping(table.get("time_step", 0.01), table.get("max_step_halvings", 6))
        validate.real(table.get("start_time", 0.0), "start_time", unit="s")
        validate.choice(table.get("mass", "full"), "mass", ("full", "lumped"))
        validate.real(table.get("density", 1.0), "density", low=0.0, low_open=True, unit="kg/m^3")
        resolve_backend(table.get("backend", "auto"))


# -- region and frames ---------------------------------------------------------------------------


# -- selectors ------------------------------------------------------------------------------------
