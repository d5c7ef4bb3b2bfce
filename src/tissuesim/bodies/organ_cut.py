"""A blade that cuts a FEM body as it moves (``Simulation.add_cut(..., body=...)``, scene
``[[cuts]]`` with ``body``): after every step, the cells its edge has swept through completely
since it started are cut (``Simulation.cut_body``, the virtual node algorithm), where the body
is at the end of the step; cells it crossed before keep their cut.

The blade is a straight edge, ``blade(t)`` its two end points, or a triangle (three corners: a
scalpel's flat blade, which cuts wherever it is as well as where it has been), moving from
``start`` to ``end``. While it moves in one plane, the area it has swept is the convex hull of
its positions so far in that plane (exact for a blade moving without turning; for one that
turns in its plane, a little more than it swept). A blade that leaves its plane (it tilts,
turns or follows a curved path) cuts along the surface it sweeps: the triangles between its
positions sampled step by step (``mesh/cutting/swept_cut.py``), each cell along the swept surface's
plane where it passes. Its force per step is the cutting
resistance: with ``toughness`` G (J/m^2, the energy to make a unit of new cut surface; 0 by
default), the work G dA of the area cut in the step over the blade's travel ds, against its
motion:
F = -G dA / |ds| ds/|ds| (N). A blade given as a function of t is a cutting path, not a body:
it takes no part in contact, so that force is what cutting costs, not a push on its faces.

An instrument can be the blade (``obstacle``): an edge or a triangle of an obstacle's surface,
moved by the obstacle's motion, prescribed or driven live between steps
(``Simulation.drive_obstacle``). Its future is then unknown, so the blade is sampled step by
step (``record``); its plane is the one its first samples span, and its cut becomes a swept
surface once it leaves it. With contact on, the instrument is in contact with the body it
cuts too (``contact``, the default): before each step, every cell the blade will touch in the
step is cut (``mesh/cutting/cut_ahead.py``), so the blade moves in the cut's kerf, both faces of the
cut stay clear of it, and what presses on its faces is a contact force. The cut then leads
the blade by at most a step's travel (capped at a cell's edge) and one cell (after each step,
without contact, it trails by at most one cell).
Either way the cut's force is what the instrument feels: its contact force plus the cutting
resistance.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.cutting.swept_cut import SweptCut
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

__all__ = ["OrganCut"]

#: blade positions sampled over the sweep (planarity check, swept hull)
SAMPLES = 17
#: blade positions sampled per step for a blade recorded step by step (an obstacle's)
STEP_SAMPLES = 5


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
    #: the obstacle whose edge or triangle is the blade (sampled step by step), or None
    obstacle: str | None = None
    #: an obstacle's blade in contact with the body it cuts: the cut is made ahead of it
    contact: bool = False
    point: np.ndarray | None = field(init=False, default=None)
    normal: np.ndarray | None = field(init=False, default=None)
    #: the blade left its plane: the cut follows the surface it sweeps (mesh/cutting/swept_cut.py)
    curved: bool = field(init=False, default=False)
    area: float = field(init=False, default=0.0)
    _samples: list = field(init=False, default_factory=list, repr=False)
    _sampled_to: float = field(init=False, default=-np.inf, repr=False)
    #: a cut made ahead of the step (``contact``): what it changed, reported after the step
    pending: dict | None = field(init=False, default=None, repr=False)
    #: out of contact with its body for this step (a new cut face crossed it at the start)
    suspended: bool = field(init=False, default=False, repr=False)
    #: a blade in contact: its edges or triangles over the step about to be taken (the cut
    #: ahead's samples), whose path the step's start keeps clear (contact/cut/blade_clearance.py)
    path: list | None = field(init=False, default=None, repr=False)

    def __post_init__(self) -> None:
        where = f"cut {self.name!r} of body {self.body!r}"
        if not self.end > self.start:
            raise InputError(f"{where}: end ({self.end}) must come after start ({self.start})")
        if self.toughness < 0 or not np.isfinite(self.toughness):
            raise InputError(f"{where}: toughness must be >= 0 J/m^2, not {self.toughness}")
        if self.contact and self.obstacle is None:
            raise InputError(
                f"{where}: a blade given as a function of t is a cutting path, not a body in "
                "contact; make the instrument an obstacle (add_obstacle) and cut with it"
            )
        self._sampled_to = self.start
        if self.obstacle is not None:  # its motion is known step by step only (record)
            self._samples.append(self.edge(self.start))
            self._plane(final=False)
            return
        if not np.isfinite(self.end):
            raise InputError(
                f"{where}: end must be a finite time for a blade given as a function of t "
                "(an obstacle's blade may cut until the end of the run)"
            )
        P = np.array([self.edge(t) for t in np.linspace(self.start, self.end, SAMPLES)])
        self._samples = list(P)
        self._plane(final=True)
        if self.curved:  # sampled step by step from now on, as the blade goes
            self._samples = [self.edge(self.start)]

    def _plane(self, final: bool) -> None:
        """Fix the cut's plane from the samples once they span one (a triangle blade spans
        its own), and follow the swept surface instead (``curved``) once a sample leaves
        it; ``final``: the samples are the whole sweep, which must span an area."""
        where = f"cut {self.name!r} of body {self.body!r}"
        pts = np.concatenate(self._samples)
        size = float(np.linalg.norm(np.ptp(pts, axis=0)))
        if self.normal is None:
            centre = pts.mean(axis=0)
            _, s, vt = np.linalg.svd(pts - centre)
            if s[1] <= 1e-9 * max(s[0], 1e-300):
                if final:
                    raise InputError(
                        f"{where}: the blade sweeps no area (it moves along itself or not at all)"
                    )
                return
            self.point, self.normal = centre, vt[2]
        off = float(np.abs((pts - self.point) @ self.normal).max())
        if off > 1e-6 * size:
            self.curved = True

    def record(self, t0: float, t1: float) -> None:
        """Sample the blade over the step t0 -> t1 (within start..end): an obstacle's (its
        motion is known step by step) or one that left its plane (the swept surface is built
        from its samples)."""
        lo, hi = max(t0, self.start, self._sampled_to), min(t1, self.end)
        if (self.obstacle is None and not self.curved) or hi <= lo:
            return
        self._samples.extend(self.edge(t) for t in np.linspace(lo, hi, STEP_SAMPLES)[1:])
        self._sampled_to = hi
        if not self.curved:
            self._plane(final=False)

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

    def swept(self, t: float) -> PlanarCut | SweptCut | None:
        """The cut it has made by time t, or None: the hull of its positions from start in
        its plane, or the surface between its samples once it left its plane."""
        from scipy.spatial import ConvexHull

        if t <= self.start:
            return None
        if self.curved:
            return SweptCut.from_blades(self._samples) if len(self._samples) > 1 else None
        if self.normal is None:
            return None
        if self.obstacle is None:
            P = [self.edge(s) for s in np.linspace(self.start, min(t, self.end), SAMPLES)]
        else:
            P = self._samples
        pts = np.concatenate(P)
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
