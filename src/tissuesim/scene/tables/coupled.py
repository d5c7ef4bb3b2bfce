"""Coupled scenes: ``[[organs]]`` tables make a scene of several bodies (organs joined by
connective tissue, graspers, supports, cuts and tearing).

``tissuesim.scene.loader`` sends every scene with an ``[[organs]]`` table here. Every key is an
argument of the Python API of ``tissuesim.simulation.Simulation``:

    [simulation]   Simulation(integrator, time_step, max_step_halvings, start_time,
                   backend); integrator "backward_euler" (default) or "quasistatic"
    [gravity]      Simulation(gravity=acceleration)
    [newton]       NewtonOptions(...), as for [mesh] scenes
    [[organs]]     add_body(name, mesh, material, density, mass), and fix(name, vertices):
                   mesh = { generator = "ellipsoid", center, radii, divisions }
                        | { generator = "box", lower, upper, divisions }
                        | { file = "organ.vtu" }  (read_mesh, relative to the scene file)
                   material = { model = "neo_hookean", youngs_modulus, poisson_ratio }
                   (make_material, as the [material] table of [mesh] scenes)
                   fix = a vertex selector (optional): the organ's support
    [[graspers]]   grasp(organ, vertices, displacement, stiffness, name): displacement is 3
                   numbers or expressions of t (the grasper moves its vertices rigidly);
                   without stiffness the motion is prescribed, with it (N/m per vertex) the
                   vertices are pulled by springs
    [tissue]       add_tissue(material, thickness, spacing, region, frames, density,
                   frame_type, shape, radius_factor, attach_distance, attachment_stiffness):
                   frames is a count or [[x, y, z], ...]; region = { where = "..." } limits
                   the layer to rest points where the condition holds
    [[cuts]]       add_cut(blade, start, end, kerf, name): blade is a polyline of >= 2 points
                   [["x(t)", "y(t)", "z(t)"], ...], each coordinate a number or an expression
                   of t; with body = "organ" the blade (an edge of 2 points or a triangle) cuts
                   that organ, with its toughness (J/m^2, optional); read in
                   ``scene/tables/cuts.py``
    [tearing]      set_tearing(threshold): the tissue; with body = "organ" and stress (Pa) or
                   stretch, that organ tears (``scene/tables/cuts.py``)
    [[rigid_bodies]] add_rigid_body(name, bodies, vertices, center, fixed, prescribed, force,
                   moment): bodies moving rigidly, and vertices of others glued to them
                   (``scene/tables/rigid.py``)
    [[visual_surfaces]] add_visual_surface(file, body, name, max_outside): a fine surface
                   carried by a FEM body for the output (``scene/tables/visual.py``)
    [run]          run(steps, every, render), as for every scene

Vertex selectors (fix, graspers' vertices) pick vertices of one organ's rest mesh: the
selector tables of [mesh] scenes (``{ on_plane = { axis = 2, value = 0.0 } }``,
``{ in_box = { lower, upper } }``, ``{ tagged = "zmin" }``, ``{ boundary = true }``) or
``{ where = "z < -0.032" }``, a condition on the rest coordinates x, y, z written with the safe
expressions of ``tissuesim.scene.expressions``: a vertex is selected where it is true
(non-zero); combine conditions with ``*`` (and), e.g. ``"(z > 0.03) * (abs(x) < 0.01)"``.

Errors are SceneErrors naming the file, the table (``organs[2].mesh``: the second
``[[organs]]`` table, counting from 1 as the other scene errors do; ``[tissue] frames``) and
the key, and saying how to fix it.
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import SceneError
from tissuesim.scene.common import (
    RUN_KEYS,
    SELECTORS,
    Scene,
    _context,
    _material,
    _newton,
    _number,
    _required,
    _run_table,
    _table,
    _unknown,
    _vector3,
    of_time,
)
from tissuesim.scene.common import condition as _condition
from tissuesim.scene.tables.contact import CONTACT_KEYS, OBSTACLE_KEYS
from tissuesim.scene.tables.cuts import CUT_KEYS, TEARING_KEYS, add_cut_tables, add_tearing_table
from tissuesim.scene.tables.fem_body import _mesh, _select
from tissuesim.scene.tables.logfiles import LOGFILE_KEYS, add_logfiles
from tissuesim.scene.tables.penalty_contact import PENALTY_KEYS, add_penalty_contacts
from tissuesim.scene.tables.rigid import JOINT_KEYS, RIGID_KEYS, add_rigid_bodies
from tissuesim.scene.tables.rigid_wall import RIGID_WALL_KEYS, add_rigid_walls
from tissuesim.scene.tables.visual import VISUAL_KEYS, add_visual_surfaces
from tissuesim.validate import short

__all__ = ["build_bodies_scene", "COUPLED_SCENE_KEYS"]

COUPLED_SIMULATION_KEYS = (
    "integrator", "time_step", "max_step_halvings", "start_time", "backend", "phases", "newmark",
    "generalized_alpha", "adaptive",
)  # fmt: skip
ORGAN_KEYS = ("name", "mesh", "material", "density", "mass", "order", "formulation", "fix")
GRASPER_KEYS = ("body", "organ", "name", "vertices", "displacement", "stiffness", "release")
ATTACHMENT_KEYS = ("body", "to", "distance", "stiffness", "name")
TISSUE_KEYS = (
    "material",
    "thickness",
    "spacing",
    "region",
    "frames",
    "density",
    "frame_type",
    "shape",
    "radius_factor",
    "attach_distance",
    "attachment_stiffness",
)
COUPLED_SCENE_KEYS: dict[str, Any] = {
    "simulation": set(COUPLED_SIMULATION_KEYS),
    "gravity": {"acceleration"},
    "newton": None,  # checked against NewtonOptions
    "organs": set(ORGAN_KEYS),
    "bodies": None,  # each checked by _body against its kind's keys
    "graspers": set(GRASPER_KEYS),
    "attachments": set(ATTACHMENT_KEYS),
    "tissue": set(TISSUE_KEYS),
    "cuts": set(CUT_KEYS),
    "tearing": set(TEARING_KEYS),
    "run": set(RUN_KEYS),
    "contact": set(CONTACT_KEYS),
    "obstacles": set(OBSTACLE_KEYS),
    "visual_surfaces": set(VISUAL_KEYS),
    "logfiles": set(LOGFILE_KEYS),
    "rigid_bodies": set(RIGID_KEYS),
    "rigid_joints": set(JOINT_KEYS),
    "penalty_contact": set(PENALTY_KEYS),
    "rigid_wall": set(RIGID_WALL_KEYS),
    "identify": None,  # read by ``tissuesim identify`` (identification/scene.py); a run ignores it
}
ARRAYS = (
    "organs", "bodies", "graspers", "attachments", "cuts", "obstacles", "visual_surfaces",
    "logfiles", "rigid_bodies", "rigid_joints", "penalty_contact", "rigid_wall",
)  # fmt: skip
MESH_GENERATORS = {
    "ellipsoid": ("center", "radii", "divisions"),
    "box": ("lower", "upper", "divisions", "element"),
    "shell": ("points", "faces", "thickness", "layers", "reference"),
}
MESH_EXAMPLE = (
    'mesh = { generator = "ellipsoid", center = [0, 0, 0], radii = [0.06, 0.04, 0.02], '
    'divisions = 8 }, { generator = "box", lower = [...], upper = [...], divisions = [4, 4, 2] } '
    'or { file = "organ.vtu" }'
)
MATERIAL_EXAMPLE = (
    'material = { model = "neo_hookean", youngs_modulus = 5000.0, poisson_ratio = 0.45 }'
)
VERTEX_SELECTORS = tuple(sorted(SELECTORS["vertices"]))
# Tables of other scenes, and what a coupled scene writes instead.
ELSEWHERE = {
    "mesh": "each organ has its own mesh = {...} in its [[organs]] table",
    "material": "each organ has its own material = {...} in [[organs]], the tissue in [tissue]",
    "frames": "the tissue's frames are [tissue] frames = N",
    "region": "the tissue fills the space between the organs: [tissue] thickness and spacing",
    "dirichlet": "hold an organ with fix = {...} in its [[organs]] table, move one with "
    "[[graspers]]",
    "fixed_frames": "hold an organ with fix = {...} in its [[organs]] table",
    "prescribed_frames": "move an organ with [[graspers]]",
    "initial": "coupled scenes start at rest",
}
_AXES = "xyz"


def build_bodies_scene(data: dict, base_dir: Path, source: str, name: str) -> Scene:
    """Build a Scene of several bodies ([[bodies]] and/or [[organs]]) and their interactions
    from parsed TOML ``data``."""
    from tissuesim.simulation import Simulation

    for key, instead in ELSEWHERE.items():
        if key in data:
            raise SceneError(
                f"{source}: [{key}] does not belong in a scene of several bodies (one with "
                f"[[bodies]] or [[organs]]); {instead}"
            )
    _unknown(data, COUPLED_SCENE_KEYS, f"{source}: top level")
    for key in ARRAYS:
        _table(data, key, source, array=True)

    newton = _newton(data, source)
    sim_where = f"{source} [simulation]"
    sim_table = _table(data, "simulation", source)
    for key in ("density", "mass", "order", "formulation"):
        if key in sim_table:
            raise SceneError(
                f"{sim_where}: {key} is set per body in a scene of several bodies: write "
                f"{key} = ... in each [[bodies]] / [[organs]] table"
                f"{' and in [tissue]' if key == 'density' else ''}"
            )
    _unknown(sim_table, COUPLED_SIMULATION_KEYS, sim_where)
    gravity = _table(data, "gravity", source)
    _unknown(gravity, COUPLED_SCENE_KEYS["gravity"], f"{source} [gravity]")
    acceleration = None
    if gravity:
        where = f"{source} [gravity]"
        acceleration = _vector3(_required(gravity, "acceleration", where), f"{where} acceleration")
    with _context(sim_where):
        sim = Simulation(newton=newton, gravity=acceleration, **sim_table)

    organs = _table(data, "organs", source, array=True)
    bodies = _table(data, "bodies", source, array=True)
    if not organs and not bodies:
        raise SceneError(f"{source}: [[bodies]] is empty: give at least one body")
    for i, item in enumerate(organs, start=1):
        _organ(sim, item, base_dir, f"{source} organs[{i}]")
    for i, item in enumerate(bodies, start=1):
        _body(sim, item, base_dir, source, i)
    for i, item in enumerate(_table(data, "graspers", source, array=True), start=1):
        _grasper(sim, item, f"{source} graspers[{i}]")
    for i, item in enumerate(_table(data, "attachments", source, array=True), start=1):
        _attachment(sim, item, f"{source} attachments[{i}]")
    from tissuesim.scene.tables.contact import add_contact_tables

    add_rigid_bodies(sim, data, source)
    add_penalty_contacts(sim, data, source)
    add_rigid_walls(sim, data, source)
    add_contact_tables(sim, data, base_dir, source)
    tissue = _table(data, "tissue", source)
    if tissue:
        _tissue(sim, tissue, f"{source} [tissue]")
    add_cut_tables(sim, data, source, bool(tissue))
    add_visual_surfaces(sim, data, base_dir, source)
    add_logfiles(sim, data, source)
    add_tearing_table(sim, data, source, bool(tissue))
    return Scene(sim, name, source, _run_table(data, source))


# -- values -------------------------------------------------------------------------------------


def _of_time(items, where: str, what: str):
    """t -> (3,) from 3 numbers or expressions of t only (``what`` moves rigidly)."""
    return of_time(items, 3, where, what)


def _vertices(mesh, organ: str, selector, where: str, key: str) -> np.ndarray:
    """Vertex ids of ``organ``'s rest mesh picked by a vertex selector (``where`` included)."""
    if not isinstance(selector, dict) or len(selector) != 1:
        raise SceneError(
            f"{where}: {key} must be a table with one selector out of {list(VERTEX_SELECTORS)}, "
            f'e.g. {key} = {{ where = "z < 0.0" }} or {{ on_plane = {{ axis = 2, value = 0.0 }} }}'
        )
    ((how, _),) = selector.items()
    _unknown([how], VERTEX_SELECTORS, f"{where} {key}")
    return _select(mesh, "vertices", selector, where, key)


def _inline_material(item: dict, where: str, mesh=None):
    value = _required(item, "material", where)
    if not isinstance(value, dict):
        raise SceneError(f"{where}: material must be a table, e.g. {MATERIAL_EXAMPLE}")
    return _material(item, "", f"{where} material", mesh)


def _organ(sim, item: dict, base_dir: Path, where: str) -> None:
    """One [[organs]] table: a FEM body with name, mesh, material, density, mass, fix."""
    _unknown(item, ORGAN_KEYS, where)
    name = _required(item, "name", where)
    if not (isinstance(name, str) and name):
        raise SceneError(f"{where}: name must be a non-empty string, e.g. name = 'liver'")
    if "mesh" not in item:
        raise SceneError(f"{where}: missing key 'mesh', e.g. {MESH_EXAMPLE}")
    with _context(f"{where}.mesh"):
        mesh = _mesh(item["mesh"], base_dir, f"{where}.mesh")
    if "material" not in item:
        raise SceneError(f"{where}: missing key 'material', e.g. {MATERIAL_EXAMPLE}")
    material = _inline_material(item, where, mesh)
    options = {}
    if "density" in item:
        options["density"] = _number(item["density"], f"{where} density", "a number > 0 (kg/m^3)")
    if "mass" in item:
        if item["mass"] not in ("consistent", "lumped", "element_rule"):
            raise SceneError(
                f"{where}: mass must be 'consistent', 'lumped' or 'element_rule', not "
                f"{item['mass']!r}"
            )
        options["mass"] = item["mass"]
    for key in ("order", "formulation"):
        if key in item:
            options[key] = item[key]
    with _context(where):
        sim.add_body(name, mesh, material, **options)
    mesh = sim.body(name).mesh  # order = 2 adds midside nodes
    if "fix" in item:
        vertices = _vertices(mesh, name, item["fix"], where, "fix")
        with _context(f"{where} fix"):
            sim.fix(name, vertices)


def _body(sim, item: dict, base_dir: Path, source: str, i: int) -> None:
    """One [[bodies]] table: a FEM body (with mesh = {...}) or a frame body (with
    frames = {...} and region = {...}); its conditions are arrays of tables inside it
    ([[bodies.dirichlet]], [[bodies.fixed_frames]], ...)."""
    from tissuesim.scene.common import body_label
    from tissuesim.scene.tables.fem_body import FEM_BODY_KEYS, add_fem_body
    from tissuesim.scene.tables.frames import FRAME_BODY_KEYS, add_frame_body_tables

    label = body_label(source, "bodies", i)
    where = label()
    if not isinstance(item, dict):
        raise SceneError(f"{where}: must be a table: [[bodies]] name = '...', mesh = {{...}}")
    name = _required(item, "name", where)
    if not (isinstance(name, str) and name):
        raise SceneError(f"{where}: name must be a non-empty string, e.g. name = 'liver'")
    kinds = [k for k in ("mesh", "frames") if k in item]
    if len(kinds) != 1:
        raise SceneError(
            f"{where}: a body is a mesh (mesh = {{...}}: finite elements) or frames "
            f"(frames = {{...}} with region = {{...}}: meshless); give exactly one"
        )
    if kinds == ["mesh"]:
        _unknown(
            item, ("name", "density", "mass", "order", "formulation", "fix", *FEM_BODY_KEYS), where
        )
        add_fem_body(sim, name, item, base_dir, source, label)
    else:
        _unknown(item, ("name", "density", "mass", *FRAME_BODY_KEYS), where)
        add_frame_body_tables(sim, name, item, base_dir, source, label)


def _fem_body_named(sim, name, where: str, key: str):
    fem = [n for n, b in sim.bodies.items() if b.kind == "fem"]
    if name not in fem:
        close = difflib.get_close_matches(str(name), fem, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise SceneError(f"{where}: unknown {key} {name!r}; {hint}the bodies with a mesh are {fem}")
    return sim.bodies[name]


def _body_named(sim, name, where: str, key: str):
    known = [n for n, b in sim.bodies.items() if b.kind in ("fem", "frames")]
    if name not in known:
        close = difflib.get_close_matches(str(name), known, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise SceneError(f"{where}: unknown {key} {short(name)}; {hint}the bodies are {known}")
    return sim.bodies[name]


def _grasper(sim, item: dict, where: str) -> None:
    _unknown(item, GRASPER_KEYS, where)
    if ("organ" in item) == ("body" in item):
        raise SceneError(f"{where}: name the grasped body with body = '...' (or organ = '...')")
    key = "organ" if "organ" in item else "body"
    body = _fem_body_named(sim, item[key], where, key)
    vertices = _vertices(
        body.mesh, body.name, _required(item, "vertices", where), where, "vertices"
    )
    displacement = _of_time(
        _required(item, "displacement", where), f"{where} displacement", "a grasper's displacement"
    )
    options = {}
    if "stiffness" in item:
        options["stiffness"] = _number(
            item["stiffness"], f"{where} stiffness", "a number > 0 (N/m per vertex)"
        )
    if "name" in item:
        if not (isinstance(item["name"], str) and item["name"]):
            raise SceneError(f"{where}: name must be a non-empty string, e.g. name = 'grasper'")
        options["name"] = item["name"]
    if "release" in item:
        options["release"] = _number(item["release"], f"{where} release", "a time in s")
    u0 = displacement(sim.start_time)
    if not np.all(np.isfinite(u0)):
        raise SceneError(
            f"{where} displacement: not finite at the start time t = {sim.start_time:g} s: "
            f"{u0.tolist()}"
        )
    with _context(where):
        sim.grasp(body.name, vertices, displacement, **options)


def _attachment(sim, item: dict, where: str) -> None:
    """attach(body, to, distance, stiffness, name): two bodies glued where they touch (FEM to
    FEM, or a frame body to a FEM body)."""
    _unknown(item, ATTACHMENT_KEYS, where)
    a = _body_named(sim, _required(item, "body", where), where, "body")
    b = _body_named(sim, _required(item, "to", where), where, "to")
    options: dict[str, Any] = {}
    for key, unit in (("distance", "m"), ("stiffness", "N/m per m^2 of contact")):
        if key in item:
            options[key] = _number(item[key], f"{where} {key}", f"a number > 0 ({unit})")
    if "name" in item:
        options["name"] = item["name"]
    with _context(where):
        sim.attach(a.name, b.name, **options)


def _tissue(sim, table: dict, where: str) -> None:
    _unknown(table, TISSUE_KEYS, where)
    material = _inline_material(table, where)
    for key, hint in (
        ("thickness", "the widest gap (m) between organ surfaces the tissue fills, e.g. 0.008"),
        ("spacing", "the distance (m) between the tissue's integration points, e.g. 0.002"),
    ):
        if key not in table:
            raise SceneError(f"{where}: missing key {key!r}: {hint}")
    options: dict[str, Any] = {
        key: _number(table[key], f"{where} {key}", "a number > 0 (m)")
        for key in ("thickness", "spacing")
    }
    for key, unit in (
        ("density", "kg/m^3"),
        ("radius_factor", "a factor"),
        ("attach_distance", "m"),
        ("attachment_stiffness", "N/m per m^2 of contact"),
    ):
        if key in table:
            options[key] = _number(table[key], f"{where} {key}", f"a number > 0 ({unit})")
    for key, valid in (("frame_type", ("affine", "rigid")), ("shape", ("wendland", "shepard"))):
        if key in table:
            if table[key] not in valid:
                raise SceneError(
                    f"{where}: {key} must be {' or '.join(map(repr, valid))}, not {table[key]!r}"
                )
            options[key] = table[key]
    if "frames" in table:
        frames = table["frames"]
        if isinstance(frames, list):
            if not frames:
                raise SceneError(f"{where}: frames must be a count or a list [[x, y, z], ...]")
            options["frames"] = np.array(
                [_vector3(p, f"{where} frames[{i}]") for i, p in enumerate(frames)]
            )
        elif isinstance(frames, int) and not isinstance(frames, bool) and frames >= 1:
            options["frames"] = frames
        else:
            raise SceneError(
                f"{where}: frames must be an integer >= 1 (placed by farthest-point sampling) "
                f"or a list of rest origins [[x, y, z], ...], not {short(frames)}"
            )
    if "region" in table:
        region = table["region"]
        if not (isinstance(region, dict) and list(region) == ["where"]):
            raise SceneError(
                f'{where}: region must be {{ where = "<condition on x, y, z>" }}, e.g. '
                f'region = {{ where = "abs(y) < 0.02" }}, not {short(region)}'
            )
        options["region"] = _condition(region["where"], f"{where} region where")
    with _context(where):
        sim.add_tissue(material, **options)
