"""The parts of FEBio's continuous fibre distribution (``continuous fiber distribution`` and its
uncoupled twin): ``<fibers type="fiber-exp-pow">`` (a fibre law, read as a mixture's
component), ``<distribution type="von-Mises-3d">`` and ``<scheme type="fibers-3d-gkt">`` (a
type and its numbers), as the tables of tissuesim's ``continuous_fiber_distribution``."""

from __future__ import annotations

from collections.abc import Callable

from tissuesim.febio.model import FebModel, _floats, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["PARTS", "read_part"]

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
