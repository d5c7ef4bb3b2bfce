"""FEBio's ``<Constraints>`` section (FEBio 3.0 and 4.0): the constraint types tissuesim runs,
each mapped onto what tissuesim already has; every other type is refused with its line."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tissuesim.febio.model import FebModel
from tissuesim.febio.xml import Node

__all__ = ["read_constraints", "set_walls_apart", "CONSTRAINT_TYPES"]

#: the <constraint> types read
CONSTRAINT_TYPES = ("rigid_wall", "linear constraint", "node distance")


def read_constraints(model: FebModel, section: Node) -> None:
    """<Constraints>: a ``rigid_wall`` (FEBio's FERigidWallInterface: the surface's nodes kept
    on one side of the plane a x + b y + c z = d, moved along its normal by ``offset``) is the
    same condition as FEBio's rigid_wall contact, and becomes tissuesim's contact with a
    moving plane obstacle (FEBio's penalty is not used: the barrier keeps the nodes off the
    plane)."""
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
                "a rigid_wall given in one <step> of several: tissuesim's contact holds for the "
                "whole run (give it in the model's <Constraints> section)"
            )
        # read as the <contact type="rigid_wall"> it is the same condition as (the element
        # keeps its attributes, children and line; only its tag is the contact's)
        copy = replace(c, tag="contact")
        _contact(model, replace(section, children=[copy]))
        if any(n is copy for n in model.noted):  # its tuning noted: not checked, as a note
            model.noted.append(c)
        model.contacts[-1]["constraint"] = True


def set_walls_apart(model: FebModel) -> None:
    """Every rigid wall that its surface starts on, moved apart (``_set_wall_apart``); run once
    the whole model is read (the offset's load curve may come after <Constraints>)."""
    for c in model.contacts:
        if c["type"] == "rigid_wall":
            _set_wall_apart(model, c)


def _set_wall_apart(model: FebModel, wall: dict) -> None:
    """A wall the surface starts on (FEBio's usual set-up: the gap is zero at the start) is
    moved away from the surface by the barrier's dhat (``contact_start.DHAT`` of the surface's
    size, written as ``[contact] dhat``: ``model.contact_dhat``), so the surface starts where
    the barrier begins to act, force-free as in FEBio; one line in ``model.changes``."""
    from tissuesim.febio.contact_start import DHAT

    a = wall["plane"][:3]
    norm = float(np.linalg.norm(a))
    if norm == 0.0:
        raise wall["node"].error("the rigid_wall's <plane> a,b,c,d has a zero normal (a, b, c)")
    nodes = model.nodes[np.unique(model.surfaces[wall["surfaces"][0]][0])]
    offset = wall["offset"]
    start = float(offset.value[0]) * (curve_value(model, offset.curve, 0.0))
    # FEBio's gap (FERigidWallInterface::ProjectSurface): the distance of a node from the
    # plane along its unit normal, less the offset; the surface is on the normal's side
    gap = float(np.min((nodes @ a - wall["plane"][3]) / norm - start))
    dhat = DHAT * float(np.linalg.norm(np.ptp(nodes, axis=0)))
    if gap >= 0.5 * dhat:
        return
    if gap < -0.5 * dhat:
        raise wall["node"].error(
            f"the surface {wall['surfaces'][0]!r} starts {-gap:.3g} behind the rigid wall "
            "(FEBio keeps it on the side the plane's normal points to): move the wall"
        )
    wall["plane"] = np.append(a, wall["plane"][3] + (gap - dhat) * norm)
    model.contact_dhat = max(model.contact_dhat or 0.0, dhat)
    model.changes.append(
        f"{wall['node'].where()}: the surface {wall['surfaces'][0]!r} starts "
        f"{'on' if gap == 0.0 else f'{gap:.3g} from'} the rigid wall: tissuesim's barrier needs "
        f"it apart, so the wall is moved {dhat - gap:.3g} (model units) away from it, to the "
        "barrier's dhat (written in [contact]), so it starts with no force; the result differs "
        "from FEBio's by at most that displacement"
    )


def curve_value(model: FebModel, curve: int | None, t: float) -> float:
    """A load curve's value at t (1 without a curve)."""
    if curve is None:
        return 1.0
    points = model.curves[curve].points
    return float(np.interp(t, points[:, 0], points[:, 1]))
