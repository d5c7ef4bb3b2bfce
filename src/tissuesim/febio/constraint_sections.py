"""FEBio's ``<Constraints>`` section (FEBio 3.0 and 4.0): the constraint types tissuesim runs,
each mapped onto what tissuesim already has; every other type is refused with its line."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tissuesim.febio.model import FebModel, Load
from tissuesim.febio.xml import Node

__all__ = ["read_constraints", "take_rigid_walls", "rigid_wall_tables", "CONSTRAINT_TYPES"]

#: the <constraint> types read
CONSTRAINT_TYPES = ("rigid_wall", "linear constraint", "node distance")
#: FEBio's rigid wall's parameters (FERigidWallInterface); its enforcement's, read here
WALL_PARAMETERS = {"laugon", "tolerance", "penalty", "offset", "plane"}
#: augmentations a step at most (FEBio's rigid wall has no cap: it augments until its
#: tolerance is met)
MAX_AUGMENTATIONS = 50


def read_constraints(model: FebModel, section: Node) -> None:
    """<Constraints>: a ``rigid_wall`` (FEBio's FERigidWallInterface: the surface's nodes kept
    on one side of the plane a x + b y + c z = d, moved along its normal by ``offset``) is the
    same condition as FEBio's rigid_wall contact: read as one, then taken by
    ``take_rigid_walls``."""
    from tissuesim.febio.condition_sections import _contact

    for c in section.children:
        kind = c.attrib.get("type", "")
        if c.tag != "constraint" or kind not in CONSTRAINT_TYPES:
            raise c.error(
                f"<{c.tag}> type {kind!r} is not supported by tissuesim; it runs "
                f"{', '.join(CONSTRAINT_TYPES)} (see docs/guide/febio.md)"
            )
        if kind == "node distance":  # a spring of its target length (febio/discrete.py)
            from tissuesim.febio.discrete import read_node_distance

            read_node_distance(model, c)
            continue
        if kind == "linear constraint":  # febio/linear_constraints.py
            from tissuesim.febio.linear_constraints import read_constraint_set

            read_constraint_set(model, c)
            continue
        if model.window is not None and model.steps > 1:
            raise c.error(
                "a rigid_wall given in one <step> of several: tissuesim's wall holds for the "
                "whole run (give it in the model's <Constraints> section)"
            )
        # read as the <contact type="rigid_wall"> it is the same condition as (the element
        # keeps its attributes, children and line; only its tag is the contact's)
        copy = replace(c, tag="contact")
        _contact(model, replace(section, children=[copy]))
        if any(n is copy for n in model.noted):
            model.noted.append(c)
        model.contacts[-1]["constraint"] = True


def take_rigid_walls(model: FebModel) -> None:
    """Every rigid wall (``<Contact>`` or ``<Constraints>``) moved from ``model.contacts`` to
    ``model.rigid_walls`` with FEBio's enforcement (``_wall``): tissuesim's rigid wall energy
    (contact/penalty/rigid_wall.py), as FEBio enforces it. Run once the whole model is read."""
    walls = [(k, c) for k, c in enumerate(model.contacts, start=1) if c["type"] == "rigid_wall"]
    model.contacts[:] = [c for c in model.contacts if c["type"] != "rigid_wall"]
    for k, c in walls:  # k: its place among the contacts, its default name's number
        wall = _wall(model, c, k)
        if wall is not None:
            model.rigid_walls.append(wall)


def _wall(model: FebModel, c: dict, k: int) -> dict | None:
    """FEBio's rigid wall's settings (``FERigidWallInterface``: laugon, tolerance, penalty,
    offset, plane); None for one of penalty 0 (FEBio's default: it pushes nothing), noted."""
    from tissuesim.febio.model import _children, _floats, _load, _unsupported

    node = c["node"]
    for child in node.children:
        if child.tag not in WALL_PARAMETERS:
            raise _unsupported(child, f"<{child.tag}> in a rigid_wall (FEBio's rigid wall "
                               "takes laugon, tolerance, penalty, offset and plane)")  # fmt: skip
    p = _children(node, WALL_PARAMETERS)
    method = (p["laugon"].text or "").strip().upper() if "laugon" in p else "PENALTY"
    methods = {"0": False, "PENALTY": False, "1": True, "AUGLAG": True}
    if method not in methods:
        raise _unsupported(p["laugon"], f"rigid wall enforcement laugon = {method!r} (FEBio's "
                           "rigid wall runs PENALTY (0) and AUGLAG (1))")  # fmt: skip
    load = _load(model, p["penalty"], 1) if "penalty" in p else Load(np.zeros(1))
    penalty = float(load.value[0])
    if load.curve is not None and load.curve not in model.curves:
        raise p["penalty"].error(f"load curve {load.curve} is used but not defined in <LoadData>")
    for child in node.children:  # an element kept as a note is not checked by the reader
        unread = [k for k in child.attrib.unread() if k not in ("name", "id")]
        if unread:
            raise _unsupported(child, f'attribute {unread[0]}="{child.attrib[unread[0]]}" on a '
                               "rigid_wall's parameter")  # fmt: skip
    if penalty < 0:
        raise p["penalty"].error("a rigid_wall's <penalty> must be >= 0")
    if penalty == 0.0:
        model.note(node, "a rigid_wall of penalty 0 (FEBio's default) pushes nothing: left out")
        return None
    tolerance = float(_floats(p["tolerance"], 1)[0]) if "tolerance" in p else 0.0
    a = np.asarray(c["plane"][:3], float)
    size = float(np.linalg.norm(a))
    if size == 0.0:
        raise node.error("the rigid_wall's <plane> a,b,c,d has a zero normal (a, b, c)")
    return {
        "name": node.attrib.get("name") or f"wall{k}",
        "node": node,
        "surface": c["surfaces"][0],
        # FEBio's gap is offset - |a| (a . x - d) (ProjectToPlane does not normalise a) and
        # its force pushes along a / |a|: on the unit plane, the offset / |a|^2 and the
        # penalty eps |a|^2 give the same force (the same for |a| = 1)
        "plane": np.append(a / size, c["plane"][3] / size),
        "penalty": penalty * size**2,
        "penalty_curve": load.curve,  # FEBio's penalty times this curve (None: constant)
        "offset": replace(c["offset"], value=np.asarray(c["offset"].value, float) / size**2),
        "augmented": methods[method],
        "tolerance": tolerance,
    }


def rigid_wall_tables(model: FebModel, names: list[str], meshes: dict) -> list[dict]:
    """[[rigid_wall]] tables: one per wall and body holding its surface (a surface of parts
    split into bodies is on each)."""
    from tissuesim.febio.curves import curve_expression, load_expression

    tables = []
    for w in model.rigid_walls:
        held = [n for n, mesh in zip(names, meshes.values(), strict=True)
                if w["surface"] in mesh.facet_sets]  # fmt: skip
        if not held:
            raise w["node"].error(
                f"the rigid_wall's surface {w['surface']!r} is on no deformable body "
                "(tissuesim's rigid wall presses FEM bodies' nodes)"
            )
        for body in held:
            name = w["name"] if len(held) == 1 else f"{w['name']}.{body}"
            table = {"name": name, "body": body, "facets": w["surface"],
                     "plane": w["plane"].tolist(), "penalty": w["penalty"],
                     "offset": load_expression(w["offset"], model)}  # fmt: skip
            if w["penalty_curve"] is not None:
                curve = model.curves[w["penalty_curve"]]
                table["penalty_scale"] = curve_expression(curve)
            if w["augmented"]:  # FEBio augments until the tolerance is met: no cap but ours
                table.update(augmented=True, tolerance=w["tolerance"],
                             max_augmentations=MAX_AUGMENTATIONS)  # fmt: skip
            tables.append(table)
    return tables
