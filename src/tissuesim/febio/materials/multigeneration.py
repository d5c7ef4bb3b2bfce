"""FEBio's ``multigeneration`` material (``FEElasticMultigeneration``): ``<generation>``s, each
a ``<start_time>`` and a ``<solid>`` (any law tissuesim reads without directions). Read as
tissuesim's ``multigeneration`` (``materials/multigeneration.py``)."""

from __future__ import annotations

from collections.abc import Callable

from tissuesim.febio.materials.curve_values import checked_values
from tissuesim.febio.model import FebModel, _floats, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["multigeneration"]


def multigeneration(model: FebModel, mat: Node, law: Callable) -> tuple:
    """(model name, parameters, density, FEBio type, None); ``law`` reads each ``<solid>``
    (``reading._law``)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    kind = mat.attrib.get("type", "")
    density, generations = 1.0, []
    for p in mat.children:
        if p.tag == "density":
            density = float(_floats(p, 1)[0])
            if not density > 0.0:
                raise p.error(f"density {density:g}: a density must be > 0")
            continue
        if p.tag != "generation":
            raise _unsupported(p, f"this child of a {kind!r} material is not read by tissuesim "
                               "(it takes <generation>, <density>)")  # fmt: skip
        parts = _once(p)
        if set(parts) - {"start_time", "solid"} or "solid" not in parts:
            raise p.error("a <generation> takes <start_time> and <solid>")
        name, params, _, solid_kind, orientation = law(model, parts["solid"], top=False)
        if orientation is not None:
            raise _unsupported(parts["solid"], f"a generation's {solid_kind!r} with directions")
        t = float(_floats(parts["start_time"], 1)[0]) if "start_time" in parts else 0.0
        generations.append({"start_time": t, "solid": {"model": name, **params}})
    if not generations:
        raise mat.error(f"a {kind!r} material needs a <generation>")
    params = {"generations": generations}
    try:
        make_material("multigeneration", **checked_values(params))
    except TissueSimError as exc:
        raise mat.error(f"material {kind!r}: {exc}") from None
    return ("multigeneration", params, density, kind, None)
