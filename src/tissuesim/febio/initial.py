"""FEBio's ``<Initial>`` section: ``<ic type="velocity">`` (FEInitialVelocity: the nodes of a
node set start with the velocity given), written as the ``[initial] velocity`` of the body
the node set covers. Other initial conditions are refused with their line."""

from __future__ import annotations

import numpy as np

from tissuesim.febio.model import FebModel, _floats, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["read_initial", "initial_velocity"]


def read_initial(model: FebModel, section: Node) -> None:
    from tissuesim.febio.condition_sections import _children, _node_set

    for ic in section.children:
        kind = ic.attrib.get("type", "")
        if ic.tag != "ic" or kind != "velocity":
            raise ic.error(
                f"<{ic.tag}> type {kind!r} is not supported by tissuesim; it reads "
                '<ic type="velocity"> (an initial velocity)'
            )
        nodes = _node_set(model, ic)
        p = _children(ic, {"value"})
        if "value" not in p:
            raise ic.error("needs a <value> (the velocity vector)")
        if "lc" in p["value"].attrib:
            raise _unsupported(p["value"], "a load curve on an initial velocity")
        model.initial_velocity.append((nodes, _floats(p["value"], 3), ic))


def initial_velocity(model: FebModel, body: dict) -> list[float] | None:
    """The velocity (3,) the body starts with (None: at rest): an <ic type="velocity"> on
    every node of the body; one on some of its nodes only is refused (tissuesim starts a
    body with one velocity field, written as a vector here), and so is one in a STATIC
    analysis (FEBio's quasi-static steps have no velocity)."""
    used = np.unique(body["cells"])
    found = None
    for name, value, node in model.initial_velocity:
        nodes = model.node_sets[name]
        inside = np.isin(used, nodes)
        if not inside.any():
            continue
        if not inside.all():
            raise node.error(
                f"an initial velocity on {int(inside.sum())} of the {used.size} nodes of a "
                "body: tissuesim starts a whole body with one velocity (give the node set all "
                "of its nodes)"
            )
        if model.analysis != "dynamic" and not any(
            p["analysis"] == "dynamic" for p in model.phases
        ):
            raise node.error("an initial velocity in a STATIC analysis has no effect: remove it")
        if found is not None:
            raise node.error("two initial velocities on one body: give one")
        found = [float(v) for v in value]
    return found
