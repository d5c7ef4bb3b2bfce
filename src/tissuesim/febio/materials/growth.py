"""FEBio's ``kinematic growth`` material (``FEKinematicGrowth``): an ``<elastic>`` law (any
coupled law tissuesim reads) and a ``<growth>`` tensor, ``volume growth``, ``area growth``,
``fiber growth`` (``<multiplier>``) or ``general growth`` (``<iso>``, ``<ani>``), each
multiplier a number or a value with ``lc`` (times its load curve), and the growth's ``<fiber>``
(``type="vector"`` or ``"angles"``; FEBio's default (1, 0, 0)). Read as tissuesim's
``kinematic_growth`` (``materials/active/kinematic_growth.py``)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tissuesim.febio.materials.axes import Orientation, _direction
from tissuesim.febio.materials.curve_values import checked_values, curve_value
from tissuesim.febio.model import FebModel, _floats, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["GROWTHS", "kinematic_growth"]

#: FEBio's growth tensors -> (tissuesim's growth, their multipliers)
GROWTHS = {
    "volume growth": ("volume", ("multiplier",)),
    "area growth": ("area", ("multiplier",)),
    "fiber growth": ("fiber", ("multiplier",)),
    "general growth": ("general", ("iso", "ani")),
}


def _growth(g: Node) -> dict:
    kind = g.attrib.get("type", "")
    if kind not in GROWTHS:
        raise g.error(f"growth type {kind!r} is not supported by tissuesim; it reads "
                      f"{', '.join(repr(k) for k in GROWTHS)}")  # fmt: skip
    name, takes = GROWTHS[kind]
    out: dict = {"growth": name}
    _once(g)
    for p in g.children:
        if p.tag == "fiber":
            how = p.attrib.get("type", "vector")
            if how not in ("vector", "angles"):
                raise _unsupported(p, f'a growth <fiber type="{how}"> (tissuesim reads "vector" '
                                   'and "angles")')  # fmt: skip
            o = Orientation("fiber")
            _direction(o, p, kind)
            out["fiber"] = (np.asarray(o.fiber) / np.linalg.norm(o.fiber)).tolist()
            continue
        if p.tag not in takes:
            raise p.error(f"parameter {p.tag!r} of {kind!r}: it takes {', '.join(takes)}, fiber")
        if "lc" in p.attrib:
            out[p.tag] = curve_value(p)
            continue
        if p.children or p.attrib.get("type") not in (None, "const"):
            raise _unsupported(p, "a growth parameter that is a field or a table")
        out[p.tag] = float(_floats(p, 1)[0])
    return out


def kinematic_growth(model: FebModel, mat: Node, law: Callable) -> tuple:
    """(model name, parameters, density, FEBio type, the elastic law's Orientation); ``law``
    reads the ``<elastic>`` (``reading._law``)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    kind = mat.attrib.get("type", "")
    parts = _once(mat)
    for p in mat.children:
        if p.tag not in ("elastic", "growth", "density"):
            raise _unsupported(p, f"this child of a {kind!r} material is not read by tissuesim "
                               "(it takes <elastic>, <growth>, <density>)")  # fmt: skip
    if "elastic" not in parts or "growth" not in parts:
        raise mat.error(f"a {kind!r} material needs an <elastic> law and a <growth>")
    base, base_params, density, base_kind, orientation = law(model, parts["elastic"], top=False)
    if "density" in parts:
        density = float(_floats(parts["density"], 1)[0])
        if not density > 0.0:
            raise parts["density"].error(f"density {density:g}: a density must be > 0")
    params = {"elastic": {"model": base, **base_params}, **_growth(parts["growth"])}
    try:
        make_material("kinematic_growth", **checked_values(params))
    except TissueSimError as exc:
        raise mat.error(f"material {kind!r}: {exc}") from None
    return ("kinematic_growth", params, density, kind, orientation)
