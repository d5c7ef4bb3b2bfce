"""A sphere probe's indentation depth: how far it has travelled into the bodies since it first
touched them, along the direction it touched in.

At every reported step the depth is measured on the bodies as they are, not on their rest
shape: while a probe touches nothing its gap g to the nearest body vertex (distance to its
centre minus its radius) and the unit direction n from its centre to that vertex are kept; at
the first step it touches (a barrier force on it), the touch point of its centre is
c_touch = c_free + g n, from the last contact-free step (or the rest configuration when it
touches from the start), and from then on

    depth = max(0, (c - c_touch) . n),

c its centre now. So the depth is 0 until the probe reaches the surface however the bodies
have sagged or moved before, grows linearly with the probe's travel (past its radius too), and
resets when the probe lets go. It is the probe's travel, not the surface's deflection: the
surface under the probe sits ``min_distance`` (the barrier gap) above it, and a body still
moving on its own under the probe moves that too. Capsules (graspers' jaws, shafts) and planes
(floors, ramps) get none: a force against such a depth is no indentation curve.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

__all__ = ["IndentationTracker", "is_probe", "probe_gap"]


def probe_gap(obstacle, points: np.ndarray, t: float) -> tuple[float, np.ndarray, np.ndarray]:
    """A sphere obstacle at time t against ``points`` (n, 3): (gap to the nearest point, m;
    unit direction from the centre to it; the centre)."""
    return _nearest(obstacle.sphere_center(t), obstacle.surface.params["radius"], points)


def _nearest(centre: np.ndarray, radius: float, points: np.ndarray):
    offsets = points - centre
    distances = np.linalg.norm(offsets, axis=1)
    k = int(np.argmin(distances))
    return float(distances[k] - radius), offsets[k] / max(distances[k], 1e-300), centre


def is_probe(obstacle) -> bool:
    """Whether an obstacle has an indentation depth (a sphere, an open cap included)."""
    return getattr(obstacle.surface, "kind", "") == "sphere"


class IndentationTracker:
    """Each sphere probe's touch point, kept between steps (on the Simulation, so it survives a
    rebuilt contact model)."""

    def __init__(self) -> None:
        self._free: dict[str, tuple[float, np.ndarray, np.ndarray]] = {}
        self._touch: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def depths(
        self,
        obstacles: Iterable,
        bodies_now: np.ndarray,
        bodies_rest: np.ndarray,
        t: float,
        forces: Mapping[str, np.ndarray],
    ) -> dict[str, float]:
        """Per sphere obstacle, its depth (m) at time t, the bodies' vertices at ``bodies_now``
        and the obstacles' forces ``forces`` (name -> N; non-zero: touching)."""
        out = {}
        for ob in obstacles:
            if not is_probe(ob):
                continue
            touching = bool(np.any(np.asarray(forces.get(ob.name, 0.0)) != 0.0))
            if not touching:
                self._touch.pop(ob.name, None)
                self._free[ob.name] = probe_gap(ob, bodies_now, t)
                out[ob.name] = 0.0
                continue
            if ob.name not in self._touch:
                # touching from the start: the bodies and the probe at rest
                p = ob.surface.params
                gap, n, centre = self._free.get(ob.name) or _nearest(
                    np.asarray(p["center"], float), p["radius"], bodies_rest
                )
                self._touch[ob.name] = (centre + gap * n, n)
            touch, n = self._touch[ob.name]
            out[ob.name] = max(0.0, float((ob.sphere_center(t) - touch) @ n))
        return out
