"""Material parameters that follow a load curve (``<T0 lc="1">0.5</T0>``: FEBio's value times
the curve at the current time). The material section is read before ``<LoadData>``, so the
reader keeps a ``CurveValue`` in the law's parameters, and the scene writer turns it into an
expression of t (``resolve_curve_values``) once the curves are known."""

from __future__ import annotations

from dataclasses import dataclass

from tissuesim.febio.model import FebModel, _floats, _int_attr, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["CurveValue", "curve_value", "resolve_curve_values", "checked_values"]


@dataclass(frozen=True)
class CurveValue:
    """value * curve(t), the curve a <load_controller> / <loadcurve> id; ``node`` for errors."""

    value: float
    curve: int
    node: Node


def curve_value(p: Node) -> CurveValue:
    """``<T0 lc="1">0.5</T0>``: the value times load curve 1."""
    if p.children or p.attrib.get("type") not in (None, "const"):
        raise _unsupported(p, "a material parameter that is a field or a table")
    curve = _int_attr(p, "lc", "a load curve id (a <load_controller>'s id)")
    return CurveValue(float(_floats(p, 1)[0]), curve, p)


def _resolve(value: object, model: FebModel | None) -> object:
    from tissuesim.febio.curves import curve_expression

    if isinstance(value, CurveValue) and model is None:
        return value.value
    if isinstance(value, CurveValue):
        if value.curve not in model.curves:
            raise value.node.error(
                f"load curve {value.curve} is used but not defined in <LoadData>"
            )
        return f"{value.value!r} * ({curve_expression(model.curves[value.curve])})"
    if isinstance(value, dict):
        return {k: _resolve(v, model) for k, v in value.items()}
    if isinstance(value, list):
        return [_resolve(v, model) for v in value]
    return value


def resolve_curve_values(params: dict, model: FebModel) -> dict:
    """A law's parameters (its components' and wrapped laws' too) with each ``CurveValue`` as
    an expression of t."""
    return _resolve(params, model)


def checked_values(params: dict) -> dict:
    """The parameters with each ``CurveValue`` as its value (the reader's check of the law,
    before the curves are read)."""
    return _resolve(params, None)
