"""FEBio's rigid bodies in the converted scene: each ``rigid body`` material's parts become one
FEM body moving rigidly as a whole (its mass the rigid body's, its faces contact surfaces), and
the nodes of deformable bodies shared with it or named by a ``<bc type="rigid">`` a point set
glued to it; one ``[[rigid_bodies]]`` table per rigid body with its held DOFs and loads."""

from __future__ import annotations

import numpy as np

from tissuesim.febio.model import FebModel, Load
from tissuesim.rigid.body import DOF_NAMES

__all__ = [
    "rigid_material_of", "rigid_bodies", "rigid_joints", "rigid_names", "interface_sets",
    "RIGID_SET",
]  # fmt: skip

#: the point set of a deformable body's nodes glued to rigid body <name>
RIGID_SET = "{}.rigid_interface"


def rigid_material_of(model: FebModel, part: str) -> str | None:
    """The rigid body material's name of a part, or None for a deformable part."""
    mat = model.domains[part][0]
    key = mat if mat in model.materials else f"#{mat}"
    spec = model.materials.get(key)
    if spec is None or spec[3] != "rigid body":
        return None
    return next(k for k, v in model.materials.items() if v is spec and not k.startswith("#"))


def interface_sets(model: FebModel, body: dict, used: np.ndarray) -> dict[str, np.ndarray]:
    """{rigid body: the model's node rows of this deformable body glued to it}: nodes it shares
    with the rigid body's elements, and its nodes in the rigid body's <bc type="rigid"> sets."""
    if body.get("rigid") is not None:
        return {}
    out: dict[str, set] = {}
    mine = set(used.tolist())
    for part, (_, cells, _, _) in model.parts.items():
        name = rigid_material_of(model, part)
        if name is not None:
            out.setdefault(name, set()).update(mine & set(np.unique(cells).tolist()))
    for nodes, name, _ in model.rigid_nodes:
        out.setdefault(name, set()).update(mine & set(model.node_sets[nodes].tolist()))
    return {k: np.array(sorted(v), dtype=np.int64) for k, v in out.items() if v}


def rigid_bodies(model: FebModel, bodies: list[dict], names: list[str], times) -> list[dict]:
    """The [[rigid_bodies]] tables: per rigid body material, the FEM body of its elements, the
    glued point sets of the deformable bodies, its centre (when the model gives it), its held
    DOFs (fixed, prescribed as expressions of t: ``times(Load, model)``) and its loads."""
    tables = []
    materials = [m for m, spec in model.materials.items()
                 if spec[3] == "rigid body" and not m.startswith("#")]  # fmt: skip
    for material in materials:
        entry: dict = {"name": material}
        own = [n for n, b in zip(names, bodies, strict=True) if b.get("rigid") == material]
        glued = [
            {"body": n, "vertices": {"tagged": RIGID_SET.format(material)}}
            for n, b in zip(names, bodies, strict=True)
            if material in b.get("interfaces", {})
        ]
        params = model.materials[material][1]
        joined = any(material in (c["a"], c["b"]) for c in model.rigid_connectors)
        if not own and not glued and not joined:
            model.notes.append(f"rigid body {material!r}: no elements and no nodes, not used")
            continue
        if not own and not glued and "center" not in params:
            raise model.rigid[material]["node"].error(
                f"rigid body {material!r} has no elements: give its <center_of_mass>"
            )
        if own:
            entry["bodies"] = own
        if glued:
            entry["vertices"] = glued
        if "center" in params:
            entry["center"] = list(params["center"])
        conditions = model.rigid.get(material, {"held": {}, "force": [], "moment": []})
        fixed = [DOF_NAMES[k] for k, load in sorted(conditions["held"].items()) if load is None]
        if fixed:
            entry["fixed"] = fixed
        prescribed = {
            DOF_NAMES[k]: load.expression(lambda a: times(a, model))
            if hasattr(load, "expression")  # rigid_euler_angles (rigid/conditions.py)
            else times(load, model)
            for k, load in sorted(conditions["held"].items())
            if load is not None
        }
        if prescribed:
            entry["prescribed"] = prescribed
        for key in ("force", "moment"):
            if conditions[key]:
                items = ["0.0"] * 3
                for axis, load in conditions[key]:  # several on one axis: their sum
                    term = times(Load(load.value, load.curve, load.window), model)
                    items[axis] = term if items[axis] == "0.0" else f"{items[axis]} + {term}"
                entry[key] = items
        tables.append(entry)
    names_used = set(names)
    for t in tables:  # a rigid body is named after its material, apart from the FEM bodies
        if t["name"] in names_used:
            t["name"] = f"{t['name']}.rigid"
    return tables


def rigid_names(tables: list[dict], model: FebModel) -> dict[str, str]:
    """rigid body material -> its [[rigid_bodies]] name in the scene."""
    out = {}
    for t in tables:
        name = t["name"]
        out[name.removesuffix(".rigid") if name not in model.materials else name] = name
    return out


def rigid_joints(model: FebModel, names: dict[str, str], times) -> list[dict]:
    """The [[rigid_joints]] tables of the model's rigid connectors (``names``: rigid body
    material -> its scene name; ``times(Load, model)`` a prescribed value's expression)."""
    tables = []
    for entry in model.rigid_connectors:
        table = {k: v for k, v in entry.items() if v is not None}
        table["a"], table["b"] = names[entry["a"]], names[entry["b"]]
        for key in ("rotation", "translation"):
            if key in table:
                table[key] = times(table[key], model)
        tables.append(table)
    return tables
