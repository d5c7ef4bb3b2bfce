"""A cut along a curved surface: what a blade sweeps when it does not stay in one plane (it
turns, tilts or follows a curved path), as the triangles between its sampled positions.

The virtual node algorithm (``mesh/cutting/virtual_nodes.py``) needs, per cut, a signed distance at
the cells' vertices (linear in each cell, so each cell's cut is planar and its fractions are
closed forms) and whether a crossed cell's section lies on what was swept. Here the distance
of a point is its signed distance to the supporting plane of the swept triangle nearest to
it: on a planar sweep exactly ``PlanarCut``'s distance, on a curved one the local tangent
plane, so each cell is cut along the plane of the swept surface where it passes (the cut
surface is then within O(h^2 kappa) of the swept surface, h the cell's size, kappa the
surface's curvature). A crossed cell is cut when every point of its section lies over the
swept triangles (its offset along the surface beyond them, not across it, within
``SECTION_TOLERANCE`` of the cell's size): the blade has passed through it completely, as a
planar cut's section must lie in its polygon.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError

__all__ = ["SweptCut", "closest_points", "SECTION_TOLERANCE"]

#: a section point this far from the swept triangles, relative to its cell's size, is not on
#: them (the blade has not reached it); it covers the linear level's own error on a curved
#: surface, h^2 kappa / 8: 1 % of h where h is 8 % of the radius of curvature
SECTION_TOLERANCE = 2e-2
#: points per chunk in the point-triangle distance (bounds the (points, triangles) arrays)
CHUNK = 4096


def closest_points(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The closest points (n, k, 3) on triangles (a, b, c) (k, 3 each) to points p (n, 3), by
    the Voronoi regions of the triangle's vertices, edges and face (Ericson, Real-Time Collision
    Detection, 5.1.5), for every point and triangle at once."""
    p = p[:, None, :]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = p - b
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = p - c
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = np.where(denom != 0.0, vb / denom, 0.0)
        w = np.where(denom != 0.0, vc / denom, 0.0)
        out = a + v[..., None] * ab + w[..., None] * ac  # inside the face
        # edge bc
        wbc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        on_bc = (va <= 0.0) & (d4 - d3 >= 0.0) & (d5 - d6 >= 0.0)
        out = np.where(on_bc[..., None], b + wbc[..., None] * (c - b), out)
        # edge ac
        wac = d2 / (d2 - d6)
        on_ac = (vb <= 0.0) & (d2 >= 0.0) & (d6 <= 0.0)
        out = np.where(on_ac[..., None], a + wac[..., None] * ac, out)
        # edge ab
        vab = d1 / (d1 - d3)
        on_ab = (vc <= 0.0) & (d1 >= 0.0) & (d3 <= 0.0)
        out = np.where(on_ab[..., None], a + vab[..., None] * ab, out)
    # the vertices' regions
    out = np.where(((d6 >= 0.0) & (d5 <= d6))[..., None], c, out)
    out = np.where(((d3 >= 0.0) & (d4 <= d3))[..., None], b, out)
    out = np.where(((d1 <= 0.0) & (d2 <= 0.0))[..., None], a, out)
    return np.broadcast_to(out, (p.shape[0], a.shape[0], 3))


@dataclass(frozen=True, eq=False)
class SweptCut:
    """A cut along the triangles (k, 3, 3) a blade swept, oriented alike (their normals on
    one side of the surface)."""

    triangles: np.ndarray

    def __post_init__(self) -> None:
        t = np.asarray(self.triangles, dtype=float)
        if t.ndim != 3 or t.shape[1:] != (3, 3) or not len(t):
            raise InputError(f"a swept cut is triangles (k, 3, 3), not shape {t.shape}")
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        area = np.linalg.norm(n, axis=1)
        keep = area > 1e-12 * max(float(area.max()), 1e-300)
        if not keep.any():
            raise InputError("the blade sweeps no area (it moves along itself or not at all)")
        object.__setattr__(self, "triangles", np.ascontiguousarray(t[keep]))
        object.__setattr__(self, "normals", n[keep] / area[keep, None])

    @classmethod
    def from_blades(cls, blades: Sequence[np.ndarray]) -> SweptCut:
        """The surface a blade swept through its sampled positions, each an edge (2, 3) or a
        triangle (3, 3): the two triangles between consecutive edges (a triangle blade: its
        own triangles and those its edges swept), oriented as the first."""
        P = [np.asarray(b, dtype=float) for b in blades]
        tris = []
        for p, q in zip(P[:-1], P[1:], strict=True):
            for i, j in ((0, 1), (1, 2), (2, 0)) if len(p) == 3 else ((0, 1),):
                tris.append([p[i], p[j], q[j]])
                tris.append([p[i], q[j], q[i]])
        tris += [p for p in P if len(p) == 3]
        t = np.array(tris)
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        big = np.argmax(np.linalg.norm(n, axis=1))
        flip = (n @ n[big]) < 0.0  # a smooth sweep: every triangle faces the largest's side
        t[flip] = t[flip][:, ::-1]
        return cls(t)

    def _nearest(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(index of the nearest triangle (n,), distance to it (n,), the closest point on it
        (n, 3)) of points x (n, 3)."""
        t = self.triangles
        index, gap = np.empty(len(x), dtype=np.int64), np.empty(len(x))
        closest = np.empty((len(x), 3))
        for s in range(0, len(x), CHUNK):
            q = x[s : s + CHUNK]
            cp = closest_points(q, t[:, 0], t[:, 1], t[:, 2])
            dist = np.linalg.norm(cp - q[:, None, :], axis=2)
            k = np.argmin(dist, axis=1)
            rows = np.arange(len(q))
            index[s : s + CHUNK] = k
            gap[s : s + CHUNK] = dist[rows, k]
            closest[s : s + CHUNK] = cp[rows, k]
        return index, gap, closest

    def distances(self, x: np.ndarray) -> np.ndarray:
        """Signed distances (...) of points x (..., 3) to the supporting plane of the swept
        triangle nearest to each (on a planar sweep: the distance to its plane)."""
        x = np.asarray(x, dtype=float)
        # the cells' vertices repeat their nodes' positions: each position once
        flat, inverse = np.unique(x.reshape(-1, 3), axis=0, return_inverse=True)
        k, _, _ = self._nearest(flat)
        d = ((flat - self.triangles[k, 0]) * self.normals[k]).sum(axis=1)
        return d[inverse.ravel()].reshape(x.shape[:-1])

    def gaps(self, x: np.ndarray) -> np.ndarray:
        """Distances (...) of points x (..., 3) to the swept triangles (0 on them)."""
        x = np.asarray(x, dtype=float)
        return self._nearest(x.reshape(-1, 3))[1].reshape(x.shape[:-1])

    def reach(self, x: np.ndarray) -> np.ndarray:
        """How far (...) points x (..., 3) lie beyond the swept triangles along the surface:
        the distance to the closest point less its part along the nearest triangle's normal
        (0 over the triangles at any height above them, as a planar cut's polygon test)."""
        x = np.asarray(x, dtype=float)
        flat = x.reshape(-1, 3)
        k, _, closest = self._nearest(flat)
        v = flat - closest
        v = v - (v * self.normals[k]).sum(axis=1)[:, None] * self.normals[k]
        return np.linalg.norm(v, axis=1).reshape(x.shape[:-1])

    def sections_inside(self, x: np.ndarray, d: np.ndarray) -> np.ndarray:
        """Whether each simplex's section (where its linear distance d (m, k) is zero; x its
        vertices (m, k, 3)) lies on the swept triangles within SECTION_TOLERANCE of its size:
        the blade has passed through it. Returns (m,)."""
        m, k = d.shape
        if not m:
            return np.zeros(0, dtype=bool)
        i, j = np.triu_indices(k, 1)
        di, dj = d[:, i], d[:, j]
        crosses = di * dj < 0.0
        t = np.where(crosses, di / np.where(crosses, di - dj, 1.0), 0.0)
        points = np.concatenate([x, x[:, i] + t[..., None] * (x[:, j] - x[:, i])], axis=1)
        valid = np.concatenate([d == 0.0, crosses], axis=1)
        size = np.linalg.norm(x.max(axis=1) - x.min(axis=1), axis=1)
        gap = np.zeros(valid.shape)
        gap[valid] = self.reach(points[valid])
        return np.all(gap <= SECTION_TOLERANCE * size[:, None], axis=1)

    def covers(self, q: np.ndarray, tol: float) -> bool:
        """Whether points q (k, 3) on the surface's planes lie over the swept triangles
        (within tol, m): what ``PlanarCut.covers`` says of its polygon."""
        return bool(np.all(self.reach(q) <= tol))
