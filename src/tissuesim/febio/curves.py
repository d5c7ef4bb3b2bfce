"""FEBio load curves as tissuesim expressions of t, with FEBio's definitions
(``FECore/PointCurve``): LINEAR, STEP (the next point's value on each interval), SMOOTH
(the quadratic through three points on the end intervals, and between two such quadratics
linearly inside), SMOOTH STEP (f0 + (f1 - f0) w^3 (10 - 15 w + 6 w^2)); extend CONSTANT,
EXTRAPOLATE with LINEAR, REPEAT and REPEAT_OFFSET."""

from __future__ import annotations

from tissuesim.febio.model import Curve, FebModel, Load

__all__ = ["curve_expression", "load_expression"]


def _r(x: float) -> str:
    return repr(float(x))


def _lerp(t0: float, f0: float, t1: float, f1: float) -> str:
    return f"({_r(f0)} + ({_r(f1)} - {_r(f0)}) * (t - {_r(t0)}) / ({_r(t1)} - {_r(t0)}))"


def _qerp(t0: float, f0: float, t1: float, f1: float, t2: float, f2: float) -> str:
    """The quadratic through three points, Lagrange's form."""
    terms = []
    for (ti, fi), (ta, _), (tb, _) in (
        ((t0, f0), (t1, f1), (t2, f2)),
        ((t1, f1), (t0, f0), (t2, f2)),
        ((t2, f2), (t0, f0), (t1, f1)),
    ):
        terms.append(
            f"{_r(fi)} * (t - {_r(ta)}) * (t - {_r(tb)}) / "
            f"(({_r(ti)} - {_r(ta)}) * ({_r(ti)} - {_r(tb)}))"
        )
    return "(" + " + ".join(terms) + ")"


def _segment(curve: Curve, n: int) -> str:
    """The curve on the interval [t_{n-1}, t_n) (1 <= n <= N)."""
    p = curve.points
    (t0, f0), (t1, f1) = p[n - 1], p[n]
    if curve.interpolate == "LINEAR":
        return _lerp(t0, f0, t1, f1)
    if curve.interpolate == "STEP":
        return _r(f1)
    if curve.interpolate == "SMOOTH STEP":
        w = f"((t - {_r(t0)}) / ({_r(t1)} - {_r(t0)}))"
        return f"({_r(f0)} + ({_r(f1)} - {_r(f0)}) * {w}**3 * (10 - 15 * {w} + 6 * {w}**2))"
    size = len(p)  # SMOOTH
    if size == 2:
        return _lerp(t0, f0, t1, f1)
    if size == 3:
        return _qerp(*p[0], *p[1], *p[2])
    if n == 1:
        return _qerp(*p[0], *p[1], *p[2])
    if n == size - 1:
        return _qerp(*p[n - 2], *p[n - 1], *p[n])
    q1 = _qerp(*p[n - 2], *p[n - 1], *p[n])
    q2 = _qerp(*p[n - 1], *p[n], *p[n + 1])
    return f"({q1} + ({q2} - {q1}) * (t - {_r(t0)}) / ({_r(t1)} - {_r(t0)}))"


def curve_expression(curve: Curve) -> str:
    """The curve's value as an expression of t (nested ``where`` over its intervals); extend
    REPEAT / REPEAT_OFFSET as FEBio's PointCurve: t shifted by whole periods Dt = tN - t0
    into (t0, tN] (from above) or [t0, tN) (from below), REPEAT_OFFSET adding (fN - f0) per
    period."""
    if curve.extend in ("REPEAT", "REPEAT_OFFSET") and len(curve.points) > 1:
        import re

        t0, tn = float(curve.points[0, 0]), float(curve.points[-1, 0])
        dt = tn - t0
        tau = (f"where(t > {_r(tn)}, {_r(tn)} - ({_r(tn)} - t) % {_r(dt)}, "
               f"where(t < {_r(t0)}, {_r(t0)} + (t - {_r(t0)}) % {_r(dt)}, t))")  # fmt: skip
        inner = curve_expression(Curve(curve.points, curve.interpolate, "CONSTANT"))
        text = re.sub(r"\bt\b", f"({tau})", inner)
        if curve.extend == "REPEAT_OFFSET":
            jump = float(curve.points[-1, 1] - curve.points[0, 1])
            text = f"({text} + (t - ({tau})) / {_r(dt)} * {_r(jump)})"
        return text
    p = curve.points
    if len(p) == 1:
        return _r(p[0, 1])
    last = len(p) - 1
    if curve.extend == "EXTRAPOLATE":  # LINEAR only (the reader refuses the others)
        before, after = _lerp(*p[0], *p[1]), _lerp(*p[last - 1], *p[last])
    else:
        before, after = _r(p[0, 1]), _r(p[last, 1])
    text = after
    for n in range(last, 0, -1):
        text = f"where(t < {_r(p[n, 0])}, {_segment(curve, n)}, {text})"
    return f"where(t <= {_r(p[0, 0])}, {before}, {text})"


def load_expression(load: Load, model: FebModel, k: int = 0, windowed: bool = True) -> str:
    """value[k] * curve(t) as an expression (a number string when there is no curve), times
    the indicator of its step's time window (``windowed``; a condition's ``active`` says it
    instead)."""
    value = float(load.value[k])
    if value == 0.0:
        return repr(value)
    text = repr(value)
    if load.curve is not None:
        text = f"{value!r} * ({curve_expression(model.curves[load.curve])})"
    if load.window is not None and windowed:
        t0, t1 = load.window
        on = f"(t > {t0!r})" if t1 == float("inf") else f"(t > {t0!r}) * (t <= {t1!r})"
        text = f"{text} * {on}"
    return text
