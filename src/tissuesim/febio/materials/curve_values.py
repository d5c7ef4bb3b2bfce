"""Material parameters that follow a load curve (``<T0 lc="1">0.5</T0>``: FEBio's value times
the curve at the current time) or a map (``<F0 type="map">name</F0>``: a value per element from
``<MeshData>``). The material section is read before ``<LoadData>`` and ``<MeshData>``, so the
reader keeps a ``CurveValue`` / ``MapValue`` in the law's parameters, and the scene writer
turns them into an expression of t or a list per element of the body
(``resolve_curve_values``) once they are known."""

from __future__ import annotations

from dataclasses import dataclass

from tissuesim.febio.model import FebModel, _floats, _int_attr, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["CurveValue", "MapValue", "curve_value", "resolve_curve_values", "checked_values"]


@dataclass(frozen=True)
class CurveValue:
    """value * curve(t), the curve a <load_controller> / <loadcurve> id; ``node`` for errors."""

    value: float
    curve: int
    node: Node


@dataclass(frozen=True)
class MapValue:
    """A value per element from the ``<ElementData name=...>`` map ``name``; ``shape`` each
    element's (() a number, (3, 3) a tensor); ``default`` the check's stand-in."""

    name: str
    shape: tuple
    default: object
    node: Node


def _map(value: MapValue, model: FebModel, parts: list[str] | None) -> object:
    import numpy as np

    if value.name not in model.element_maps:
        raise value.node.error(f"map {value.name!r}: no <ElementData name={value.name!r}> in "
                               "<MeshData>")  # fmt: skip
    data, values = model.element_maps[value.name]
    rows = []
    for part in parts or ():
        for row in range(len(model.parts[part][1])):
            if (part, row) not in values:
                raise data.error(f"map {value.name!r} has no value for element {row + 1} of "
                                 f"part {part!r}")  # fmt: skip
            rows.append(np.reshape(values[(part, row)], value.shape))
    rows = np.array(rows)
    if len(rows) and np.allclose(rows, rows[0], rtol=0.0, atol=0.0):
        return rows[0].tolist()
    return rows.tolist()


def curve_value(p: Node) -> CurveValue:
    """``<T0 lc="1">0.5</T0>``: the value times load curve 1."""
    if p.children or p.attrib.get("type") not in (None, "const"):
        raise _unsupported(p, "a material parameter that is a field or a table")
    curve = _int_attr(p, "lc", "a load curve id (a <load_controller>'s id)")
    return CurveValue(float(_floats(p, 1)[0]), curve, p)


def _resolve(value: object, model: FebModel | None, parts: list[str] | None = None) -> object:
    from tissuesim.febio.curves import curve_expression

    if isinstance(value, CurveValue) and model is None:
        return value.value
    if isinstance(value, MapValue):
        return value.default if model is None else _map(value, model, parts)
    if isinstance(value, CurveValue):
        if value.curve not in model.curves:
            raise value.node.error(
                f"load curve {value.curve} is used but not defined in <LoadData>"
            )
        return f"{value.value!r} * ({curve_expression(model.curves[value.curve])})"
    if isinstance(value, dict):
        return {k: _resolve(v, model, parts) for k, v in value.items()}
    if isinstance(value, list):
        return [_resolve(v, model, parts) for v in value]
    return value


def resolve_curve_values(params: dict, model: FebModel, parts: list[str] | None = None) -> dict:
    """A law's parameters (its components' and wrapped laws' too) with each ``CurveValue`` as
    an expression of t and each ``MapValue`` as the values of the body's elements (its
    ``parts`` in order)."""
    return _resolve(params, model, parts)


def checked_values(params: dict) -> dict:
    """The parameters with each ``CurveValue`` as its value and each ``MapValue`` as its stand-in
    (the reader's check of the law, before the curves and maps are read)."""
    return _resolve(params, None)
