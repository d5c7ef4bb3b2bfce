"""The study's table: one row per run, assembled from the runs' own result files
(``runs/<run_id>.json``), written as ``runs.csv`` always and ``runs.parquet`` where pyarrow is
installed. Columns: run_id, index, status, error, wall_time_s, build_time_s (the scene
built), setup_time_s (the model set up), solve_time_s (the steps), steps,
newton_iterations, then each parameter by its key path (a vector as ``KEY[0]``, ``KEY[1]``,
...), then each force as ``<name>_x_N``, ``<name>_y_N``, ``<name>_z_N`` (as in forces.csv), then
``fields_write_s`` and ``fields_bytes`` when fields were saved."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

__all__ = ["read_results", "table_rows", "write_table", "BASE_COLUMNS"]

BASE_COLUMNS = (
    "run_id",
    "index",
    "status",
    "error",
    "wall_time_s",
    "build_time_s",
    "setup_time_s",
    "solve_time_s",
    "steps",
    "newton_iterations",
)


def read_results(directory: Path) -> list[dict[str, Any]]:
    """Every run's result file in ``directory/runs``, by index."""
    results = []
    for path in (directory / "runs").glob("r*.json"):
        results.append(json.loads(path.read_text(encoding="utf-8")))
    return sorted(results, key=lambda r: r["index"])


def table_rows(results: list[dict[str, Any]], keys: list[str]) -> list[dict[str, Any]]:
    """Flat rows (one per run) with the columns in the module's order; ``keys``: the
    parameters' key paths in the study's order."""
    forces: list[str] = []
    for r in results:
        forces += [n for n in r.get("forces", {}) if n not in forces]
    extra = [c for c in ("fields_write_s", "fields_bytes") if any(c in r for r in results)]
    rows = []
    for r in results:
        row = {c: r.get(c) for c in BASE_COLUMNS}
        row["error"] = row["error"] or None  # empty in the CSV, null in Parquet
        for key in keys:
            value = r["params"].get(key)
            if isinstance(value, list):
                row.update({f"{key}[{i}]": v for i, v in enumerate(value)})
            else:
                row[key] = value
        for name in forces:
            f = r.get("forces", {}).get(name) or [None, None, None]
            row.update({f"{name}_{a}_N": v for a, v in zip("xyz", f, strict=False)})
        row.update({c: r.get(c) for c in extra})
        rows.append(row)
    return rows


def write_table(directory: Path, rows: list[dict[str, Any]]) -> list[Path]:
    """``runs.csv`` (always) and ``runs.parquet`` (pyarrow installed), each atomically; the
    paths written."""
    from tissuesim.io.atomic import atomic_output, write_text_atomic

    columns: list[str] = []
    for row in rows:
        columns += [c for c in row if c not in columns]
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:  # floats as repr: the CSV reads back bit for bit
        writer.writerow({c: "" if row.get(c) is None else row[c] for c in columns})
    written = [write_text_atomic(directory / "runs.csv", buffer.getvalue())]
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    table = pa.Table.from_pylist([{c: row.get(c) for c in columns} for row in rows])
    with atomic_output(directory / "runs.parquet") as tmp:
        pq.write_table(table, tmp)
    written.append(directory / "runs.parquet")
    return written
