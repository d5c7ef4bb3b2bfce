"""A blade that cuts a FEM body as it moves (``Simulation.add_cut(..., body=...)``, scene
``[[cuts]]`` with ``body``): after every step, the cells its edge has swept through completely
since it started are cut (``Simulation.cut_body``, the virtual node algorithm), where the body
is at the end of the step; cells it crossed before keep their cut.

The blade is a straight edge, ``blade(t)`` its two end points, or a triangle (three corners: a
scalpel's flat blade, which cuts wherever it is as well as where it has been), moving in its
own plane from ``start`` to ``end`` (a straight cut: the plane is checked at the start). The
area it has swept is the convex hull of its positions so far (exact for a blade moving without
turning; for one that turns, a little more than it swept). Its force per step is the cutting
resistance: with ``toughness`` G (J/m^2, the energy to make a unit of new cut surface; 0 by
default), the work G dA of the area cut in the step over the blade's travel ds, against its
motion:
F = -G dA / |ds| ds/|ds| (N). The blade does not take part in contact (it must pass through the
body to cut it), so that force is what cutting costs, not a push on its faces.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.virtual_nodes import PlanarCut

__all__ = ["OrganCut"]

#: blade positions sampled over the sweep (planarity check, swept hull)
SAMPLES = 17


@dataclass
class OrganCut:
    """A blade ``blade(t) -> (2, 3)`` (an edge) or ``(3, 3)`` (a triangle) cutting FEM body
    ``body`` from ``start`` to ``end`` (s), reported as ``name``, with cutting ``toughness``
    (J/m^2)."""

    blade: Callable[[float], np.ndarray]
    start: float
    end: float
    body: str
    name: str = "cut"
    toughness: float = 0.0
    point: np.ndarray = field(init=False)
    normal: np.ndarray = field(init=False)
    area: float = field(init=False, default=0.0)

    def __post_init__(self) -> None:
        where = f"cut {self.name!r} of body {self.body!r}"
        if not self.end > self.start:
            raise InputError(f"{where}: end ({self.end}) must come after start ({self.start})")
        if self.toughness < 0 or not np.isfinite(self.toughness):
            raise InputError(f"{where}: toughness must be >= 0 J/m^2, not {self.toughness}")
        P = np.array([self.edge(t) for t in np.linspace(self.start, self.end, SAMPLES)])
        pts = P.reshape(-1, 3)
        centre = pts.mean(axis=0)
        _, s, vt = np.linalg.svd(pts - centre)
        size = float(np.linalg.norm(np.ptp(pts, axis=0)))
        if s[1] <= 1e-9 * max(s[0], 1e-300):
            raise InputError(
                f"{where}: the blade sweeps no area (it moves along itself or not at all)"
            )
        off = float(np.abs((pts - centre) @ vt[2]).max())
        if off > 1e-6 * size:
            raise InputError(
                f"{where}: the blade leaves its plane ({off:.3g} m off it); an organ cut is "
                "planar: split a curved cut into cuts of their own names"
            )
        self.point, self.normal = centre, vt[2]

    def edge(self, t: float) -> np.ndarray:
        """The blade at t: its two end points (2, 3), or a triangle's three corners (3, 3)."""
        try:
            P = np.asarray(self.blade(t), dtype=float)
        except Exception as exc:  # a user's function
            raise InputError(f"cut {self.name!r}: blade({t:g}) failed: {exc}") from None
        if P.ndim != 2 or P.shape[1] != 3 or len(P) < 2 or not np.all(np.isfinite(P)):
            raise InputError(
                f"cut {self.name!r}: blade(t) must return a straight edge (2, 3) or a triangle "
                f"(3, 3) of finite points (m), got shape {P.shape}"
            )
        if len(P) == 2:
            return P
        a, b = P[0], P[-1]
        axis = (b - a) / max(np.linalg.norm(b - a), 1e-300)
        off = np.linalg.norm(np.cross(P - a, axis), axis=1).max()
        if off <= 1e-9 * np.linalg.norm(b - a):
            return P[[0, -1]]  # points along one line: that edge
        if len(P) > 3:
            raise InputError(
                f"cut {self.name!r}: an organ's blade is a straight edge or a triangle; "
                f"{len(P)} points off one line are neither"
            )
        return P

    def swept(self, t: float) -> PlanarCut | None:
        """The cut it has made by time t (the hull of its positions from start), or None."""
        from scipy.spatial import ConvexHull

        if t <= self.start:
            return None
        P = np.array([self.edge(s) for s in np.linspace(self.start, min(t, self.end), SAMPLES)])
        pts = P.reshape(-1, 3)
        u = np.cross(self.normal, [1.0, 0.0, 0.0])
        if np.linalg.norm(u) < 0.5:
            u = np.cross(self.normal, [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        w = np.cross(self.normal, u)
        flat = np.column_stack([(pts - self.point) @ u, (pts - self.point) @ w])
        try:
            hull = ConvexHull(flat)
        except Exception:  # no area swept yet
            return None
        corners = self.point + flat[hull.vertices, :1] * u + flat[hull.vertices, 1:] * w
        return PlanarCut(self.point, self.normal, corners)

    def force(self, new_area: float, t0: float, t1: float) -> np.ndarray:
        """The blade's cutting force (N, 3) over the step t0 -> t1 that cut ``new_area``."""
        if self.toughness == 0.0 or new_area <= 0.0:
            return np.zeros(3)
        lo, hi = max(t0, self.start), min(t1, self.end)
        move = self.edge(hi).mean(axis=0) - self.edge(lo).mean(axis=0)
        travel = float(np.linalg.norm(move))
        if travel == 0.0:
            return np.zeros(3)
        return -self.toughness * new_area / travel * move / travel
