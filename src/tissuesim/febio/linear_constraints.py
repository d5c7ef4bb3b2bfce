"""FEBio's ``<bc type="linear constraint">`` (FELinearConstraint: the parent DOF equals the sum
of its child DOFs times their values, plus an offset), as the ``[[linear_constraints]]`` of the
body its nodes are on (``constraints/linear.py``: a stiff penalty where FEBio eliminates the
parent DOF)."""

from __future__ import annotations

import numpy as np

from tissuesim.febio.model import FebModel, Load, _floats, _int_attr
from tissuesim.febio.xml import Node

__all__ = ["read_linear_constraint", "read_constraint_set", "linear_constraint_tables"]

AXES = {"x": 0, "y": 1, "z": 2}


def _dof(model: FebModel, node: Node, p: dict) -> tuple[int, int]:
    """(node row, axis) of a <dof> and <node> pair."""
    if "dof" not in p or p["dof"].text.strip() not in AXES:
        raise node.error("needs a <dof> x, y or z")
    if "node" not in p:
        raise node.error("needs a <node> (a node id)")
    number = int(_floats(p["node"], 1)[0])
    if number not in model._node_index:
        raise p["node"].error(f"node id {number} is not defined in <Nodes>")
    return model._node_index[number], AXES[p["dof"].text.strip()]


def read_linear_constraint(model: FebModel, bc: Node) -> None:
    from tissuesim.febio.model import _children, _load

    if model.window is not None and model.steps > 1:
        raise bc.error("a linear constraint inside one <step> of several: give it in <Boundary>")
    for c in bc.children:
        if c.tag not in ("dof", "node", "offset", "child_dof"):
            raise c.error(f"this parameter of <{bc.tag}> is not supported by tissuesim")
    p = _children(Node(bc.tag, {}, bc.line, bc.source,
                       children=[c for c in bc.children if c.tag != "child_dof"]),
                  {"dof", "node", "offset"})  # fmt: skip
    parent = _dof(model, bc, p)
    offset = _load(model, p["offset"], 1) if "offset" in p else Load(np.zeros(1))
    children = []
    for child in (c for c in bc.children if c.tag == "child_dof"):
        q = _children(child, {"dof", "node", "value"})
        value = _load(model, q["value"], 1) if "value" in q else Load(np.ones(1))
        children.append((*_dof(model, child, q), value))
    if not children:
        raise bc.error("a linear constraint needs at least one <child_dof>")
    if _int_attr(bc, "lc", "a load curve id") is not None:
        raise bc.error("a load curve on a linear constraint itself")
    terms = [(*parent, Load(np.ones(1)))]
    terms += [(row, axis, Load(-v.value, v.curve, v.window)) for row, axis, v in children]
    model.linear_constraints.append(
        {"parent": parent, "terms": terms, "offset": offset, "node": bc,
         "name": bc.attrib.get("name")}
    )  # fmt: skip


def read_constraint_set(model: FebModel, node: Node) -> None:
    """<constraint type="linear constraint"> (FEBio's FELinearConstraintSet, augmented
    Lagrangian): each <linear_constraint> sum_i value_i u[node_i, bc_i] = rhs; FEBio's
    enforcement settings are a note (tissuesim holds it by its penalty)."""
    from tissuesim.febio.model import _load

    tuning = {"laugon", "tol", "penalty", "minaug", "maxaug"}
    rhs = Load(np.zeros(1))
    noted = []
    for c in node.children:
        if c.tag in tuning:
            noted.append(c.tag)
        elif c.tag == "rhs":
            rhs = _load(model, c, 1)
        elif c.tag == "linear_constraint":
            terms = []
            for n in c.children:
                axis = n.attrib.get("bc", "")
                number = _int_attr(n, "id", "a node id")
                if n.tag != "node" or axis not in AXES or number not in model._node_index:
                    raise n.error('expected <node id="n" bc="x|y|z">value</node> of a defined node')
                terms.append((model._node_index[number], AXES[axis], _load(model, n, 1)))
            terms = [t for t in terms if t[2].value[0] != 0.0 or t[2].curve is not None]
            if not terms:
                raise c.error("a linear constraint of no term")
            model.linear_constraints.append(
                {"parent": None, "terms": terms, "offset": rhs, "node": c,
                 "name": node.attrib.get("name") or None}
            )  # fmt: skip
        else:
            raise c.error("this parameter of a linear constraint set is not read by tissuesim")
    if noted:
        model.note(node, f"FEBio's augmented Lagrangian settings not used ({', '.join(noted)}): "
                   "tissuesim holds a linear constraint by a stiff penalty")  # fmt: skip


def linear_constraint_tables(model: FebModel, body: dict, local, times) -> list[dict]:
    """The body's [[linear_constraints]]: u_parent - sum_j value_j u_child_j = offset, each
    coefficient and the offset an expression of t (``times(load)``); a constraint whose
    nodes are on two bodies, or on none of this body's elements, is refused / skipped."""
    out = []
    used = np.unique(body["cells"])
    for c in model.linear_constraints:
        rows = [row for row, _, _ in c["terms"]]
        inside = np.isin(rows, used)
        if not inside.any():
            continue
        if not inside.all():
            raise c["node"].error(
                "a linear constraint between nodes of two bodies (or of no element): "
                "tissuesim's linear constraints hold within one body"
            )
        if body.get("rigid") is not None:
            raise c["node"].error("a linear constraint on a rigid body's nodes")
        terms = [[int(local[row]), axis, times(value)] for row, axis, value in c["terms"]]
        table = {"terms": terms, "offset": times(c["offset"])}
        if c["name"]:
            table["name"] = c["name"]
        out.append(table)
    return out
