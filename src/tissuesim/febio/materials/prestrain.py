"""FEBio's ``prestrain elastic`` material (``FEPrestrainElastic``): an ``<elastic>`` law (any
law tissuesim reads) and a ``<prestrain>`` gradient, ``prestrain gradient`` (``<F0>`` nine
numbers row by row or ``type="map"``, ``<ramp>``) or ``in-situ stretch`` (``<stretch>`` a number
or ``type="map"``, ``<isochoric>``, along the elastic law's fibre). Read as tissuesim's
``prestrain_elastic`` (``materials/prestrain.py``). FEBio's prestrain constraint (its
``<Constraints>``, which updates the gradient) is not read here."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tissuesim.febio.materials.curve_values import MapValue, checked_values
from tissuesim.febio.model import FebModel, _floats, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["PRESTRAINS", "prestrain_elastic"]

#: FEBio's prestrain gradients -> (tissuesim's prestrain, parameter -> shape of one value)
PRESTRAINS = {
    "prestrain gradient": ("gradient", {"F0": (3, 3), "ramp": ()}),
    "in-situ stretch": ("in_situ_stretch", {"stretch": (), "isochoric": ()}),
}


def _prestrain(g: Node) -> dict:
    kind = g.attrib.get("type", "")
    if kind not in PRESTRAINS:
        raise g.error(f"prestrain type {kind!r} is not supported by tissuesim; it reads "
                      f"{', '.join(repr(k) for k in PRESTRAINS)}")  # fmt: skip
    name, takes = PRESTRAINS[kind]
    out: dict = {"prestrain": name}
    _once(g)
    for p in g.children:
        if p.tag not in takes:
            raise p.error(f"parameter {p.tag!r} of {kind!r}: it takes {', '.join(takes)}")
        shape = takes[p.tag]
        how = p.attrib.get("type")
        if how == "map" and p.tag in ("F0", "stretch"):
            default = np.eye(3).tolist() if shape else 1.0
            out[p.tag] = MapValue(p.text.strip(), shape, default, p)
            continue
        if p.children or "lc" in p.attrib or how not in (None, "const"):
            raise _unsupported(p, "a prestrain parameter that is a curve, a field or a table")
        if p.tag == "isochoric":
            out[p.tag] = bool(int(_floats(p, 1)[0]))
        elif shape:
            out[p.tag] = _floats(p, 9).reshape(3, 3).tolist()
        else:
            out[p.tag] = float(_floats(p, 1)[0])
    return out


def prestrain_elastic(model: FebModel, mat: Node, law: Callable) -> tuple:
    """(model name, parameters, density, FEBio type, the elastic law's Orientation); ``law``
    reads the ``<elastic>`` (``reading._law``)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    kind = mat.attrib.get("type", "")
    parts = _once(mat)
    for p in mat.children:
        if p.tag not in ("elastic", "prestrain", "density"):
            raise _unsupported(p, f"this child of a {kind!r} material is not read by tissuesim "
                               "(it takes <elastic>, <prestrain>, <density>)")  # fmt: skip
    if "elastic" not in parts:
        raise mat.error(f"a {kind!r} material needs an <elastic> law")
    base, base_params, density, base_kind, orientation = law(model, parts["elastic"], top=False)
    if "density" in parts:
        density = float(_floats(parts["density"], 1)[0])
        if not density > 0.0:
            raise parts["density"].error(f"density {density:g}: a density must be > 0")
    params = {"elastic": {"model": base, **base_params}}
    if "prestrain" in parts:  # FEBio: none is Fp = I
        params.update(_prestrain(parts["prestrain"]))
    try:
        make_material("prestrain_elastic", **checked_values(params))
    except TissueSimError as exc:
        raise mat.error(f"material {kind!r}: {exc}") from None
    return ("prestrain_elastic", params, density, kind, orientation)
