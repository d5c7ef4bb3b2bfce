"""``[[logfiles]]``: FEBio's log tables written by a run (``Simulation.add_logfile``,
``io/logfiles.py``), in every scene with a FEM body; ``convert`` writes one per FEBio
``<logfile>`` request.

    [[logfiles]]
    kind = "node_data"          # or "element_data"
    data = ["ux", "uy", "uz"]   # FEBio's variable names
    body = "body"               # a FEM body; a one-body scene's is its body
    nodes = [4, 5, 6, 7]        # 0-based vertices of its mesh (element_data: elements = [...])
    ids = [5, 6, 7, 8]          # the ids written in the table (default: the rows + 1)
    file = "top.csv"            # in the output directory (default "<kind>_<n>.csv")
"""

from __future__ import annotations

from tissuesim.errors import SceneError
from tissuesim.scene.common import _context, _table, _unknown
from tissuesim.validate import short

__all__ = ["LOGFILE_KEYS", "add_logfiles"]

LOGFILE_KEYS = ("kind", "data", "body", "nodes", "elements", "ids", "file")


def add_logfiles(sim, data: dict, source: str, body: str | None = None) -> None:
    """Read the scene's [[logfiles]] into ``sim``; ``body``: the default body (a one-body
    scene's)."""
    for i, item in enumerate(_table(data, "logfiles", source, array=True), start=1):
        where = f"{source} logfiles[{i}]"
        _unknown(item, LOGFILE_KEYS, where)
        kind = item.get("kind")
        rows = {"node_data": "nodes", "element_data": "elements"}.get(kind)
        other = {"nodes", "elements"} - {rows}
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
