"""The scene tables of contact: ``[contact]`` (switch it on, its parameters) and
``[[obstacles]]`` (kinematic rigid surfaces and their motion), for every scene (the one-body
[mesh] and [frames] short forms and ``[[bodies]]``). Each key is an argument of
``Simulation.set_contact`` / ``Simulation.add_obstacle`` (docs/guide/contact.md).

    [contact]
    dhat = 0.001          # m, activation distance (default 1e-3 of the scene's size)
    stiffness = 1e4       # Pa, a fixed barrier kappa (default: IPC's adaptive kappa,
                          # from the largest Young's modulus E, within [E, 100 E])
    friction = 0.3        # Coulomb mu (default 0); eps_v (m/s), friction_iterations
    surfaces = { block = "zmax" }   # a body's contact surface: a facet set (default: boundary)
    mode = "accurate"     # or "interactive", "barrier", "auto" (the default): time/contact_step.py

    [[contact.pairs]]     # per pair of bodies (a body twice: its self contact; or an obstacle)
    bodies = ["liver", "gallbladder"]
    friction = 0.1        # and/or enabled = false

    [[obstacles]]
    name = "probe"
    sphere = { center = [0, 0, 0.11], radius = 0.1, refinement = 3 }  # cap_angle, cap_axis
    translation = ["0", "0", "-0.001 * t"]     # m, expressions of t
    rotation = ["0", "0", "0"]                 # rad, rotation vector about the centroid
    friction = 0.2                             # its own mu against every body (optional)
"""

from __future__ import annotations

from pathlib import Path

from tissuesim.errors import SceneError
from tissuesim.validate import short

__all__ = ["add_contact_tables", "CONTACT_KEYS", "OBSTACLE_KEYS", "SHAPES"]

CONTACT_KEYS = {
    "enabled",
    "dhat",
    "stiffness",
    "friction",
    "eps_v",
    "friction_iterations",
    "surfaces",
    "pairs",
    "mode",
}
SHAPES = {
    "plane": {"point", "normal", "size"},
    "sphere": {"center", "radius", "refinement", "cap_angle", "cap_axis"},
    "box": {"lower", "upper", "divisions"},
    "capsule": {"start", "end", "radius", "segments"},
    "cylinder": {"start", "end", "radius", "segments"},
    "triangle": {"corners"},
    "file": None,
}
OBSTACLE_KEYS = {"name", "translation", "rotation", "friction", *SHAPES}


def add_contact_tables(sim, data: dict, base_dir: Path, source: str) -> None:
    """Read [contact] and [[obstacles]] of a parsed scene into ``sim``."""
    from tissuesim.scene.common import _context, _table, _unknown

    contact = _table(data, "contact", source)
    obstacles = _table(data, "obstacles", source, array=True)
    where = f"{source} [contact]"
    _unknown(contact, CONTACT_KEYS, where)
    enabled = contact.get("enabled", bool(contact) or bool(obstacles))
    if not isinstance(enabled, bool):
        raise SceneError(f"{where}: enabled must be true or false, not {short(enabled)}")
    if not enabled:
        if obstacles:
            raise SceneError(f"{where}: enabled = false, but the scene has [[obstacles]]")
        return
    with _context(where):
        options = {
            k: contact[k]
            for k in ("friction", "eps_v", "friction_iterations", "surfaces", "pairs", "mode")
            if k in contact
        }
        sim.set_contact(dhat=contact.get("dhat"), stiffness=contact.get("stiffness"), **options)
    for i, item in enumerate(obstacles, start=1):
        _obstacle(sim, item, base_dir, f"{source} obstacles[{i}]")


def _obstacle(sim, item: dict, base_dir: Path, where: str) -> None:
    from tissuesim.contact.obstacles import capsule, cylinder, plane, sphere, triangle
    from tissuesim.frames.sampling import box_surface, read_surface
    from tissuesim.scene.common import _context, _unknown, of_time

    _unknown(item, OBSTACLE_KEYS, where)
    name = item.get("name")
    if not isinstance(name, str) or not name:
        raise SceneError(f"{where}: name must be a non-empty string, e.g. name = 'probe'")
    shapes = [k for k in SHAPES if k in item]
    if len(shapes) != 1:
        raise SceneError(
            f"{where}: give exactly one shape: plane = {{ point, normal, size }}, sphere = "
            "{ center, radius }, box = { lower, upper }, capsule or cylinder = { start, end, "
            "radius }, triangle = { corners } (a flat blade), or file = 'instrument.stl'"
        )
    shape = shapes[0]
    here = f"{where} {shape}"
    value = item[shape]
    with _context(here):
        if shape == "file":
            if not isinstance(value, str):
                raise SceneError(f"{here}: must be a path (a string), not {short(value)}")
            path = Path(value)
            surface = read_surface(path if path.is_absolute() else base_dir / path)
        else:
            if not isinstance(value, dict):
                raise SceneError(f"{here}: must be a table of {sorted(SHAPES[shape])}")
            _unknown(value, SHAPES[shape], here)
            make = {
                "plane": plane,
                "sphere": sphere,
                "box": box_surface,
                "capsule": capsule,
                "cylinder": cylinder,
                "triangle": triangle,
            }[shape]
            surface = make(**value)
    motions = {}
    for key in ("translation", "rotation"):
        if key in item:
            motions[key] = of_time(item[key], 3, f"{where} {key}", f"the obstacle's {key}")
    if "friction" in item:
        motions["friction"] = item["friction"]
    with _context(where):
        sim.add_obstacle(name, surface, **motions)
