"""FEBio's discrete springs: ``<DiscreteSet>`` (in <Mesh>: node pairs) and the ``<Discrete>``
section (a ``discrete_material`` per set: ``linear spring``, ``tension-only linear spring``,
``nonlinear spring``), as tissuesim's ``[[discrete_springs]]`` of a body
(``energies/node_springs.py``).

A spring whose end is a node of no element (FEBio lets a discrete element end at a loose
node) is kept where that node is fully clamped (x, y and z fixed, never prescribed): the
spring then ends at a fixed point (``anchors``); a loose end that moves is refused.
"""

from __future__ import annotations

import numpy as np

from tissuesim.febio.model import Curve, FebModel, _flag, _floats, _int_attr, _ints, _unsupported
from tissuesim.febio.xml import Node

__all__ = [
    "read_discrete_set", "read_discrete", "read_node_distance", "spring_tables", "SPRING_TYPES",
]  # fmt: skip

#: FEBio discrete material type -> tissuesim's spring law
SPRING_TYPES = {
    "linear spring": "linear",
    "tension-only linear spring": "tension_only",
    "nonlinear spring": "curve",
}
MEASURES = ("elongation", "strain", "stretch")


def read_discrete_set(model: FebModel, node: Node) -> None:
    """<DiscreteSet name=...>: <delem>a,b</delem> node pairs (FEBio node ids)."""
    from tissuesim.febio.model import _index

    name = node.attrib.get("name")
    if not name:
        raise node.error("a DiscreteSet needs a name")
    pairs = []
    for c in node.children:
        if c.tag != "delem":
            raise _unsupported(c, "expected <delem>a,b</delem> node pairs")
        ids = _ints(c)
        if len(ids) != 2 or ids[0] == ids[1]:
            raise c.error(f"a discrete element joins two different nodes, got {c.text!r}")
        pairs.append(_index(model, c, ids))
    if not pairs:
        raise node.error("a DiscreteSet needs at least one <delem>")
    model.discrete_sets[name] = (np.array(pairs, dtype=np.int64), node)


def read_discrete(model: FebModel, section: Node) -> None:
    """<Discrete>: discrete materials by id and name, and <discrete dmat=... discrete_set=...>
    giving a set its material."""
    materials: dict[str, dict] = {}
    for c in section.children:
        if c.tag == "discrete_material":
            law = _material(model, c)
            number = _int_attr(c, "id", "a discrete material id")
            for key in (str(number), c.attrib.get("name")):
                if key is not None:
                    materials[key] = law
        elif c.tag == "discrete":
            dmat = c.attrib.get("dmat")
            if dmat not in materials:
                raise c.error(f'dmat="{dmat}": no <discrete_material> with that id or name')
            name = c.attrib.get("discrete_set")
            if name not in model.discrete_sets:
                raise c.error(f"no DiscreteSet named {name!r}")
            if c.children:
                raise _unsupported(c.children[0], "parameters of <discrete>")
            model.springs.append({**materials[dmat], "set": name, "node": c})
        else:
            raise _unsupported(c, "expected <discrete_material> or <discrete>")


def read_node_distance(model: FebModel, c: Node) -> None:
    """<constraint type="node distance"> (FEDistanceConstraint) with laugon 0: the penalty
    force eps(t) (l - l0) between two nodes, l0 = target (relative 1: the rest distance plus
    target), eps the penalty times its curve: a linear spring of rest length l0 whose
    stiffness follows the curve. Augmented (laugon 1) is refused."""
    from tissuesim.febio.model import _index

    p = {k.tag: k for k in c.children}
    for tag in p:
        if tag not in ("laugon", "augtol", "penalty", "node", "minaug", "maxaug", "target",
                       "relative"):  # fmt: skip
            raise _unsupported(p[tag], "this parameter of a node distance constraint")
    if "laugon" in p and p["laugon"].text.strip().upper() not in ("0", "PENALTY", "FALSE"):
        raise p["laugon"].error(
            "an augmented node distance constraint: tissuesim runs its penalty form (laugon 0)"
        )
    if "node" not in p or "penalty" not in p:
        raise c.error("a node distance constraint needs <node>a,b</node> and a <penalty>")
    ids = _ints(p["node"])
    if len(ids) != 2 or ids[0] == ids[1]:
        raise p["node"].error(f"expected two different node ids, got {p['node'].text!r}")
    pairs = _index(model, p["node"], ids)[None, :]
    eps = float(_floats(p["penalty"], 1)[0])
    if not eps > 0:
        raise p["penalty"].error("the penalty must be > 0")
    name = f"{c.attrib.get('name') or 'node_distance'}"
    while name in model.discrete_sets:
        name += "_"
    model.discrete_sets[name] = (pairs, c)
    target = float(_floats(p["target"], 1)[0]) if "target" in p else 0.0
    relative = _flag(p["relative"]) if "relative" in p else True  # FEBio's default
    model.springs.append({
        "law": "linear", "stiffness": eps, "material": c, "set": name, "node": c,
        "target": target, "relative": relative,
        "curve": _int_attr(p["penalty"], "lc", "a load curve id"),
    })  # fmt: skip
    if any(t in p for t in ("augtol", "minaug", "maxaug")):
        model.note(c, "FEBio's augmentation settings not used: laugon 0, a penalty spring")


def _material(model: FebModel, node: Node) -> dict:
    kind = node.attrib.get("type", "")
    if kind not in SPRING_TYPES:
        raise node.error(
            f"discrete material type {kind!r} is not supported by tissuesim; it runs "
            f"{', '.join(repr(k) for k in SPRING_TYPES)}"
        )
    law = SPRING_TYPES[kind]
    p = {c.tag: c for c in node.children}
    if law != "curve":
        extra = [t for t in p if t != "E"]
        if extra or "E" not in p:
            raise node.error(f"a {kind!r} takes its stiffness <E> (N/m) only")
        E = float(_floats(p["E"], 1)[0])
        if not E > 0:
            raise p["E"].error("the spring stiffness E must be > 0")
        return {"law": law, "stiffness": E, "material": node}
    extra = [t for t in p if t not in ("scale", "measure", "force")]
    if extra:
        raise _unsupported(p[extra[0]], f"this parameter of a {kind!r}")
    if "force" not in p:
        raise node.error("a nonlinear spring needs its <force> curve")
    measure = p["measure"].text.strip().lower() if "measure" in p else "elongation"
    if measure not in MEASURES:
        raise p["measure"].error(f"measure {measure!r}: FEBio's are {', '.join(MEASURES)}")
    scale = float(_floats(p["scale"], 1)[0]) if "scale" in p else 1.0
    return {"law": law, "curve": _force_curve(model, p["force"]), "measure": measure,
            "scale": scale, "material": node}  # fmt: skip


def _force_curve(model: FebModel, node: Node):
    """<force type="point"> with <interpolate>, <extend>, <points> (a Curve), or FEBio 3's
    <force lc="n">scale</force> (the load curve n, resolved once <LoadData> is read)."""
    from tissuesim.febio.condition_sections import _load_data

    curve = _int_attr(node, "lc", "a load curve id")
    if curve is not None:
        return (curve, float(_floats(node, 1)[0]))
    kind = node.attrib.get("type", "point")
    if kind == "math":
        return _math_force(model, node)
    if kind != "point":
        raise node.error(f'force type "{kind}": tissuesim reads a "point" or "math" curve')
    holder = FebModel(source=model.source, version=model.version)
    _load_data(holder, Node("LoadData", {}, node.line, node.source, children=[
        Node("load_controller", {}, node.line, node.source, children=node.children)]))  # fmt: skip
    return holder.curves[1]


def _math_force(model: FebModel, node: Node) -> str:
    """<force type="math"><math>fem.a*(exp(fem.b*x)-1)</math>: the expression of the measure
    x as tissuesim reads it (``^`` a power; FEBio's global variables ``fem.name``, from
    <Globals><Variables>, by their values)."""
    import re

    from tissuesim.energies.node_springs import ExpressionForce
    from tissuesim.errors import InputError

    math = node.find("math")
    if math is None or not (math.text or "").strip():
        raise node.error('a force of type "math" needs its <math> expression of x')

    def value(match: re.Match) -> str:
        name = match.group(1)
        if name not in model.variables:
            raise math.error(f"fem.{name}: no <var name={name!r}> in <Globals><Variables>")
        return f"({model.variables[name]!r})"

    text = re.sub(r"\bfem\.(\w+)", value, math.text.strip()).replace("^", "**")
    try:
        ExpressionForce(text, "force")
    except InputError as exc:
        raise math.error(f"{exc} (read as {text!r})") from None
    return text


def _curve(model: FebModel, spring: dict) -> tuple[Curve, float]:
    curve = spring["curve"]
    if isinstance(curve, Curve):
        return curve, 1.0
    number, factor = curve
    if number not in model.curves:
        raise spring["material"].error(f"load curve {number} is not defined in <LoadData>")
    return model.curves[number], factor


def _clamped(model: FebModel) -> np.ndarray:
    """The nodes every one of whose x, y, z a zero-displacement <bc> of the whole run holds."""
    held = np.zeros((len(model.nodes), 3), dtype=bool)
    for nodes, comps, load, _, window in model.dirichlet:
        if load is None and window is None:
            held[np.ix_(model.node_sets[nodes], comps or [0, 1, 2])] = True
    return held.all(axis=1)


def spring_tables(model: FebModel, bodies: list[dict], j: int, local: np.ndarray) -> list:
    """The [[discrete_springs]] tables of body j (``local``: model node row -> the body's vertex;
    an end at a clamped loose node as an anchor point). A spring between two bodies, or to a
    loose node that is not clamped, is refused."""
    out: list = []
    if not model.springs:
        return out
    owner = np.full(len(model.nodes), -1)
    for k, other_body in enumerate(bodies):
        owner[np.unique(other_body["cells"])] = k
    clamped = _clamped(model)
    body = bodies[j]
    for spring in model.springs:
        pairs, _ = model.discrete_sets[spring["set"]]
        where = spring["node"]
        if np.any((owner[pairs] < 0).all(axis=1)):
            raise where.error(
                f"discrete set {spring['set']!r} has a spring between two nodes of no element"
            )
        on = (owner[pairs] == j).any(axis=1)
        if on.any():
            mine = pairs[on]
            other = owner[mine]
            if np.any((other >= 0) & (other != j)):
                raise where.error(
                    f"discrete set {spring['set']!r} joins two bodies: tissuesim's springs join "
                    "vertices of one body"
                )
            if body.get("rigid") is not None:
                raise where.error(f"discrete set {spring['set']!r} ends on a rigid body")
            loose = other < 0
            if np.any(loose & ~clamped[mine]):
                raise where.error(
                    f"discrete set {spring['set']!r} ends at a node of no element that is not "
                    "clamped: tissuesim's springs end at a body's vertex or a fixed point"
                )
            flip = loose[:, 0]  # the body's vertex first
            mine = np.where(flip[:, None], mine[:, ::-1], mine)
            loose = np.where(flip[:, None], loose[:, ::-1], loose)
            table: dict = {
                "name": spring["set"],
                "pairs": [[int(local[a]), int(local[b]) if not lo else -1]
                          for (a, b), lo in zip(mine, loose[:, 1], strict=True)],
            }  # fmt: skip
            if loose[:, 1].any():
                table["anchors"] = [model.nodes[b].tolist() for b in mine[:, 1]]
            if "target" in spring:  # a node distance constraint: rest length, scaled penalty
                rest = np.linalg.norm(model.nodes[mine[:, 0]] - model.nodes[mine[:, 1]], axis=1)
                length = spring["target"] + (rest if spring["relative"] else 0.0)
                table["rest_length"] = [float(v) for v in np.broadcast_to(length, rest.shape)]
                if spring["curve"] is not None:
                    from tissuesim.febio.curves import curve_expression

                    if spring["curve"] not in model.curves:
                        raise where.error(f"load curve {spring['curve']} is not defined")
                    table["stiffness_scale"] = curve_expression(model.curves[spring["curve"]])
            if spring["law"] == "curve" and isinstance(spring["curve"], str):
                table["force"] = spring["curve"]  # FEBio's math force: an expression of x
                table["measure"] = spring["measure"]
                table["scale"] = spring["scale"]
            elif spring["law"] == "curve":
                curve, factor = _curve(model, spring)
                table["force"] = {
                    "points": curve.points.tolist(),
                    "interpolate": curve.interpolate.lower(),
                    "extend": curve.extend.lower(),
                }
                table["measure"] = spring["measure"]
                table["scale"] = spring["scale"] * factor
            else:
                table["stiffness"] = spring["stiffness"]
                if spring["law"] == "tension_only":
                    table["tension_only"] = True
            out.append(table)
    return out
