"""FEBio's rigid bodies: the ``rigid body`` material, the ``<Rigid>`` section (``rigid_fixed``,
``rigid_displacement``, ``rigid_rotation``; ``rigid_force``, ``rigid_moment``) and
``<bc type="rigid">`` node sets, read into ``FebModel.rigid`` for tissuesim's rigid bodies
(``simulation/rigid.py``; the scene's ``[[rigid_bodies]]``, written by ``febio/scene.py``).

FEBio's rigid DOFs are x, y, z (the centre of mass' translation) and u, v, w (rotation about
the global axes through it): tissuesim's x, y, z, rx, ry, rz. A DOF no condition holds is free,
as in FEBio. A prescribed value is the displacement (rotation, rad) from the reference
configuration (``relative`` 1 is refused after the first step). Rigid connectors (joints,
springs, dampers) are refused in one line."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.febio.model import FebModel, Load, _flag, _floats, _int_attr, _once, _unsupported
from tissuesim.febio.rigid.connectors import read_connector, rigid_body_name
from tissuesim.febio.xml import Node

__all__ = ["rigid_material", "read_rigid", "read_rigid_nodes", "RIGID_DOFS", "IC_TYPES"]

#: FEBio's initial conditions of a rigid body (a note in a static analysis)
IC_TYPES = ("initial_rigid_velocity", "initial_rigid_angular_velocity")

#: FEBio's rigid DOF names (rigid_fixed's R*_dof, rigid_displacement's / rigid_force's dof)
#: -> tissuesim's DOF index (rigid/body.py DOF_NAMES)
RIGID_DOFS = {
    "x": 0, "y": 1, "z": 2, "Rx": 0, "Ry": 1, "Rz": 2,
    "Ru": 3, "Rv": 4, "Rw": 5, "u": 3, "v": 4, "w": 5,
}  # fmt: skip


def rigid_material(model: FebModel, mat: Node) -> tuple:
    """("rigid", {"center": [...] or absent, "E", "v"}, density, "rigid body", None): the
    rigid body's density and centre of mass (FEBio computes it from the elements when it is
    not given); E and v only condition FEBio's own solve."""
    params: dict = {}
    density = 1.0
    name = mat.attrib.get("name") or mat.attrib.get("id", "")
    _rigid(model, name)["node"] = mat
    for p in _once(mat).values():
        if p.children or "lc" in p.attrib or p.attrib.get("type") not in (None, "const"):
            raise _unsupported(p, "a rigid body parameter that is a field, a curve or a table")
        if p.tag == "density":
            density = float(_floats(p, 1)[0])
            if density <= 0:
                raise p.error(f"density {density:g}: a rigid body's density must be > 0")
        elif p.tag == "center_of_mass":
            params["center"] = _floats(p, 3).tolist()
        elif p.tag in ("E", "v"):
            params[p.tag] = float(_floats(p, 1)[0])
        else:
            raise p.error(
                f"parameter {p.tag!r} of 'rigid body': it takes density, center_of_mass, E, v"
            )
    return ("rigid", params, density, "rigid body", None)


def _body(model: FebModel, node: Node) -> str:
    """The rigid body a condition names (<rb>: the material's name or id)."""
    rb = _once(node).get("rb")
    if rb is None:
        raise node.error("needs <rb>, the rigid body's material")
    return rigid_body_name(model, rb)


@dataclass(frozen=True)
class EulerComponent:
    """Component k of the rotation vector of FEBio's Euler angles (Ex, Ey, Ez in degrees,
    each a Load): quatd::SetEuler's quaternion (half angles; w = cz cx cy + sz sx sy, ...)
    and its rotation vector 2 atan2(|q|, w) q / |q| (quatd::GetRotationVector)."""

    angles: tuple
    k: int

    def expression(self, times) -> str:
        """As an expression of t, the angles' values written by ``times(load)``."""
        half = [f"(0.5 * {np.pi / 180.0!r} * ({times(a)}))" for a in self.angles]
        cx, cy, cz = (f"cos({h})" for h in half)
        sx, sy, sz = (f"sin({h})" for h in half)
        w = f"({cz} * {cx} * {cy} + {sz} * {sx} * {sy})"
        q = [
            f"({cz} * {sx} * {cy} - {sz} * {cx} * {sy})",
            f"({cz} * {cx} * {sy} + {sz} * {sx} * {cy})",
            f"({sz} * {cx} * {cy} - {cz} * {sx} * {sy})",
        ]
        n = f"sqrt({q[0]}**2 + {q[1]}**2 + {q[2]}**2)"
        return (
            f"where({n} > 0, {q[self.k]} / where({n} > 0, {n}, 1.0) * 2 * arctan2({n}, {w}), 0.0)"
        )


def _rigid(model: FebModel, name: str) -> dict:
    return model.rigid.setdefault(name, {"held": {}, "force": [], "moment": []})


def _hold(model: FebModel, node: Node, body: str, dof: int, load: Load | None) -> None:
    held = _rigid(model, body)["held"]
    if dof in held:
        raise node.error(f"rigid body {body!r}: this DOF is held twice (by another condition)")
    held[dof] = load


def _value(model: FebModel, node: Node, p: dict) -> Load:
    if "value" not in p:
        raise node.error("needs a <value>")
    curve = _int_attr(p["value"], "lc", "a load curve id (a <load_controller>'s id)")
    return Load(_floats(p["value"], 1), curve, model.window)


def read_rigid(model: FebModel, section: Node) -> None:
    """<Rigid>: rigid_bc (fixed, prescribed) and rigid_load (force, moment) per rigid body;
    then the forces given on prismatic joints (``joint_forces``)."""
    _read_rigid(model, section)
    joint_forces(model)


def joint_forces(model: FebModel) -> None:
    """A prismatic joint's <force> (FERigidPrismaticJoint: F e on body a, -F e on body b, e
    its translation axis, which turns with body a) as rigid forces on the two bodies: exact
    where the axis does not turn, a body of the joint held in every rotation (the joint locks
    their relative rotation); refused otherwise."""
    for entry in model.rigid_connectors:
        if "force" not in entry:
            continue
        load, node = entry.pop("force")
        held = [set(model.rigid.get(b, {}).get("held", {})) for b in (entry["a"], entry["b"])]
        fixed = [
            {3, 4, 5} <= h and all(model.rigid[b]["held"][d] is None for d in (3, 4, 5))
            for h, b in zip(held, (entry["a"], entry["b"]), strict=True)
        ]
        if not any(fixed):
            raise node.error(
                "a force on a prismatic joint whose bodies may turn: tissuesim applies it along "
                "the joint's axis at rest (hold one body's rotations, rigid_fixed Ru, Rv, Rw)"
            )
        axis = np.asarray(entry["axis"], dtype=float)
        axis = axis / np.linalg.norm(axis)
        for body, sign in ((entry["a"], 1.0), (entry["b"], -1.0)):
            for k in range(3):
                if axis[k] != 0.0:
                    value = load.value * sign * axis[k]
                    _rigid(model, body)["force"].append((k, Load(value, load.curve, load.window)))


def _read_rigid(model: FebModel, section: Node) -> None:
    """<Rigid>: rigid_bc (fixed, prescribed) and rigid_load (force, moment) per rigid body."""
    for c in section.children:
        kind = c.attrib.get("type", "")
        if c.tag == "rigid_connector":
            read_connector(model, c, kind)
            continue
        if c.tag == "rigid_ic" and kind in IC_TYPES:
            if model.analysis != "static":
                raise c.error(
                    f"{kind}: tissuesim starts a rigid body at rest in a dynamic analysis (an "
                    "initial rigid velocity is not supported yet)"
                )
            model.note(c, f"{kind} has no effect in a STATIC analysis (nor in FEBio's)")
            continue
        if model.window is not None:
            raise c.error(
                "a rigid body condition inside a <step>: tissuesim holds a rigid body's DOFs "
                "for the whole run (give it in the model's <Rigid> section)"
            )
        body = _body(model, c)
        p = _once(c)
        if c.tag == "rigid_bc" and kind == "rigid_fixed":
            flags = [k for k in p if k.endswith("_dof")]
            for k in flags:
                if k.removesuffix("_dof") not in RIGID_DOFS:
                    raise p[k].error(f"<{k}>: the DOFs are Rx, Ry, Rz, Ru, Rv, Rw")
                if _flag(p[k]):
                    _hold(model, c, body, RIGID_DOFS[k.removesuffix("_dof")], None)
            continue
        if c.tag == "rigid_bc" and kind in ("rigid_displacement", "rigid_rotation"):
            allowed = ("x", "y", "z") if kind == "rigid_displacement" else ("Ru", "Rv", "Rw")
            dof = p.get("dof")
            if dof is None or dof.text.strip() not in allowed:
                raise c.error(f"{kind} needs <dof> {', '.join(allowed)}")
            if "relative" in p and _flag(p["relative"]):
                raise p["relative"].error(
                    "relative = 1: tissuesim prescribes a rigid body's motion from its reference "
                    "configuration (relative = 0)"
                )
            _hold(model, c, body, RIGID_DOFS[dof.text.strip()], _value(model, c, p))
            continue
        if c.tag == "rigid_bc" and kind == "rigid_rotation_vector":
            # FERigidRotationVector: the rotation vector's components vx, vy, vz (rad, each
            # with its curve) prescribed on Ru, Rv, Rw, as three rigid_rotation conditions
            for tag in p:
                if tag not in ("rb", "vx", "vy", "vz"):
                    raise p[tag].error(f"<{tag}>: a rigid_rotation_vector takes vx, vy, vz")
            for k, tag in enumerate(("vx", "vy", "vz")):
                value = p.get(tag)
                load = (
                    Load(np.zeros(1))
                    if value is None
                    else Load(
                        _floats(value, 1), _int_attr(value, "lc", "a load curve id"), model.window
                    )
                )
                _hold(model, c, body, 3 + k, load)
            continue
        if c.tag == "rigid_bc" and kind == "rigid_euler_angles":
            # FERigidEulerAngles: Ex, Ey, Ez (degrees, each with its curve) turned into the
            # rotation vector of quatd::SetEuler's quaternion, prescribed on Ru, Rv, Rw
            for tag in p:
                if tag not in ("rb", "Ex", "Ey", "Ez"):
                    raise p[tag].error(f"<{tag}>: a rigid_euler_angles takes Ex, Ey, Ez")
            angles = tuple(
                Load(np.zeros(1))
                if p.get(tag) is None
                else Load(_floats(p[tag], 1), _int_attr(p[tag], "lc", "a load curve id"),
                          model.window)
                for tag in ("Ex", "Ey", "Ez")
            )  # fmt: skip
            for k in range(3):
                _hold(model, c, body, 3 + k, EulerComponent(angles, k))
            continue
        if c.tag == "rigid_load" and kind in ("rigid_force", "rigid_moment"):
            allowed = ("Rx", "Ry", "Rz") if kind == "rigid_force" else ("Ru", "Rv", "Rw")
            dof = p.get("dof")
            if dof is None or dof.text.strip() not in allowed:
                raise c.error(f"{kind} needs <dof> {', '.join(allowed)}")
            load_type = p.get("load_type")
            if load_type is not None and load_type.text.strip() not in ("LOAD", "0"):
                raise load_type.error(
                    f"load_type {load_type.text.strip()!r}: tissuesim applies a rigid force as a "
                    "load (LOAD), not a follower or a target"
                )
            if "relative" in p and _flag(p["relative"]):
                raise p["relative"].error("relative = 1 is not supported by tissuesim")
            key = "force" if kind == "rigid_force" else "moment"
            axis = RIGID_DOFS[dof.text.strip()] % 3
            _rigid(model, body)[key].append((axis, _value(model, c, p)))
            continue
        raise c.error(
            f"<{c.tag} type={kind!r}> is not supported by tissuesim; it runs rigid_fixed, "
            "rigid_displacement, rigid_rotation, rigid_rotation_vector, rigid_euler_angles, "
            "rigid_force and rigid_moment"
        )


def read_rigid_nodes(model: FebModel, bc: Node, nodes: str) -> None:
    """<bc type="rigid">: the node set moves with the rigid body (FEBio's rigid interface)."""
    p = _once(bc)
    for k, c in p.items():
        if k not in ("rb", "clamp_shells"):
            raise _unsupported(c, "this parameter of a rigid <bc> is not supported by tissuesim")
    model.rigid_nodes.append((nodes, _body(model, bc), bc))
