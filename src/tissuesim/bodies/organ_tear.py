"""A FEM body that tears (``Simulation.set_tearing(stress=..., body=...)``, scene ``[tearing]``
with ``body``): by the machinery of a cut (``Simulation.cut_body``, virtual nodes), along a
crack that grows, normal to the largest principal stress, through the elements that exceed
the strength.

After every step, each element's largest principal Cauchy stress sigma_1 (or largest principal
stretch, with ``stretch``) and its direction are computed where the body is. The first time
one exceeds the threshold, the crack's plane is set: through the centroid of the element that
exceeds it most, normal to its principal direction (the crack opens against that stress). Then
every step the crack takes the elements its plane crosses that exceed the threshold: the crack
polygon is the convex hull, in that plane, of their sections and of the crack so far, and the
body is cut along it (a named cut that goes on).

The crack turns where the stress ahead of it turns: when the mean principal direction of the
new elements it would take is more than TURN_DEGREES off its plane's normal, the crack goes on
as a new planar piece from its front, through the front's nearest edge (so the pieces join
along it), normal to that direction (turned about the edge), taking only elements ahead of
the front. The pieces together are a swept surface (``mesh/cutting/swept_cut.py``), each element cut
along the piece nearest to it. The rule is deterministic (no random nucleation). Its size per
step, and so the load at which a body tears, depends on the mesh as every local strength
criterion on a stress field does: the guide reports it.

A body may tear in several places, one crack growing at a time: in a step where none of its
cracks grows (each has stopped, or parted the body) and an element farther than FAR_CELLS of
its own size from every crack exceeds the threshold, a new crack starts there by the same rule
(the element exceeding it most), cut as ``tear2``, ``tear3``, ... Near a crack the stress is
the crack's own (concentrated at its front, relieved at its faces), so it starts none there;
while a crack grows, the stress elsewhere has not yet felt it, so none starts either.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.cutting.swept_cut import SweptCut
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

__all__ = ["BodyTearing", "Crack", "FAR_CELLS", "TURN_DEGREES"]

#: the crack turns (a new planar piece from its front) where the mean principal direction of
#: the elements over the threshold ahead of it is more than this far off its plane's normal
TURN_DEGREES = 15.0
#: a new crack starts only in elements farther than this many of their own sizes (longest
#: edge) from every crack: the stress concentrated at a crack's front and faces is its own
FAR_CELLS = 2.0


@dataclass
class Crack:
    """One crack of a tearing body, cut as the named cut ``name``: its current planar piece
    (``point``, ``normal``, the polygon ``corners`` so far) and the pieces before it turned."""

    name: str
    point: np.ndarray
    normal: np.ndarray
    corners: np.ndarray | None = None
    pieces: list[PlanarCut] = field(default_factory=list)
    #: the current piece's start on the front it turned at (the edge's ends), and the way it
    #: grows in its plane (None for the first piece)
    _front: np.ndarray | None = field(default=None, repr=False)
    _growth: np.ndarray | None = field(default=None, repr=False)

    def grow(
        self, X: np.ndarray, over: np.ndarray, direction: np.ndarray, span: float
    ) -> PlanarCut | SweptCut | None:
        """The crack after taking the elements over the threshold (``over``) its plane crosses
        ahead of its front, or None when it takes none. X (m, k, 3): where each element's
        vertices are; ``direction`` (m, 3): their principal directions; ``span``: a 2D body's
        size (its crack's polygon spans z by it), 0 in 3D."""
        crossed, points = self._sections(X, over)
        if self.corners is not None and crossed.any():
            turn = self._turn(X, crossed, direction)
            if turn is not None:
                self._start_piece(*turn)
                crossed, points = self._sections(X, over)
        if not crossed.any():
            return None  # nothing new: the crack stays as it is
        if span:  # a 2D body's crack is a line: the cut's polygon spans it in z
            up = np.array([0.0, 0.0, span])
            points = np.concatenate([points + up, points - up])
        if self.corners is not None:
            points = np.concatenate([points, self.corners])
        if self._front is not None:
            points = np.concatenate([points, self._front])
        piece = PlanarCut.hull(points, self.point.copy(), self.normal.copy())
        if piece is None:
            return None
        self.corners = piece.polygon
        if not self.pieces:
            return piece
        done = [*self.pieces, PlanarCut(self.point, self.normal, self.corners)]
        return SweptCut(np.concatenate([p.triangles() for p in done]))

    def distance(self, q: np.ndarray) -> np.ndarray:
        """A lower bound of each point's (n, 3) distance to the crack's surface so far (its
        pieces' polygons; inf before it has any): off each plane and outside its polygon."""
        done = [*self.pieces]
        if self.corners is not None:
            done.append(PlanarCut(self.point, self.normal, self.corners))
        out = np.full(len(q), np.inf)
        for piece in done:
            off = (q - piece.point) @ piece.normal
            out = np.minimum(out, np.hypot(off, piece.reach(q - np.outer(off, piece.normal))))
        return out

    def _sections(self, X: np.ndarray, over: np.ndarray):
        """(the elements over the threshold the current piece's plane crosses ahead of its
        front (m,), the points where it crosses their edges (p, 3))."""
        d = (X - self.point) @ self.normal
        crossed = over & (d.max(axis=1) > 0.0) & (d.min(axis=1) < 0.0)
        if self._growth is not None:  # a piece after a turn grows forward only
            crossed &= ((X - self.point) @ self._growth).max(axis=1) > 0.0
        k = X.shape[1]
        i, j = np.triu_indices(k, 1)
        di, dj = d[crossed][:, i], d[crossed][:, j]
        hit = di * dj < 0.0
        t = np.where(hit, di / np.where(hit, di - dj, 1.0), 0.0)
        P = X[crossed][:, i] + t[..., None] * (X[crossed][:, j] - X[crossed][:, i])
        return crossed, P[hit]

    def _turn(self, X: np.ndarray, crossed: np.ndarray, direction: np.ndarray):
        """Where and how the crack turns, or None: the new elements it would take (crossed,
        their centroids beyond the polygon) and their mean principal direction; if that is more
        than TURN_DEGREES off the normal, (the nearest point of the polygon's boundary, that
        edge's ends, the new normal: the mean direction turned about the edge, the way ahead)."""
        centre = X[crossed].mean(axis=1)
        on_plane = centre - np.outer((centre - self.point) @ self.normal, self.normal)
        current = PlanarCut(self.point, self.normal, self.corners)
        new = current.reach(on_plane) > 0.0
        if not new.any():
            return None
        dirs = direction[crossed][new]
        dirs = dirs * np.sign(dirs @ self.normal)[:, None]
        n = dirs.sum(axis=0)
        if np.linalg.norm(n) == 0.0:
            return None
        n = n / np.linalg.norm(n)
        if np.degrees(np.arccos(min(1.0, abs(float(n @ self.normal))))) <= TURN_DEGREES:
            return None
        q = on_plane[new].mean(axis=0)
        ring = self.corners
        best = None
        for a, b in zip(ring, np.roll(ring, -1, axis=0), strict=True):
            e = b - a
            s = np.clip((q - a) @ e / max(float(e @ e), 1e-300), 0.0, 1.0)
            p = a + s * e
            gap = float(np.linalg.norm(q - p))
            if best is None or gap < best[0]:
                best = (gap, p, np.array([a, b]))
        _, p, edge = best
        axis = edge[1] - edge[0]
        axis = axis / np.linalg.norm(axis)
        n = n - (n @ axis) * axis  # turned about the front's edge: the pieces join along it
        if np.linalg.norm(n) < 1e-6:
            return None
        n = n / np.linalg.norm(n)
        growth = np.cross(n, axis)
        if growth @ (q - p) < 0.0:
            growth = -growth
        return p, edge, n, growth

    def _start_piece(self, p, edge, normal, growth) -> None:
        """Close the current piece and go on from ``p`` on its front ``edge`` in the plane of
        ``normal``, growing along ``growth``."""
        self.pieces.append(PlanarCut(self.point, self.normal, self.corners))
        self.point, self.normal, self.corners = p, normal, None
        self._front, self._growth = edge, growth


@dataclass
class BodyTearing:
    """Tearing of FEM body ``body`` where the largest principal Cauchy stress exceeds
    ``stress`` (Pa), or the largest principal stretch exceeds ``stretch``; one of the two.
    ``cracks``: its cracks in the order they started, cut as ``name``, ``name2``, ..."""

    body: str
    stress: float | None = None
    stretch: float | None = None
    name: str = "tear"
    cracks: list[Crack] = field(default_factory=list, init=False)

    def __post_init__(self) -> None:
        given = [v for v in (self.stress, self.stretch) if v is not None]
        if len(given) != 1:
            raise InputError(
                f"tearing of body {self.body!r}: give stress (Pa, the strength: the largest "
                "principal Cauchy stress it bears) or stretch (the largest principal stretch), "
                "one of the two"
            )
        value = float(given[0])
        low = 0.0 if self.stress is not None else 1.0
        if not np.isfinite(value) or value <= low:
            what = "stress must be > 0 Pa" if self.stress is not None else "stretch must be > 1"
            raise InputError(f"tearing of body {self.body!r}: {what}, not {value:g}")

    @property
    def threshold(self) -> float:
        return float(self.stress if self.stress is not None else self.stretch)

    def crack_name(self, k: int) -> str:
        """The cut name of crack k (0-based): ``tear``, ``tear2``, ``tear3``, ..."""
        return self.name if k == 0 else f"{self.name}{k + 1}"

    def measure(self, body, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(per element of the body's current mesh: its largest principal stress or stretch,
        the principal direction (m, 3)) where the body is (configuration c)."""
        if self.stress is not None:
            sigma = body.cell_fields(c)["cauchy_stress"]
            w, v = np.linalg.eigh(0.5 * (sigma + np.swapaxes(sigma, 1, 2)))
            return w[:, -1], v[:, :, -1]
        F = body.model.kinematics.deformation_gradients(c)
        F = body.model.kinematics.cell_average(F)
        w, v = np.linalg.eigh(F @ np.swapaxes(F, 1, 2))  # left Cauchy-Green: spatial axes
        return np.sqrt(np.maximum(w[:, -1], 0.0)), v[:, :, -1]

    def grow(self, body, c: np.ndarray) -> list[tuple[str, PlanarCut | SweptCut]]:
        """The body's cracks after this step, as (cut name, the crack's whole surface: a plane
        bounded by a polygon, or once it has turned its pieces as a swept surface), from the
        body's configuration c (its current mesh): those whose plane crosses elements over
        the threshold (cutting it again takes the ones not taken yet)."""
        if not self.cracks:
            return []
        value, direction, X, span = self._field(body, c)
        over = value >= self.threshold
        grown = []
        for crack in self.cracks:
            surface = crack.grow(X, over, direction, span) if over.any() else None
            if surface is not None:
                grown.append((crack.name, surface))
        return grown

    def start(self, body, c: np.ndarray) -> tuple[str, PlanarCut] | None:
        """A new crack, as (cut name, its first plane bounded by a polygon), or None: through
        the element that exceeds the threshold most among those farther than FAR_CELLS of
        their own size (longest edge) from every crack, normal to its principal direction.
        Called when no crack grew in the step."""
        value, direction, X, span = self._field(body, c)
        over = value >= self.threshold
        centre = X.mean(axis=1)
        if self.cracks and over.any():
            size = np.linalg.norm(X[:, :, None] - X[:, None, :], axis=3).max(axis=(1, 2))
            near = np.min([crack.distance(centre) for crack in self.cracks], axis=0)
            over &= near > FAR_CELLS * size
        if not over.any():
            return None
        worst = int(np.argmax(np.where(over, value / self.threshold, -np.inf)))
        normal = direction[worst] / np.linalg.norm(direction[worst])
        crack = Crack(self.crack_name(len(self.cracks)), centre[worst], normal)
        surface = crack.grow(X, over, direction, span)
        if surface is None:
            return None
        self.cracks.append(crack)
        return crack.name, surface

    def _field(self, body, c: np.ndarray):
        """(each element's value and principal direction (m, 3), where its vertices are
        (m, k, 3), a 2D body's size (0 in 3D)) at configuration c."""
        value, direction = self.measure(body, c)
        mesh = body.mesh
        x = c.reshape(-1, mesh.dim)
        x = np.column_stack([x, np.zeros(len(x))]) if mesh.dim == 2 else x
        if direction.shape[1] == 2:
            direction = np.column_stack([direction, np.zeros(len(direction))])
        span = float(np.ptp(x, axis=0).max()) if mesh.dim == 2 else 0.0
        return value, direction, x[mesh.cells], span
