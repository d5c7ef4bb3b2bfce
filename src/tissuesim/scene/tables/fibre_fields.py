"""Fibre directions of a FEM body's [material] given per element by the mesh: a named cell
data array of the mesh file (``fiber = { cell_data = "fiber" }``) or expressions of the rest
coordinates (``fiber = ["-y", "x", "0"]``, evaluated at each cell's centroid). Plain vectors
and lists of vectors pass through unchanged (the laws check them)."""

from __future__ import annotations

import os

import numpy as np

from tissuesim.errors import SceneError
from tissuesim.scene.expressions import compile_expression
from tissuesim.validate import short

__all__ = ["DIRECTION_KEYS", "resolve_directions"]

#: the keys of the fibre laws that take directions (FEBio's fiber and mat_axis)
DIRECTION_KEYS = ("fiber", "mat_axis_a", "mat_axis_d")


def resolve_directions(table: dict, mesh, where: str) -> dict:
    """``table`` (a material table, its model popped or not) with every direction key given as
    a cell data name or as expressions replaced by an (m, d) array, one row per cell of
    ``mesh`` (None: a body without a FEM mesh, which refuses both forms); the ``elastic``
    table of a viscoelastic law and the ``components`` tables of a solid mixture too."""
    out = dict(table)
    if isinstance(out.get("elastic"), dict):
        out["elastic"] = resolve_directions(out["elastic"], mesh, f"{where} elastic")
    if isinstance(out.get("components"), list):
        out["components"] = [
            resolve_directions(c, mesh, f"{where} components[{i}]") if isinstance(c, dict) else c
            for i, c in enumerate(out["components"])
        ]
    for key in DIRECTION_KEYS:
        value = out.get(key)
        if isinstance(value, dict):
            out[key] = _cell_data(value, mesh, f"{where} {key}")
        elif isinstance(value, list) and any(isinstance(v, str) for v in value):
            out[key] = _expressions(value, mesh, f"{where} {key}")
        elif isinstance(value, list) and mesh is not None:
            _check_vectors(value, mesh, f"{where} {key}")
    return out


def _check_vectors(value: list, mesh, where: str) -> None:
    """A direction given as numbers: a vector of the body's dimension (a 2-vector on a 3D
    body lost its third component) or one per cell (a list of the wrong length is said so,
    before the law reads it as per-cell axes that may look parallel)."""
    per_cell = bool(value) and all(isinstance(v, list) for v in value)
    rows = value if per_cell else [value]
    if per_cell and len(rows) not in (1, mesh.n_cells):
        raise SceneError(
            f"{where}: {len(rows)} vectors given, read as one per cell, but the body has "
            f"{mesh.n_cells} cells: give one per cell or one vector [x, y, z] for the whole body"
        )
    if mesh.dim == 3 and any(isinstance(r, list) and len(r) == 2 for r in rows):
        raise SceneError(f"{where}: {short(value)} has 2 components on a 3D body; give [x, y, z]")


def _need_mesh(mesh, where: str, form: str) -> None:
    if mesh is None:
        raise SceneError(f"{where}: directions {form} need a FEM body's mesh")


def _expressions(value: list, mesh, where: str) -> np.ndarray:
    _need_mesh(mesh, where, "as expressions")
    d = mesh.dim
    if len(value) != d:
        raise SceneError(
            f"{where}: expected {d} expressions of x, y, z (one per axis), got {short(value)}"
        )
    centroids = mesh.points[mesh.cells].mean(axis=1)
    columns = []
    for i, text in enumerate(value):
        if isinstance(text, str) and "t" in _names(text):
            raise SceneError(
                f"{where}[{i}]: {text!r} uses t; fibre directions are set once, on the rest "
                "coordinates x, y, z"
            )
        f = compile_expression(text, f"{where}[{i}]")
        columns.append(f(centroids, 0.0))
    return _checked(np.stack(columns, axis=1), where, "the expressions give")


def _cell_data(value: dict, mesh, where: str) -> np.ndarray:
    if set(value) != {"cell_data"} or not isinstance(value["cell_data"], str):
        raise SceneError(
            f'{where}: expected a vector, expressions or {{ cell_data = "name" }} (an array '
            f"of the mesh file), got {short(value)}"
        )
    _need_mesh(mesh, where, "from cell data")
    name = value["cell_data"]
    path = mesh.source
    if not os.path.isfile(path):
        raise SceneError(f"{where}: cell_data {name!r} needs a mesh read from a file")
    from tissuesim.mesh.io import _load

    m = _load(path)
    blocks = [i for i, b in enumerate(m.cells) if b.type == mesh.cell_type]
    data = (m.cell_data or {}).get(name)
    if data is None:
        have = sorted(k for k in (m.cell_data or {}) if not k.startswith("gmsh:"))
        raise SceneError(
            f"{where}: {path} has no cell data named {name!r} (it has {have or 'none'})"
        )
    rows = np.concatenate([np.asarray(data[i], dtype=float).reshape(len(m.cells[i]), -1)
                           for i in blocks])  # fmt: skip
    if rows.shape != (mesh.n_cells, mesh.dim) and rows.shape != (mesh.n_cells, 3):
        raise SceneError(
            f"{where}: cell data {name!r} has shape {rows.shape}; a direction per cell needs "
            f"({mesh.n_cells}, {mesh.dim})"
        )
    return _checked(rows, where, f"cell data {name!r} has")


def _checked(rows: np.ndarray, where: str, what: str) -> np.ndarray:
    norm = np.linalg.norm(rows, axis=1)
    bad = np.flatnonzero(~np.isfinite(norm) | (norm == 0.0))
    if len(bad):
        raise SceneError(
            f"{where}: {what} a zero or non-finite direction at cell {int(bad[0])} "
            f"({rows[bad[0]].tolist()})"
        )
    return rows


def _names(text: str) -> set[str]:
    import ast

    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, RecursionError, MemoryError, ValueError):
        return set()
    return {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
