"""FEBio loads given as fields: FEBio 3's non-const body load (math of X, Y, Z, t) and the
uniform surface force (a total force spread over a surface's reference area), read into
``FebModel`` for ``condition_sections._loads``."""

from __future__ import annotations

import numpy as np

from tissuesim.febio.model import FebModel, Load, _flag, _int_attr, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["field_body_force", "surface_force", "facet_area"]


def field_body_force(model: FebModel, load: Node) -> None:
    """FEBio 3's body_load type="non-const" (FENonConstBodyForceOld): each of x, y, z a
    <type="math"> expression of the reference coordinates X, Y, Z (and t) times its curve;
    the force applied is its negative, as a const body load's
    (``condition_sections._body_force``). Kept as (component, expression in tissuesim's
    syntax, Load of the curve) in ``model.body_force_fields``."""
    import re

    from tissuesim.errors import SceneError
    from tissuesim.febio.model import _children
    from tissuesim.scene.expressions import compile_expression

    p = _children(load, {"x", "y", "z"})
    for k, axis in enumerate("xyz"):
        c = p.get(axis)
        if c is None:
            continue
        if c.attrib.get("type", "math") != "math":
            raise c.error(f'type="{c.attrib["type"]}": tissuesim reads type="math" expressions')
        text = re.sub(r"\b([XYZ])\b", lambda m: m.group(1).lower(), c.text).replace("^", "**")
        try:
            compile_expression(text, c.where())
        except SceneError as exc:
            raise c.error(f"the expression {c.text!r} is not one tissuesim reads ({exc})") from None
        curve = _int_attr(c, "lc", "a load curve id")
        model.body_force_fields.append((k, text, Load(-np.ones(1), curve, model.window)))


def surface_force(model: FebModel, load: Node) -> None:
    """FEBio's surface_load type="force" (FESurfaceForceUniform): the force spread over the
    surface as the uniform dead traction scale * force / A, A the surface's reference area
    (each facet's integral of |x_r x x_s|, 2 x 2 Gauss points on a quadrilateral)."""
    surface = load.attrib.get("surface")
    if surface not in model.surfaces:
        raise load.error(f"no Surface named {surface!r}")
    from tissuesim.febio.model import _children, _load

    p = _children(load, {"force", "scale", "shell_bottom"})
    if "force" not in p:
        raise load.error("needs a <force> (the total force vector)")
    if "shell_bottom" in p and _flag(p["shell_bottom"]):
        raise _unsupported(p["shell_bottom"], "shell_bottom = 1")
    force = _load(model, p["force"], 3)
    scale = _load(model, p["scale"], 1) if "scale" in p else Load(np.ones(1))
    if force.curve is not None and scale.curve is not None:
        raise p["scale"].error("a curve on both <force> and <scale>")
    area = facet_area(model.nodes, model.surfaces[surface][0])
    if not area > 0:
        raise load.error(f"surface {surface!r} has no area")
    traction = force.value * scale.value[0] / area
    model.tractions.append((surface, "traction", Load(traction, scale.curve or force.curve,
                                                      model.window)))  # fmt: skip


def facet_area(points: np.ndarray, facets: np.ndarray) -> float:
    """The total area of facets: triangles (k, 3) exactly, quadrilaterals (k, 4) as the
    bilinear patch's integral of |x_r x x_s| on 2 x 2 Gauss points (FEBio's FaceArea)."""
    x = points[facets]
    if facets.shape[1] == 3:
        return float(
            0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1).sum()
        )
    g = 1.0 / np.sqrt(3.0)
    total = 0.0
    for r in (-g, g):
        for s in (-g, g):
            # bilinear shape derivatives on [-1, 1]^2, corners (-1,-1), (1,-1), (1,1), (-1,1)
            dr = 0.25 * np.array([-(1 - s), 1 - s, 1 + s, -(1 + s)])
            ds = 0.25 * np.array([-(1 - r), -(1 + r), 1 + r, 1 - r])
            xr, xs = np.einsum("a,kaj->kj", dr, x), np.einsum("a,kaj->kj", ds, x)
            total += float(np.linalg.norm(np.cross(xr, xs), axis=1).sum())
    return total
