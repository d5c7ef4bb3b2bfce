"""``[[logfiles]]``: FEBio's log tables written by a run (``Simulation.add_logfile``,
``io/logfiles.py``), in every scene with a FEM body; ``convert`` writes one per FEBio
``<logfile>`` request.

    [[logfiles]]
    kind = "node_data"          # or "element_data", "rigid_body_data"
    data = ["ux", "uy", "uz"]   # FEBio's variable names
    body = "body"               # a FEM body; a one-body scene's is its body
    nodes = [4, 5, 6, 7]        # 0-based vertices of its mesh (element_data: elements = [...];
                                # rigid_body_data: bodies = ["platen"], no body)
    ids = [5, 6, 7, 8]          # the ids written in the table (default: the rows + 1)
    file = "top.csv"            # in the output directory (default "<kind>_<n>.csv")
"""

from __future__ import annotations

from tissuesim.errors import SceneError
from tissuesim.scene.common import _context, _table, _unknown
from tissuesim.validate import short

__all__ = ["LOGFILE_KEYS", "add_logfiles"]

LOGFILE_KEYS = ("kind", "data", "body", "nodes", "elements", "bodies", "ids", "file")


def add_logfiles(sim, data: dict, source: str, body: str | None = None) -> None:
    """Read the scene's [[logfiles]] into ``sim``; ``body``: the default body (a one-body
    scene's)."""
    for i, item in enumerate(_table(data, "logfiles", source, array=True), start=1):
        where = f"{source} logfiles[{i}]"
        _unknown(item, LOGFILE_KEYS, where)
        kind = item.get("kind")
        if kind == "rigid_body_data":
            _rigid(sim, item, where)
            continue
        rows = {"node_data": "nodes", "element_data": "elements"}.get(kind)
        other = {"nodes", "elements", "bodies"} - {rows}
        given = sorted(other & set(item))
        if rows is not None and given:
            raise SceneError(f"{where}: {given[0]} is not a key of a {kind} table; use {rows}")
        name = item.get("body", body)
        if name is not None and (not isinstance(name, str) or name not in sim.bodies):
            raise SceneError(
                f"{where} body: {short(name)} is not a body of this scene; bodies: "
                f"{', '.join(sim.bodies)}"
            )
        with _context(where):
            sim.add_logfile(
                kind,
                item.get("data"),
                body=name,
                items=item.get(rows) if rows else None,
                ids=item.get("ids"),
                file=item.get("file"),
            )


def _rigid(sim, item: dict, where: str) -> None:
    """A rigid_body_data table: ``bodies`` the rigid bodies' names (default all)."""
    given = sorted({"nodes", "elements", "body"} & set(item))
    if given:
        raise SceneError(f"{where}: {given[0]} is not a key of a rigid_body_data table; use bodies")
    names = item.get("bodies")
    items = None
    if names is not None:
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise SceneError(f"{where} bodies: expected a list of rigid body names")
        known = list(sim.rigid_bodies)
        unknown = [n for n in names if n not in known]
        if unknown:
            raise SceneError(
                f"{where} bodies: {short(unknown[0])} is not a rigid body of this scene; rigid "
                f"bodies: {', '.join(known) or 'none'}"
            )
        items = [known.index(n) for n in names]
    with _context(where):
        sim.add_logfile(
            "rigid_body_data", item.get("data"), items=items, ids=item.get("ids"),
            file=item.get("file"),
        )  # fmt: skip
