"""``[[rigid_wall]]``: a FEM body's facets pressed out of a plane by a penalty or augmented
Lagrangian, as FEBio's rigid wall (``Simulation.add_rigid_wall``,
``contact/penalty/rigid_wall.py``); ``convert`` writes one per FEBio rigid wall.

    [[rigid_wall]]
    name = "floor"                    # its force on the body in forces.csv
    body = "block"                    # the FEM body (default "body": a [mesh] scene's)
    facets = "zmin"                   # a facet set (default: the whole boundary)
    plane = [0, 0, 1, 0]              # a x + b y + c z = d; the body on the side (a, b, c)
    penalty = 1e5                     # Pa/m
    penalty_scale = "min(1, 10 * t)"  # times this expression of t (FEBio's penalty curve)
    offset = "0.01 * t"               # m along the unit normal: a number or an expression of t
    augmented = false                 # FEBio's augmented Lagrangian, until the multipliers'
    tolerance = 0.01                  #   norm changes by less than this (relative),
    max_augmentations = 10            #   at most this many times a step
"""

from __future__ import annotations

from tissuesim.errors import SceneError
from tissuesim.scene.common import _context, _table, _unknown, of_time

__all__ = ["RIGID_WALL_KEYS", "add_rigid_walls"]

RIGID_WALL_KEYS = (
    "name", "body", "facets", "plane", "penalty", "offset", "augmented", "tolerance",
    "max_augmentations", "penalty_scale",
)  # fmt: skip


def add_rigid_walls(sim, data: dict, source: str) -> None:
    """Read the scene's [[rigid_wall]] into ``sim``."""
    for i, item in enumerate(_table(data, "rigid_wall", source, array=True), start=1):
        where = f"{source} rigid_wall[{i}]"
        _unknown(item, RIGID_WALL_KEYS, where)
        for key in ("body", "facets", "name"):
            if key in item and not isinstance(item[key], str):
                raise SceneError(f"{where}: {key} must be a text")
        if "plane" not in item or "penalty" not in item:
            raise SceneError(f"{where}: give plane = [a, b, c, d] and penalty (Pa/m)")
        if "augmented" in item and not isinstance(item["augmented"], bool):
            raise SceneError(f"{where}: augmented must be true or false")
        options = {k: item[k] for k in ("facets", "augmented", "tolerance",
                                        "max_augmentations") if k in item}  # fmt: skip
        offset = item.get("offset", 0.0)
        if isinstance(offset, str):
            at = of_time([offset], 1, f"{where} offset", "the wall's offset")
            options["offset"] = lambda t, at=at: float(at(t)[0])
        else:
            options["offset"] = offset
        if "penalty_scale" in item:
            scale = item["penalty_scale"]
            if isinstance(scale, bool) or not isinstance(scale, str | int | float):
                raise SceneError(f"{where}: penalty_scale must be a number or an expression of t")
            at = of_time([str(scale)], 1, f"{where} penalty_scale", "the penalty's scale")
            options["penalty_scale"] = lambda t, at=at: float(at(t)[0])
        with _context(where):
            sim.add_rigid_wall(item.get("body", "body"), item["plane"], penalty=item["penalty"],
                               name=item.get("name"), **options)  # fmt: skip
