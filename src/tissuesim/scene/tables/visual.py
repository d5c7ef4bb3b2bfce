"""``[[visual_surfaces]]``: a fine surface carried by a FEM body for the output
(``Simulation.add_visual_surface``, ``bodies/visual_surface.py``), in every scene with a mesh.

    [[visual_surfaces]]
    body = "liver"              # a FEM body; a one-body scene's is its body
    file = "liver_fine.stl"     # relative to the scene file; STL, OBJ, PLY, ... (2D: lines)
    name = "liver_fine"         # its series (default "<body>_visual")
    max_outside = 0.004         # m a point may lie outside the body (default: one element)
"""

from __future__ import annotations

from pathlib import Path

from tissuesim.errors import SceneError
from tissuesim.scene.common import _context, _table, _unknown
from tissuesim.validate import short

__all__ = ["VISUAL_KEYS", "add_visual_surfaces"]

VISUAL_KEYS = ("body", "file", "name", "max_outside")


def add_visual_surfaces(
    sim, data: dict, base_dir: Path, source: str, body: str | None = None
) -> None:
    """Read the scene's [[visual_surfaces]] into ``sim``; ``body``: the default body (a
    one-body scene's)."""
    for i, item in enumerate(_table(data, "visual_surfaces", source, array=True), start=1):
        where = f"{source} visual_surfaces[{i}]"
        _unknown(item, VISUAL_KEYS, where)
        file = item.get("file")
        if not isinstance(file, str) or not file:
            raise SceneError(
                f"{where}: file must name a surface file (STL, OBJ, PLY, ...), e.g. file = "
                f"'liver_fine.stl', not {short(file)}"
            )
        path = Path(file) if Path(file).is_absolute() else base_dir / file
        if not path.is_file():
            raise SceneError(
                f"{where} file: {file!r}: no such surface file ({path}; paths are relative to "
                "the scene file)"
            )
        name = item.get("body", body)
        if name is not None and (not isinstance(name, str) or name not in sim.bodies):
            raise SceneError(
                f"{where} body: {short(name)} is not a body of this scene; bodies: "
                f"{', '.join(sim.bodies)}"
            )
        with _context(where):
            sim.add_visual_surface(
                str(path), body=name, name=item.get("name"), max_outside=item.get("max_outside")
            )
