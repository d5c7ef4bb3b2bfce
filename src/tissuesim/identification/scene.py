"""Identification from a scene file: its ``[identify]`` table names the parameters (scene keys
by their path, as ``tissuesim sweep`` names them), what is observed, and the measured data.

    [identify]
    steps = 10
    parameters = { "material.youngs_modulus" = [2e4, 1e3, 1e6] }  # initial[, low, high]
    observations = [
        { reaction = "platen", component = 2 },                   # N, as forces()["platen"][2]
        { displacement = [12, 40], component = 0, body = "liver" },  # m, one value per vertex
        { surface_points = [[0.01, 0.02, 0.03], ...] },  # m from the deformed surface, per point
        { contact_force = "probe", component = 2 },      # N, an obstacle's, as forces()["probe"]
    ]
    data = "measured.csv"   # a header row, then one row per step: a first column "step"
                            # (1, 2, ...), then one column per observed value; empty: not measured

``tissuesim identify SCENE --out DIR`` fits them (``fit.py``) and writes ``identify.json``
(parameters, standard errors, rms, runs) and ``fit.csv`` (measured and simulated per step).
"""

from __future__ import annotations

import copy
import csv
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError, SceneError
from tissuesim.identification.observations import (
    ContactForce,
    Displacement,
    Reaction,
    SurfaceDistance,
)

__all__ = ["read_identify_scene"]

_KEYS = {"steps", "parameters", "observations", "data", "max_runs"}
_KINDS = ("reaction", "contact_force", "displacement", "surface_points")


def _observation(entry: Any, i: int, source: str):
    where = f"{source}: [identify] observations[{i}]"
    if not isinstance(entry, dict):
        raise SceneError(f'{where}: each observation is a table, e.g. {{ reaction = "platen" }}')
    kinds = [k for k in _KINDS if k in entry]
    extra = set(entry) - {*_KINDS, "component", "body"}
    if len(kinds) != 1 or extra:
        raise SceneError(
            f"{where}: give one of reaction = NAME, contact_force = OBSTACLE, displacement = "
            f"[VERTICES] or surface_points = [[x, y, z], ...] (with component and body where "
            f"they apply); got keys {sorted(entry)}"
        )
    component = entry.get("component")
    if kinds[0] == "reaction":
        return Reaction(str(entry["reaction"]), component)
    if kinds[0] == "contact_force":
        return ContactForce(str(entry["contact_force"]), component)
    if kinds[0] == "surface_points":
        return SurfaceDistance(entry["surface_points"], entry.get("body"))
    return Displacement(entry["displacement"], entry.get("body"), component)


def _parameters(table: Any, source: str) -> tuple[dict, dict]:
    where = f"{source}: [identify] parameters"
    if not isinstance(table, dict) or not table:
        raise SceneError(
            f"{where}: a table of scene key paths, e.g. "
            '{ "material.youngs_modulus" = [2e4, 1e3, 1e6] } (initial, low, high)'
        )
    initial, bounds = {}, {}
    for key, value in table.items():
        values = value if isinstance(value, list) else [value]
        if len(values) not in (1, 3) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in values
        ):
            raise SceneError(f"{where}.{key}: an initial value, or [initial, low, high]")
        initial[key] = float(values[0])
        if len(values) == 3:
            bounds[key] = (float(values[1]), float(values[2]))
    return initial, bounds


def _read_data(value: Any, base_dir: Path, source: str) -> np.ndarray:
    where = f"{source}: [identify] data"
    if isinstance(value, list):
        try:
            return np.array(value, dtype=float)
        except (TypeError, ValueError):
            raise SceneError(f"{where}: a list of rows of numbers") from None
    if not isinstance(value, str):
        raise SceneError(f"{where}: a CSV file's path, or a list of rows of numbers")
    path = base_dir / value
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except OSError as exc:
        raise SceneError(f"{where}: cannot read {path} ({exc.strerror})") from None
    if len(rows) < 2 or not rows[0] or rows[0][0].strip().lower() != "step":
        raise SceneError(
            f"{where}: {path} needs a header row starting with 'step', then one row per step"
        )
    out = []
    for n, row in enumerate(rows[1:], start=2):
        try:
            out.append([float(c) if c.strip() else np.nan for c in row[1:]])
        except ValueError:
            raise SceneError(f"{where}: {path} line {n}: not a number in {row}") from None
    if len({len(r) for r in out}) != 1:
        raise SceneError(f"{where}: {path}: every row needs the same number of columns")
    return np.array(out, dtype=float)


def read_identify_scene(path: str | Path) -> dict:
    """The scene's model function and its ``[identify]`` table read: a dict with ``build``,
    ``initial``, ``bounds``, ``observations``, ``data``, ``steps`` and ``max_runs``
    (module docstring)."""
    from tissuesim.scene.loader import build_scene
    from tissuesim.sweep.keypaths import parse_key_path

    path = Path(path)
    source = str(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SceneError(f"{source}: cannot read the scene file ({exc.strerror})") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{source}: not valid TOML: {exc}") from None
    table = data.pop("identify", None)
    if not isinstance(table, dict):
        raise SceneError(
            f"{source}: no [identify] table: name the parameters, observations and data "
            "(docs/guide/identify.md)"
        )
    unknown = set(table) - _KEYS
    if unknown:
        raise SceneError(f"{source}: [identify]: unknown keys {sorted(unknown)}; valid: "
                         f"{sorted(_KEYS)}")  # fmt: skip
    initial, bounds = _parameters(table.get("parameters"), source)
    paths = {key: parse_key_path(key) for key in initial}
    for p in paths.values():
        try:
            p.get(data)
        except InputError as exc:
            raise SceneError(f"{source}: [identify] parameters: {exc}") from None
    observations = [_observation(e, i, source)
                    for i, e in enumerate(table.get("observations") or [])]  # fmt: skip
    if not observations:
        raise SceneError(f"{source}: [identify] observations: name at least one")
    measured = _read_data(table.get("data"), path.parent, source)
    steps = table.get("steps", len(measured))
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        raise SceneError(f"{source}: [identify] steps: a positive integer")

    def build(params: dict):
        d = copy.deepcopy(data)
        for key, value in params.items():
            paths[key].set(d, value)
        return build_scene(d, base_dir=path.parent, source=source, name=path.stem).simulation

    return {
        "build": build,
        "initial": initial,
        "bounds": bounds,
        "observations": observations,
        "data": measured,
        "steps": steps,
        "max_runs": int(table.get("max_runs", 50)),
    }
