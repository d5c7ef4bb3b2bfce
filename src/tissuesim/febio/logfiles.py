"""FEBio's ``<Output><logfile>`` requests: node_data and element_data become tables a run
writes (``io/logfiles.py``; ``convert`` writes them as ``[[logfiles]]``), with the variables
tissuesim has; FEBio's other variables are named in one note per request, and
rigid_body_data / rigid_connector_data are refused (a rigid body's force and moment are in
forces.csv)."""

from __future__ import annotations

from pathlib import PurePosixPath, PureWindowsPath

import numpy as np

from tissuesim.febio.model import FebModel, _ints, _unsupported
from tissuesim.febio.xml import Node
from tissuesim.io.logfiles import KINDS

__all__ = ["read_logfile", "TABLE_LAYOUT", "logfile_tables", "cell_rows"]

#: attributes that shape FEBio's text file; tissuesim writes CSV (a note when given)
TABLE_LAYOUT = ("delim", "format", "comments")
#: the attribute naming a set (FEBio 2.5 and later; before, "set" and "elset")
SET_ATTRIBUTES = {"node_data": ("node_set", "set"), "element_data": ("elem_set", "elset")}


def read_logfile(model: FebModel, node: Node) -> None:
    """<logfile>: each node_data / element_data request kept in ``model.logfiles``."""
    if node.attrib.get("file") is not None:
        model.note(node, f"FEBio's log file {node.attrib['file']!r} is not written: tissuesim "
                   "writes summary.json, and each data request as a CSV table")  # fmt: skip
    for c in node.children:
        if c.tag == "rigid_connector_data":
            raise c.error(
                f"{c.tag}: tissuesim runs no rigid connectors, so there is none to log "
                "(remove the request to run)"
            )
        if c.tag not in KINDS:
            raise _unsupported(c, "this logfile request is not supported by tissuesim")
        _request(model, c)


def _request(model: FebModel, node: Node) -> None:
    kind = node.tag
    text = node.attrib.get("data")
    if not text or not text.strip():
        raise node.error(f'<{kind}> needs data="..." (variables separated by ";")')
    names = [n.strip() for n in text.split(";") if n.strip()]
    known = [n for n in names if n in KINDS[kind]]
    unknown = [n for n in names if n not in KINDS[kind]]
    if unknown:
        kept = f"the table has {', '.join(known)}" if known else "the request is dropped"
        model.note(node, f"{kind} variables {', '.join(unknown)} not written ({kept}): "
                   f"tissuesim writes {', '.join(KINDS[kind])}")  # fmt: skip
    layout = [a for a in TABLE_LAYOUT if node.attrib.get(a) is not None]
    if node.attrib.get("delim") in (",", None) and layout == ["delim"]:
        layout = []
    if layout:
        model.note(node, f"FEBio's table layout ({', '.join(layout)}) not used: tissuesim "
                   "writes comma-separated tables")  # fmt: skip
    items = _rigid_items(model, node) if kind == "rigid_body_data" else _items(model, node, kind)
    file = node.attrib.get("file")
    if file is not None:
        file = PureWindowsPath(PurePosixPath(file).name).name  # FEBio's path: the model's
    if known:
        model.logfiles.append(
            {"kind": kind, "data": known, "items": items, "file": file, "node": node}
        )


def _rigid_items(model: FebModel, node: Node) -> list[str] | None:
    """A rigid_body_data request's rigid bodies (material names) from its material ids; None
    for all."""
    if not node.text.strip():
        return None
    names = []
    for i in _id_ranges(node):
        spec = model.materials.get(f"#{i}")
        if spec is None or spec[3] != "rigid body":
            raise node.error(f"material id {i} is not a 'rigid body' material of this model")
        names.append(next(k for k, v in model.materials.items()
                          if v is spec and not k.startswith("#")))  # fmt: skip
    return names


def _items(model: FebModel, node: Node, kind: str):
    """The request's nodes (rows of model.nodes) or elements ((part, row) pairs), in the
    order given; None for all."""
    for attribute in SET_ATTRIBUTES[kind]:
        name = node.attrib.get(attribute)
        if name is None:
            continue
        if kind == "node_data":
            if name not in model.node_sets:
                raise node.error(f'{attribute}="{name}": no NodeSet of that name')
            return np.asarray(model.node_sets[name], dtype=np.int64)
        if name not in model.element_sets:
            raise node.error(f'{attribute}="{name}": no ElementSet of that name')
        return list(model.element_sets[name][0])
    if not node.text.strip():
        return None
    ids = _id_ranges(node)
    if kind == "node_data":
        missing = [i for i in ids if i not in model._node_index]
        if missing:
            raise node.error(f"node id {missing[0]} is not defined in <Nodes>")
        return np.array([model._node_index[i] for i in ids], dtype=np.int64)
    missing = [i for i in ids if i not in model._element_index]
    if missing:
        raise node.error(f"element id {missing[0]} is not defined in <Elements>")
    return [model._element_index[i] for i in ids]


def _id_ranges(node: Node) -> list[int]:
    """FEBio's item list: ids and ranges ``a:b`` or ``a:b:step``, separated by commas."""
    ids: list[int] = []
    for part in node.text.split(","):
        part = part.strip()
        if ":" not in part:
            ids += _ints(node, part)
            continue
        bounds = _ints(node, part.replace(":", ","))
        if len(bounds) not in (2, 3) or (len(bounds) == 3 and bounds[2] < 1):
            raise node.error(f"expected a range a:b or a:b:step, got {part!r}")
        step = bounds[2] if len(bounds) == 3 else 1
        ids += list(range(bounds[0], bounds[1] + 1, step))
    return ids


def _material_id(model: FebModel, name: str) -> int:
    spec = model.materials[name]
    return next(int(k[1:]) for k, v in model.materials.items() if v is spec and k.startswith("#"))


def _rigid_table(model: FebModel, request: dict, n: int, rigid: dict[str, str]) -> dict:
    """A rigid_body_data request as a [[logfiles]] table: the scene's names of its rigid
    bodies (``rigid``: material -> scene name) and their FEBio material ids."""
    materials = request["items"] if request["items"] is not None else list(rigid)
    table = {"kind": "rigid_body_data", "data": list(request["data"])}
    table["bodies"] = [rigid[m] for m in materials]
    table["ids"] = [_material_id(model, m) for m in materials]
    table["file"] = request["file"] or f"rigid_body_data_{n}.csv"
    return table


def logfile_tables(
    model: FebModel, bodies: list[dict], names: list[str], rigid: dict[str, str] | None = None
) -> list[dict]:
    """The <logfile> requests as [[logfiles]] tables: per body the rows of its mesh and their
    FEBio ids; a request over several bodies is one table per body (``<file stem>_<body>``).
    A request without a file is written as ``<kind>_<n>.csv`` (n: its place among them)."""
    row_ids = np.full(len(model.nodes), -1, dtype=np.int64)  # -1: a node FEBio has not
    row_ids[list(model._node_index.values())] = list(model._node_index)  # (a shell's back)
    tables = []
    for n, request in enumerate(model.logfiles, start=1):
        kind, items = request["kind"], request["items"]
        if kind == "rigid_body_data":
            tables.append(_rigid_table(model, request, n, rigid or {}))
            continue
        per_body = []
        for name, body in zip(names, bodies, strict=True):
            if kind == "node_data":
                used = np.unique(body["cells"])
                local = np.full(len(model.nodes), -1)
                local[used] = np.arange(len(used))
                # FEBio's nodes only: a shell's back nodes (febio/shells.py) are tissuesim's
                rows = used[row_ids[used] >= 0] if items is None else items[local[items] >= 0]
                if len(rows):
                    per_body.append((name, "nodes", local[rows], row_ids[rows], len(used)))
                continue
            members = [(p, r) for p in body["parts"] for r in range(len(model.parts[p][1]))]
            members = members if items is None else [m for m in items if m[0] in body["parts"]]
            if members:
                cells = cell_rows(body, members, model)
                ids = np.array([model.parts[p][2][r] for p, r in members], dtype=np.int64)
                per_body.append((name, "elements", cells, ids, len(body["cells"])))
        file = request["file"] or f"{kind}_{n}.csv"
        stem, dot, suffix = file.rpartition(".")
        for name, key, rows, ids, everything in per_body:
            if len(per_body) > 1:
                file = f"{stem}_{name}.{suffix}" if dot else f"{suffix}_{name}"
            table = {"kind": kind, "data": list(request["data"])}
            if names != ["body"]:
                table["body"] = name
            whole = items is None and np.array_equal(rows, np.arange(everything))
            if not (whole and np.array_equal(ids, rows + 1)):  # else: all rows, ids = rows + 1
                table.update({key: rows.tolist(), "ids": ids.tolist()})
            tables.append({**table, "file": file})
    return tables


def cell_rows(body: dict, members: list, model: FebModel) -> np.ndarray:
    """The rows in a body's cells of (part, row) members (its parts' cells in turn)."""
    offsets, start = {}, 0
    for p in body["parts"]:
        offsets[p] = start
        start += len(model.parts[p][1])
    return np.array([offsets[p] + r for p, r in members if p in offsets], dtype=np.int64)
