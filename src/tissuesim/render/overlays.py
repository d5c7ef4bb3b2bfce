"""What the pictures draw besides the bodies' own surfaces (``render/scene.py``): the visual
surfaces FEM bodies carry (``Simulation.add_visual_surface``), drawn instead of their coarse
surfaces in 3D and as black polylines over them in 2D, coloured by the body's vertex values
carried the same way; and the outline of a cut of the tissue once its blade has stopped (its
translucent sheet hid the organs under it for the rest of the run)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["cut_outline", "cutting_at", "polylines_2d", "visual_layers", "visuals_of"]


def visuals_of(sim: Any) -> dict[str, list]:
    """Body name -> the visual surfaces it carries (``Simulation.add_visual_surface``)."""
    out: dict = {}
    for v in getattr(sim, "visual_surfaces", {}).values():
        out.setdefault(v.body, []).append(v)
    return out


def visual_layers(
    b: Any, d: dict, vals: np.ndarray | None, visuals: dict, bar: str, clim: tuple[float, float]
) -> list:
    """Body ``b``'s visual surfaces where its mesh points are now (``d``), coloured by its
    vertex values ``vals`` carried the same way (``|u|`` carried as the vector); [] when it
    has none, or when its mesh is no longer the one they were embedded in."""
    from tissuesim.render.pyvista3d import SurfaceLayer

    mesh = d.get("mesh", b.mesh)
    layers = []
    for v in visuals.get(b.name, ()):
        if v.embedding.matrix.shape[1] != mesh.n_points or v.dim != 3:
            return []
        if vals is None:  # the field is the displacement: carry the vector, then its length
            values = np.linalg.norm(v.positions(d["displacement"]), axis=1)
        else:
            values = v.embedding.interpolate(vals)
        layers.append(
            SurfaceLayer(
                v.name if len(visuals[b.name]) > 1 else b.name,
                v.positions(d["positions"]),
                v.cells,
                scalars=values,
                scalar_name=bar,
                clim=clim,
            )
        )
    return layers


def polylines_2d(bodies: list, data: dict, visuals: dict) -> np.ndarray | None:
    """The segments (k, 2, 2) of the 2D bodies' visual polylines where the bodies are in
    ``data`` (None: no body carries one)."""
    parts = [
        v.positions(data[b.name]["positions"])[v.cells]
        for b in bodies
        for v in visuals.get(b.name, ())
        if v.embedding.matrix.shape[1] == len(data[b.name]["positions"])
    ]
    return np.concatenate(parts) if parts else None


def cut_outline(cut: np.ndarray) -> np.ndarray:
    """The border (k, 2, 3) of a swept cut surface given as triangles (m, 3, 3): the edges of
    one triangle only, once corners that coincide (to 1e-9 of its size) are merged."""
    cut = np.asarray(cut, dtype=float)
    corners = cut.reshape(-1, 3)
    scale = 1e-9 * max(float(np.ptp(corners, axis=0).max()), 1e-300)
    key = np.round((corners - corners.min(axis=0)) / scale).astype(np.int64)
    ids = np.unique(key, axis=0, return_inverse=True)[1].reshape(-1, 3)
    local = np.array([[0, 1], [1, 2], [2, 0]])
    edges = np.sort(ids[:, local].reshape(-1, 2), axis=1)
    _, first, counts = np.unique(edges, axis=0, return_index=True, return_counts=True)
    e = np.sort(first[counts == 1])  # edge e: triangle e // 3, its local edge e % 3
    return cut[e // 3][np.arange(len(e))[:, None], local[e % 3]]


def cutting_at(sim: Any) -> Callable[[float], bool]:
    """t -> whether a blade of the tissue's cuts is sweeping at time t (its [start, end])."""
    tools = list(sim.tissue.cuts) if getattr(sim, "tissue", None) is not None else []

    def at(t: float) -> bool:
        slack = 1e-9 * max(1.0, abs(t))
        return any(c.start - slack <= t <= c.end + slack for c in tools)

    return at
