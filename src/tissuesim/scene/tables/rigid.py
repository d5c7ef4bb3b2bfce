"""``[[rigid_bodies]]``: rigid bodies of a scene of several bodies (``Simulation.add_rigid_body``,
``simulation/rigid.py``); ``convert`` writes one per FEBio rigid body.

    [[rigid_joints]]                      # between two rigid bodies (rigid/joints.py)
    kind = "revolute"                     # spherical, revolute, prismatic, cylindrical,
    a = "ground"                          # planar, or spring
    b = "arm"
    origin = [0.0, 0.0, 0.0]              # m, at rest
    axis = [0.0, 0.0, 1.0]
    transverse = [1.0, 0.0, 0.0]          # the zero of rotation
    rotation = "0.5 * t"                  # rad (translation: m), prescribed, optional
    enforcement = { penalty = 10.0, tolerance = 0.1 }   # FEBio's rule, optional (joints.py)
    # a spring: point_a, point_b (m, at rest), stiffness (N/m), free_length (m)

    [[rigid_bodies]]
    name = "platen"
    bodies = ["platen_mesh"]              # FEM bodies that move rigidly as a whole
    vertices = [{ body = "sample", vertices = { tagged = "top" } }]   # glued to it
    center = [0.0, 0.0, 1.0]              # m (default: the bodies' centre of mass)
    fixed = ["x", "y", "rx", "ry", "rz"]  # DOFs: x, y, z, rx, ry, rz
    prescribed = { z = "-0.1 * t" }       # m or rad, numbers or expressions of t
    force = [0.0, 0.0, "-2.0 * t"]        # N, on the centre
    moment = [0.0, 0.0, 0.0]              # N m, about the centre
"""

from __future__ import annotations

from tissuesim.errors import SceneError
from tissuesim.scene.common import _context, _table, _unknown, of_time
from tissuesim.scene.expressions import compile_expression
from tissuesim.validate import short

__all__ = ["RIGID_KEYS", "JOINT_KEYS", "add_rigid_bodies"]

RIGID_KEYS = ("name", "bodies", "vertices", "center", "fixed", "prescribed", "force", "moment")
JOINT_KEYS = (
    "kind", "a", "b", "origin", "axis", "transverse", "rotation", "translation", "name",
    "point_a", "point_b", "stiffness", "free_length", "enforcement",
)  # fmt: skip


def _names(value, where: str) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise SceneError(f"{where}: expected a list of names, not {short(value)}")
    return value


def _scalar_of_time(value, where: str):
    import numpy as np

    f = compile_expression(value, where)
    origin = np.zeros((1, 3))
    return lambda t: float(f(origin, t)[0])


def add_rigid_bodies(sim, data: dict, source: str) -> None:
    """Read the scene's [[rigid_bodies]] into ``sim``."""
    from tissuesim.scene.tables.fem_body import _select

    for i, item in enumerate(_table(data, "rigid_bodies", source, array=True), start=1):
        where = f"{source} rigid_bodies[{i}]"
        _unknown(item, RIGID_KEYS, where)
        if not isinstance(item.get("name"), str):
            raise SceneError(f"{where}: name must be a text (the rigid body's name)")
        bodies = _names(item.get("bodies", []), f"{where} bodies")
        vertices = {}
        for k, entry in enumerate(item.get("vertices", []), start=1):
            here = f"{where} vertices[{k}]"
            if not isinstance(entry, dict):
                raise SceneError(f"{here}: expected {{ body = ..., vertices = {{...}} }}")
            _unknown(entry, ("body", "vertices"), here)
            body = entry.get("body")
            if body not in sim.bodies or sim.bodies[body].kind != "fem":
                raise SceneError(
                    f"{here} body: {short(body)} is not a FEM body of this scene; bodies: "
                    f"{sorted(sim.bodies)}"
                )
            if "vertices" not in entry:
                raise SceneError(f"{here}: missing key 'vertices' (a selector table)")
            vertices[body] = _select(sim.bodies[body].mesh, "vertices", entry["vertices"], here)
        fixed = _names(item.get("fixed", []), f"{where} fixed")
        prescribed = item.get("prescribed", {})
        if not isinstance(prescribed, dict):
            raise SceneError(f"{where} prescribed: expected a table {{ dof = value, ... }}")
        prescribed = {
            dof: _scalar_of_time(value, f"{where} prescribed.{dof}")
            for dof, value in prescribed.items()
        }
        loads = {
            key: of_time(item[key], 3, f"{where} {key}", key)
            for key in ("force", "moment")
            if key in item
        }
        with _context(where):
            sim.add_rigid_body(
                item["name"],
                bodies,
                vertices=vertices,
                center=item.get("center"),
                fixed=fixed,
                prescribed=prescribed,
                **loads,
            )
    add_rigid_joints(sim, data, source)


def add_rigid_joints(sim, data: dict, source: str) -> None:
    """Read the scene's [[rigid_joints]] into ``sim``."""
    for i, item in enumerate(_table(data, "rigid_joints", source, array=True), start=1):
        where = f"{source} rigid_joints[{i}]"
        _unknown(item, JOINT_KEYS, where)
        kind = item.get("kind")
        for key in ("kind", "a", "b"):
            if not isinstance(item.get(key), str):
                raise SceneError(f"{where}: {key} must be a text (the joint's kind, its bodies)")
        with _context(where):
            if kind == "spring":
                sim.add_rigid_spring(
                    item["a"], item["b"], item.get("point_a"), item.get("point_b"),
                    item.get("stiffness"), free_length=item.get("free_length"),
                    name=item.get("name"),
                )  # fmt: skip
                continue
            motion = {
                key: _scalar_of_time(item[key], f"{where} {key}")
                for key in ("rotation", "translation")
                if key in item
            }
            sim.add_rigid_joint(
                kind, item["a"], item["b"], item.get("origin"), axis=item.get("axis"),
                transverse=item.get("transverse"), name=item.get("name"),
                enforcement=item.get("enforcement"), **motion,
            )  # fmt: skip
