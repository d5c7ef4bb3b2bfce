"""FEBio's rigid connectors (``<rigid_connector>`` in ``<Rigid>``) as tissuesim's joints and
springs between rigid bodies (``rigid/joints.py``; the scene's ``[[rigid_joints]]``):

    rigid joint, rigid spherical joint   spherical (``joint`` / ``joint_origin``)
    rigid revolute joint                 revolute (``rotation_axis``, ``transverse_axis``;
                                         ``prescribed_rotation`` with ``rotation``)
    rigid prismatic joint                prismatic (``translation_axis``, ``transverse_axis``;
                                         ``prescribed_translation`` with ``translation``)
    rigid cylindrical joint              cylindrical (``joint_axis``, ``transverse_axis``; both)
    rigid planar joint                   planar (``rotation_axis`` its normal)
    rigid spring                         a spring (``k``, ``insertion_a``, ``insertion_b``,
                                         ``free_length``)

A ``rigid joint`` or ``rigid spherical joint`` (whose constraint is FEBio's c = p_b - p_a)
keeps FEBio's enforcement as the joint's ``enforcement`` (``joints.Enforcement``): ``laugon``
PENALTY (0) / AUGLAG (1, FEBio's default) with the ``penalty`` (``force_penalty``) and the
augmentation rule, FEBio's ``Augment``: ``rigid joint`` its ``tolerance`` (default 0.01), no
limit on augmentations; ``rigid spherical joint`` ``tolerance``, ``gaptol`` (default 0, unused),
``minaug`` (0), ``maxaug`` (10), ``force_penalty`` (default 1). So its residual is what FEBio's
tolerance leaves (ri02: -2.8e-8 from FEBio's norm, -1.6e-3 held to 1e-9). LAGMULT (2),
``auto_penalty`` on, or the other joints (whose residuals are not FEBio's, so its penalties
would not mean the same): a note, and tissuesim holds the joint to 1e-9 of the model's size.
An applied force or moment on a joint, a prescribed rotation of a spherical or planar joint,
dampers and contractile forces are refused in one line."""

from __future__ import annotations

from tissuesim.febio.model import FebModel, Load, _flag, _floats, _int_attr, _once
from tissuesim.febio.xml import Node

__all__ = ["read_connector", "rigid_body_name", "CONNECTORS"]

#: FEBio connector type -> (tissuesim kind, FEBio's name of the axis, of the transverse axis)
CONNECTORS = {
    "rigid joint": ("spherical", None, None),
    "rigid spherical joint": ("spherical", None, None),
    "rigid revolute joint": ("revolute", "rotation_axis", "transverse_axis"),
    "rigid prismatic joint": ("prismatic", "translation_axis", "transverse_axis"),
    "rigid cylindrical joint": ("cylindrical", "joint_axis", "transverse_axis"),
    "rigid planar joint": ("planar", "rotation_axis", "translation_axis_1"),
}
TUNING = {
    "laugon", "tolerance", "gaptol", "angtol", "force_penalty", "moment_penalty", "penalty",
    "force_damping", "moment_damping", "minaug", "maxaug", "auto_penalty",
}  # fmt: skip
#: an applied load on the joint: refused unless zero
LOADS = ("force", "moment", "moment_x", "moment_y", "moment_z", "torsion_stiffness")


def _named(model: FebModel, key: str) -> str:
    """The material's name for an id key (materials are listed under both)."""
    spec = model.materials[key]
    return next(k for k, v in model.materials.items() if v is spec and not k.startswith("#"))


def rigid_body_name(model: FebModel, rb: Node) -> str:
    """The rigid body material an element's text names (its name or id)."""
    name = rb.text.strip()
    for key in (name, f"#{name}"):
        spec = model.materials.get(key)
        if spec is not None and spec[3] == "rigid body":
            return key if not key.startswith("#") else _named(model, key)
    raise rb.error(f"<rb>{name}</rb> is not a 'rigid body' material of this model")


def _body(model: FebModel, node: Node) -> str:
    return rigid_body_name(model, node)


def _value(model: FebModel, node: Node) -> Load:
    curve = _int_attr(node, "lc", "a load curve id (a <load_controller>'s id)")
    return Load(_floats(node, 1), curve, model.window)


def read_connector(model: FebModel, c: Node, kind: str) -> None:
    """One <rigid_connector> into ``model.rigid_connectors``."""
    p = _once(c)
    if kind == "rigid spring":
        _spring(model, c, p)
        return
    if kind not in CONNECTORS:
        raise c.error(
            f"rigid connector {kind!r} is not supported by tissuesim; it runs "
            f"{', '.join(repr(k) for k in [*CONNECTORS, 'rigid spring'])}"
        )
    joint, axis_key, transverse_key = CONNECTORS[kind]
    for key in ("body_a", "body_b"):
        if key not in p:
            raise c.error(f"{kind} needs <{key}>")
    origin_key = "joint" if kind == "rigid joint" else "joint_origin"
    if origin_key not in p:
        raise c.error(f"{kind} needs <{origin_key}>")
    entry = {
        "kind": joint,
        "a": _body(model, p["body_a"]),
        "b": _body(model, p["body_b"]),
        "origin": _floats(p[origin_key], 3).tolist(),
        "name": c.attrib.get("name"),
    }
    if axis_key is not None:
        if axis_key not in p:
            raise c.error(f"{kind} needs <{axis_key}>")
        entry["axis"] = _floats(p[axis_key], 3).tolist()
        if transverse_key in p:
            entry["transverse"] = _floats(p[transverse_key], 3).tolist()
    tuning = []
    for key, node in p.items():
        if key in TUNING:
            tuning.append(key)
        elif key == "force" and joint == "prismatic" and float(_floats(node, 1)[0]) != 0.0:
            entry["force"] = (_value(model, node), node)  # rigid/conditions.py joint_forces
        elif key in LOADS:
            if float(_floats(node, 1)[0]) != 0.0:
                raise node.error(
                    f"<{key}> on a {kind}: tissuesim applies no force or moment through a "
                    "joint (put it on the rigid body, <rigid_load>)"
                )
        elif key in ("prescribed_rotation", "prescribed_translation"):
            if not _flag(node):
                continue
            what = key.removeprefix("prescribed_")
            if joint not in (("revolute", "cylindrical") if what == "rotation"
                             else ("prismatic", "cylindrical")):  # fmt: skip
                raise node.error(f"a prescribed {what} of a {kind} is not supported by tissuesim")
            if what not in p:
                raise node.error(f"<{key}>1 needs <{what}>, its value")
            entry[what] = _value(model, p[what])
        elif key in ("rotation", "translation"):
            continue  # read with its flag
        elif key not in ("body_a", "body_b", origin_key, axis_key, transverse_key):
            raise node.error(f"parameter <{key}> of a {kind} is not supported by tissuesim")
    enforcement = _enforcement(c, kind, p) if joint == "spherical" else None
    if enforcement is not None:
        entry["enforcement"] = enforcement
    elif tuning or joint == "spherical":
        model.note(c, f"FEBio's joint enforcement ({', '.join(tuning) or 'its defaults'}) not "
                   "used: tissuesim holds this joint to 1e-9 of the model's size")  # fmt: skip
    model.rigid_connectors.append(entry)


def _enforcement(c: Node, kind: str, p: dict) -> dict | None:
    """FEBio's enforcement of a (spherical) rigid joint as the joint's ``enforcement`` table;
    None where tissuesim holds it tight instead (LAGMULT, auto_penalty)."""
    method = (p["laugon"].text or "").strip().upper() if "laugon" in p else "AUGLAG"
    methods = {"0": False, "PENALTY": False, "1": True, "AUGLAG": True, "2": None,
               "LAGMULT": None}  # fmt: skip
    if method not in methods:
        raise p["laugon"].error(f"laugon = {method!r}: FEBio's methods are PENALTY (0), AUGLAG "
                                "(1) and LAGMULT (2)")  # fmt: skip
    if methods[method] is None or ("auto_penalty" in p and _flag(p["auto_penalty"])):
        return None

    def number(key: str, default: float) -> float:
        return float(_floats(p[key], 1)[0]) if key in p else default

    def count(key: str, default: int) -> int:
        x = number(key, default)
        if x < 0 or x != int(x):
            raise p[key].error(f"{key} = {x:g}: expected a count >= 0")
        return int(x)

    old = kind == "rigid joint"  # FERigidJoint: penalty, tolerance; no gaptol, min/maxaug
    key = "penalty" if old else "force_penalty"
    penalty = number(key, 0.0 if old else 1.0)
    if penalty <= 0:
        raise p.get(key, c).error(f"{kind}: FEBio's penalty and augmented Lagrangian need a "
                                  f"positive <{key}>, got {penalty:g}")  # fmt: skip
    tolerance = number("tolerance", 0.01 if old else 0.0)
    for name, x in (("tolerance", tolerance), ("gaptol", number("gaptol", 0.0))):
        if x < 0:
            raise p[name].error(f"{name} = {x:g}: expected a number >= 0")
    out: dict = {"penalty": penalty, "augmented": bool(methods[method]), "tolerance": tolerance}
    if not old:
        out.update(gap_tolerance=number("gaptol", 0.0), min_augmentations=count("minaug", 0),
                   max_augmentations=count("maxaug", 10))  # fmt: skip
    return out


def _spring(model: FebModel, c: Node, p: dict) -> None:
    for key in ("body_a", "body_b", "k", "insertion_a", "insertion_b"):
        if key not in p:
            raise c.error(f"a rigid spring needs <{key}>")
    for key in p:
        if key not in ("body_a", "body_b", "k", "insertion_a", "insertion_b", "free_length"):
            raise p[key].error(f"parameter <{key}> of a rigid spring is not supported by tissuesim")
    k = float(_floats(p["k"], 1)[0])
    if k <= 0:
        raise p["k"].error(f"k = {k:g}: a rigid spring's stiffness must be > 0")
    entry = {
        "kind": "spring",
        "a": _body(model, p["body_a"]),
        "b": _body(model, p["body_b"]),
        "point_a": _floats(p["insertion_a"], 3).tolist(),
        "point_b": _floats(p["insertion_b"], 3).tolist(),
        "stiffness": k,
        "name": c.attrib.get("name"),
    }
    if "free_length" in p:
        entry["free_length"] = float(_floats(p["free_length"], 1)[0])
    model.rigid_connectors.append(entry)
