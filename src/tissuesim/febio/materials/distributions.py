"""The parts of FEBio's continuous fibre distribution (``continuous fiber distribution`` and its
uncoupled twin): ``<fibers type="fiber-exp-pow">`` (a fibre law, read as a mixture's
component), ``<distribution type="von-Mises-3d">`` and ``<scheme type="fibers-3d-gkt">`` (a
type and its numbers), as the tables of tissuesim's ``continuous_fiber_distribution``."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tissuesim.febio.materials.axes import axes_from
from tissuesim.febio.model import FebModel, _floats, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["PARTS", "read_part", "check_adaptive_axes"]

#: the children of a continuous fibre distribution that are tables
PARTS = ("fibers", "distribution", "scheme")


def read_part(model: FebModel, p: Node, law: Callable) -> dict:
    """A ``<fibers>``, ``<distribution>`` or ``<scheme>`` as a table {model, parameters};
    ``law``: the reader of a material element (``reading._law``), for the fibre law."""
    kind = p.attrib.get("type")
    if not kind:
        raise p.error(f'<{p.tag}> needs its type, e.g. type="fiber-exp-pow"')
    if p.tag == "fibers":
        name, params, _, _, _ = law(model, p, top=False, component=True, bulk=False)
        return {"model": name, **params}
    table: dict = {"model": kind}
    _once(p)
    for q in p.children:
        if q.children or "lc" in q.attrib or q.attrib.get("type") not in (None, "const"):
            raise _unsupported(q, f"a {p.tag} parameter that is a field, a curve or a table")
        values = _floats(q)
        table[q.tag] = values.tolist() if values.size > 1 else float(values[0])
    return table


def check_adaptive_axes(mat: Node, outer: tuple | None, parts: list, components: list) -> None:
    """Refuse, on its ``<solid>`` line, a mixture's continuous distribution summed by
    fibers-3d-gkt under a mat_axis (its own or the mixture's) other than the global axes: FEBio
    takes that scheme's points in the eigenvectors of the global C and reads them as local
    directions, so its stress is not the derivative of an energy of F
    (``ContinuousFiberDistribution``)."""
    solids = [c for c in mat.children if c.tag == "solid"]
    for node, orientation, table in zip(solids, parts, components, strict=True):
        scheme = table.get("scheme")
        name = str(scheme.get("model", "")) if isinstance(scheme, dict) else ""
        if name.strip().lower().replace("_", "-") != "fibers-3d-gkt":
            continue
        for axis in (getattr(orientation, "axis", None), outer):
            if axis is None:
                continue
            if axis[0] == "vector" and np.allclose(axes_from(axis[1], axis[2]), np.eye(3),
                                                   rtol=0.0, atol=1e-12):  # fmt: skip
                continue
            raise node.error(
                "a continuous fiber distribution with fibers-3d-gkt under a mat_axis other than "
                "the global axes: FEBio takes that scheme's points in the eigenvectors of the "
                "global C and reads them as local directions, so its stress is not the "
                "derivative of an energy of F, which tissuesim minimises (give global axes or "
                "fibers-2d-trapezoidal)"
            )
