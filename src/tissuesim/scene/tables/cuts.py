"""The [[cuts]] and [tearing] tables of a scene of several bodies (``coupled.py``): blades
through the connective tissue or an organ (a polyline of 3 numbers or expressions of t per
point, or an instrument's edge, ``obstacle = "..."``), the connective tissue tearing at a strain
threshold, an organ tearing at a stress or a stretch. Every key is an argument of
``Simulation.add_cut`` / ``set_tearing`` (``simulation/cuts.py``)."""

from __future__ import annotations

import numpy as np

from tissuesim.errors import SceneError
from tissuesim.scene.common import (
    _body_name,
    _context,
    _number,
    _required,
    _table,
    _unknown,
    of_time,
)
from tissuesim.validate import short

__all__ = ["add_cut_tables", "add_tearing_table", "CUT_KEYS", "TEARING_KEYS"]

CUT_KEYS = (
    "blade",
    "start",
    "end",
    "kerf",
    "name",
    "body",
    "toughness",
    "obstacle",
    "edge",
    "contact",
)
TEARING_KEYS = ("threshold", "body", "stress", "stretch")


def add_cut_tables(sim, data: dict, source: str, has_tissue: bool) -> None:
    """Every [[cuts]] table of ``data``; a cut without ``body`` needs the scene's [tissue]."""
    cuts = _table(data, "cuts", source, array=True)
    for i, item in enumerate(cuts, start=1):
        if not has_tissue and isinstance(item, dict) and "body" not in item:
            raise SceneError(
                f"{source} cuts[{i}]: a cut without body = '...' dissects the connective "
                "tissue, and the scene has none; name the organ it cuts (body = 'liver'), or "
                "add a [tissue] table (material, thickness, spacing)"
            )
    for i, item in enumerate(cuts, start=1):
        _cut(sim, item, f"{source} cuts[{i}]")


def add_tearing_table(sim, data: dict, source: str, has_tissue: bool) -> None:
    """The [tearing] table of ``data``: an organ's (``body``, ``stress`` / ``stretch``) or the
    connective tissue's (``threshold``, which needs the scene's [tissue])."""
    tearing = _table(data, "tearing", source)
    if not tearing:
        return
    where = f"{source} [tearing]"
    _unknown(tearing, TEARING_KEYS, where)
    if "body" in tearing:  # an organ tears (bodies/organ_tear.py)
        body = _body_name(sim, tearing["body"], where)
        if "threshold" in tearing:
            raise SceneError(
                f"{where}: a body tears at stress = ... (Pa) or stretch = ..., not at a "
                "strain threshold (that is the connective tissue's)"
            )
        options = {
            key: _number(tearing[key], f"{where} {key}", want)
            for key, want in (("stress", "a stress > 0 (Pa)"), ("stretch", "a stretch > 1"))
            if key in tearing
        }
        with _context(where):
            sim.set_tearing(body=body, **options)
        return
    if "stress" in tearing or "stretch" in tearing:
        raise SceneError(f"{where}: stress and stretch are for a body that tears (body = ...)")
    if not has_tissue:
        raise SceneError(
            f"{where}: tearing removes overstretched connective tissue, and the scene has "
            f"none; add a [tissue] table, or name the body that tears (body = '...', stress)"
        )
    threshold = _required(tearing, "threshold", where)
    _number(threshold, f"{where} threshold", "a strain > 0 (largest principal Green strain)")
    with _context(where):
        sim.set_tearing(threshold)


def _cut(sim, item: dict, where: str) -> None:
    _unknown(item, CUT_KEYS, where)
    if "obstacle" in item:
        _obstacle_cut(sim, item, where)
        return
    for key in ("edge", "contact"):
        if key in item:
            raise SceneError(f"{where}: {key} is for an instrument's blade (obstacle = '...')")
    blade = _required(item, "blade", where)
    example = '[["-0.07 + 0.14 * t", "-0.05", "0.01"], ["-0.07 + 0.14 * t", "0.05", "0.01"]]'
    if not (isinstance(blade, list) and all(isinstance(p, list) for p in blade)):
        raise SceneError(
            f"{where}: blade must be a polyline of points, each 3 numbers or expressions of t, "
            f"e.g. blade = {example}; got {short(blade)}"
        )
    if len(blade) < 2:
        raise SceneError(
            f"{where}: blade needs at least 2 points (a polyline), got {len(blade)}; e.g. "
            f"blade = {example}"
        )
    points = [of_time(p, 3, f"{where} blade[{i}]", "a blade point") for i, p in enumerate(blade)]

    def polyline(t: float) -> np.ndarray:
        return np.stack([p(t) for p in points])

    start = _number(_required(item, "start", where), f"{where} start", "a time (s)", False)
    end = _number(_required(item, "end", where), f"{where} end", "a time (s)", False)
    if not end > start:
        raise SceneError(f"{where}: end ({end:g} s) must be after start ({start:g} s)")
    options = {}
    name = item.get("name", "cut")
    if not (isinstance(name, str) and name):
        raise SceneError(f"{where}: name must be a non-empty string, e.g. name = 'cut'")
    taken = [c.name for c in sim.organ_cuts] + ([] if sim.tissue is None else
                                                [c.name for c in sim.tissue.cuts])  # fmt: skip
    if name in taken:
        raise SceneError(
            f"{where}: a cut named {name!r} exists already; give each [[cuts]] table its own "
            f"name = '...'"
        )
    if "body" in item:  # a blade cutting an organ (bodies/organ_cut.py)
        body = _body_name(sim, item["body"], where)
        if "kerf" in item:
            raise SceneError(f"{where}: kerf is for the tissue's cuts; an organ's cut has none")
        if len(blade) not in (2, 3):
            raise SceneError(
                f"{where}: an organ's blade is a straight edge (2 points) or a triangle "
                f"(3 points), got {len(blade)}"
            )
        options = {"body": body}
        if "toughness" in item:
            options["toughness"] = _number(
                item["toughness"], f"{where} toughness", "an energy per area >= 0 (J/m^2)", False
            )
    elif "toughness" in item:
        raise SceneError(f"{where}: toughness is for a cut of an organ (body = '...')")
    elif "kerf" in item:
        options["kerf"] = _number(item["kerf"], f"{where} kerf", "a width > 0 (m)")
    with _context(where):
        sim.add_cut(polyline, start, end, name=name, **options)


def _obstacle_cut(sim, item: dict, where: str) -> None:
    """[[cuts]] with obstacle = "scalpel": an instrument's edge or triangle (``edge``, vertex
    indices of its surface) cuts ``body`` from ``start`` (default 0) to ``end`` (default: the
    end of the run)."""
    if "blade" in item:
        raise SceneError(f"{where}: give blade = [...] or obstacle = '...', not both")
    if "body" not in item:
        raise SceneError(f"{where}: an obstacle's blade cuts a body: give body = '...'")
    obstacle = item["obstacle"]
    if not (isinstance(obstacle, str) and obstacle):
        raise SceneError(f"{where}: obstacle must be the name of an [[obstacles]] table")
    body = _body_name(sim, item["body"], where)
    start = _number(item.get("start", 0.0), f"{where} start", "a time (s)", False)
    end = float("inf")  # the blade cuts as long as it moves
    if "end" in item:
        end = _number(item["end"], f"{where} end", "a time (s)", False)
    options = {"body": body, "name": item.get("name", "cut")}
    if not (isinstance(options["name"], str) and options["name"]):
        raise SceneError(f"{where}: name must be a non-empty string, e.g. name = 'cut'")
    if "edge" in item:
        options["edge"] = item["edge"]
    if "toughness" in item:
        options["toughness"] = _number(
            item["toughness"], f"{where} toughness", "an energy per area >= 0 (J/m^2)", False
        )
    if "kerf" in item:
        raise SceneError(f"{where}: kerf is for the tissue's cuts; an organ's cut has none")
    if "contact" in item:
        if not isinstance(item["contact"], bool):
            raise SceneError(
                f"{where}: contact must be true (the instrument touches the body it cuts, the "
                f"default) or false (it passes through it), not {short(item['contact'])}"
            )
        options["contact"] = item["contact"]
    with _context(where):
        sim.add_cut(obstacle, start, end, **options)
