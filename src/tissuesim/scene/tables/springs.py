"""The ``[[discrete_springs]]`` table of a FEM body (top level in a one-body scene, inside each
``[[bodies]]`` entry): discrete springs between its vertices, or from a vertex to a fixed
point, as ``Simulation.add_springs`` makes them (``energies/node_springs.py``)::

    [[discrete_springs]]
    name = "ligament"            # its energy term (default "springs")
    pairs = [[0, 17], [4, -1]]   # vertex pairs of the body's mesh; -1: to the anchor point
    anchors = [[0, 0, 0], [0.1, 0, 0.2]]   # m, one per pair (read where the pair has -1)
    stiffness = 50.0             # N/m: a linear spring, f = E (l - L0)
    tension_only = false         # true: no force in compression
    # or a force curve instead of a stiffness (FEBio's nonlinear spring):
    # force = { points = [[-1, -1], [0, 0], [1, 2]], interpolate = "smooth", extend = "constant" }
    # force = "2 * (exp(50 * x) - 1)"   # or an expression of the measure x (FEBio's math force)
    # measure = "elongation"     # or "strain" (dl / L0), "stretch" (l / L0)
    # scale = 1.0                # the force is scale * F(measure), N
    rest_length = 0.0            # m: instead of the rest distance (FEBio's node distance)
    stiffness_scale = "min(t, 1)"   # the law times this expression of t

A force curve's ``interpolate`` is linear (default), step, smooth or smooth step and its
``extend`` constant (default) or extrapolate, with FEBio's point-curve definitions
(``febio/curves.py``); its energy is the curve's exact integral. An expression's energy is its
integral by composite Gauss-Legendre, its stiffness a complex step (``ExpressionForce``).

And ``[[linear_constraints]]``, sum_i c_i u[v_i, a_i] = offset over displacement components
of the body (``Simulation.add_linear_constraint``, ``constraints/linear.py``)::

    [[linear_constraints]]
    terms = [[5, 0, 1.0], [8, 0, "-1.0 * min(t, 1)"]]   # vertex, axis, coefficient (or of t)
    offset = 0.0              # m (a number or an expression of t)
    stiffness = 1e6           # N/m, the penalty (default 1e5 mu times the median edge)
    name = "tie_x"
"""

from __future__ import annotations

import re

import numpy as np

from tissuesim.errors import InputError, SceneError
from tissuesim.scene.common import _context, _unknown
from tissuesim.validate import short

__all__ = [
    "SPRING_KEYS", "LINEAR_CONSTRAINT_KEYS", "add_spring_tables", "add_linear_constraint_tables",
    "point_force_curve",
]  # fmt: skip

LINEAR_CONSTRAINT_KEYS = {"terms", "offset", "stiffness", "name"}
SPRING_KEYS = {"name", "pairs", "anchors", "stiffness", "tension_only", "force", "measure", "scale",
               "rest_length", "stiffness_scale"}  # fmt: skip
FORCE_KEYS = {"points", "interpolate", "extend"}
INTERPOLATE = {"linear": "LINEAR", "step": "STEP", "smooth": "SMOOTH", "smooth step": "SMOOTH STEP"}


def point_force_curve(table: dict, where: str):
    """A ``ForceCurve`` from ``{points, interpolate, extend}``: FEBio's point curve through
    the points, as polynomial pieces between them."""
    from tissuesim.energies.node_springs import ForceCurve
    from tissuesim.febio.curves import curve_expression
    from tissuesim.febio.model import Curve
    from tissuesim.scene.expressions import compile_expression

    if not isinstance(table, dict):
        raise SceneError(f"{where}: force must be a table {{ points = [[s, F], ...] }}")
    _unknown(table, FORCE_KEYS, where)
    try:
        points = np.asarray(table.get("points"), dtype=float)
    except (TypeError, ValueError):
        points = np.zeros((0,))
    if (
        points.ndim != 2
        or points.shape[1] != 2
        or len(points) < 2
        or not np.all(np.isfinite(points))
    ):
        raise SceneError(f"{where}: points must be at least two [s, F] pairs of numbers")
    if np.any(np.diff(points[:, 0]) <= 0):
        raise SceneError(f"{where}: the points' s must increase")
    interpolate = str(table.get("interpolate", "linear")).lower()
    extend = str(table.get("extend", "constant")).lower()
    if interpolate not in INTERPOLATE:
        raise SceneError(f"{where}: interpolate must be one of {sorted(INTERPOLATE)}")
    if extend not in ("constant", "extrapolate") or (
        extend == "extrapolate" and interpolate != "linear"
    ):
        raise SceneError(f"{where}: extend must be constant (or extrapolate, with linear)")
    text = curve_expression(Curve(points, INTERPOLATE[interpolate], extend.upper()))
    f = compile_expression(re.sub(r"\bt\b", "x", text), where)
    return ForceCurve.from_function(
        lambda s: f(np.stack([s, 0 * s, 0 * s], axis=1), 0.0), points[:, 0], extend=extend
    )


def _scale(entry: dict, where: str):
    """``stiffness_scale``: a number or an expression of t (None: 1)."""
    if "stiffness_scale" not in entry:
        return None
    value = _of_t(entry["stiffness_scale"], f"{where} stiffness_scale")
    return value if callable(value) else (lambda t, v=value: v)


def add_spring_tables(sim, body: str, entries: list, label) -> None:
    """Every [[discrete_springs]] table of ``body`` (``label(key, i)`` names it in errors)."""
    for i, entry in enumerate(entries, start=1):
        where = label("discrete_springs", i)
        if not isinstance(entry, dict):
            raise SceneError(f"{where}: expected a table")
        _unknown(entry, SPRING_KEYS, where)
        if "pairs" not in entry:
            raise SceneError(f"{where}: missing key 'pairs' (vertex pairs [[a, b], ...])")
        try:
            pairs = np.asarray(entry["pairs"])
        except ValueError:
            pairs = np.zeros((0,))
        if pairs.ndim != 2 or pairs.shape[1:] != (2,) or not np.issubdtype(pairs.dtype, np.integer):
            raise SceneError(f"{where}: pairs must be [[a, b], ...] integers, got {short(pairs)}")
        if ("stiffness" in entry) == ("force" in entry):
            raise SceneError(f"{where}: give a stiffness (N/m) or a force curve, one of them")
        curve = None
        if isinstance(entry.get("force"), str):  # an expression of the measure x
            from tissuesim.energies.node_springs import ExpressionForce

            try:
                curve = ExpressionForce(entry["force"], f"{where} force")
            except InputError as exc:
                raise SceneError(str(exc)) from None
        elif "force" in entry:
            curve = point_force_curve(entry["force"], f"{where} force")
        with _context(where):
            sim.add_springs(
                pairs,
                entry.get("stiffness"),
                tension_only=bool(entry.get("tension_only", False)),
                force=curve,
                measure=entry.get("measure", "elongation"),
                scale=float(entry.get("scale", 1.0)),
                anchors=entry.get("anchors"),
                rest_length=entry.get("rest_length"),
                stiffness_scale=_scale(entry, where),
                body=body,
                name=entry.get("name", "springs"),
            )


def _of_t(value, where: str):
    """A number, or a callable t -> float for an expression string of t."""
    from tissuesim.scene.common import of_time

    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    f = of_time([value], 1, where, "a coefficient")
    return lambda t: float(f(t)[0])


def add_linear_constraint_tables(sim, body: str, entries: list, label) -> None:
    """Every [[linear_constraints]] table of ``body``."""
    for i, entry in enumerate(entries, start=1):
        where = label("linear_constraints", i)
        if not isinstance(entry, dict):
            raise SceneError(f"{where}: expected a table")
        _unknown(entry, LINEAR_CONSTRAINT_KEYS, where)
        terms = entry.get("terms")
        if (
            not isinstance(terms, list)
            or not terms
            or not all(isinstance(t, list) and len(t) == 3 for t in terms)
        ):
            raise SceneError(f"{where}: terms must be [[vertex, axis, coefficient], ...]")
        terms = [(v, a, _of_t(c, f"{where} terms[{k}]")) for k, (v, a, c) in enumerate(terms)]
        with _context(where):
            sim.add_linear_constraint(
                terms,
                _of_t(entry.get("offset", 0.0), f"{where} offset"),
                stiffness=entry.get("stiffness"),
                body=body,
                name=entry.get("name"),
            )
