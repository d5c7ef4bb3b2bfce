"""A planar cut: a plane bounded by a convex polygon (the area a straight blade sweeps), the
input of the virtual node algorithm (``mesh/cutting/virtual_nodes.py``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError

__all__ = ["EMPTY", "PLANE_TOLERANCE", "PlanarCut"]

#: a vertex this close to the plane, relative to the element's size, counts as on it
PLANE_TOLERANCE = 1e-9
#: a face part (or a side's volume) below this fraction of the whole counts as empty
EMPTY = 1e-12


@dataclass(frozen=True)
class PlanarCut:
    """A cut in the plane through ``point`` with unit ``normal``, bounded by the convex
    ``polygon`` (k, 3) of points in that plane (counter-clockwise or clockwise)."""

    point: np.ndarray
    normal: np.ndarray
    polygon: np.ndarray

    @classmethod
    def swept_segment(cls, a0, b0, a1, b1) -> PlanarCut:
        """The area a straight blade edge sweeps from segment a0-b0 to a1-b1 (moved without
        turning out of its plane: the four points must be coplanar)."""
        p = np.array([a0, b0, b1, a1], dtype=float)
        if p.shape != (4, 3):
            raise InputError("a swept segment is four 3D points: a0, b0, a1, b1")
        n = np.cross(p[1] - p[0], p[3] - p[0])
        if np.linalg.norm(n) == 0.0:
            n = np.cross(p[1] - p[0], p[2] - p[0])
        size = float(np.max(np.linalg.norm(p - p[0], axis=1)))
        if np.linalg.norm(n) <= 1e-12 * size**2:
            raise InputError("the blade sweeps no area (it moved along itself or not at all)")
        n = n / np.linalg.norm(n)
        off = np.abs((p - p[0]) @ n).max()
        if off > 1e-9 * size:
            raise InputError(
                f"the swept segment is not planar (a corner {off:.3g} m off the plane of the "
                "others); split the motion into steps that are"
            )
        return cls(p[0].copy(), n, p)

    @classmethod
    def hull(cls, points: np.ndarray, point: np.ndarray, normal: np.ndarray) -> PlanarCut | None:
        """The cut in the plane (point, normal) bounded by the convex hull of ``points`` (k, 3)
        in it, grown by 1e-6 of its size (so sections the points came from lie inside), or None
        when they span no area."""
        from scipy.spatial import ConvexHull, QhullError

        u = np.cross(normal, [1.0, 0.0, 0.0])
        if np.linalg.norm(u) < 0.5:
            u = np.cross(normal, [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        w = np.cross(normal, u)
        flat = np.column_stack([(points - point) @ u, (points - point) @ w])
        if len(flat) < 3:
            return None
        try:
            ring = flat[ConvexHull(flat).vertices]
        except QhullError:
            return None
        centre = ring.mean(axis=0)
        size = float(np.ptp(ring, axis=0).max())
        ring = centre + (ring - centre) * (1.0 + 1e-6) + 1e-9 * size * np.sign(ring - centre)
        return cls(point, normal, point + ring[:, :1] * u + ring[:, 1:] * w)

    # -- what the virtual node algorithm asks of a cut (mesh/cutting/swept_cut.py answers it too)
    def distances(self, x: np.ndarray) -> np.ndarray:
        """Signed distances (...) of points x (..., 3) to the plane."""
        return (np.asarray(x, dtype=float) - self.point) @ self.normal

    def sections_inside(self, x: np.ndarray, d: np.ndarray) -> np.ndarray:
        """Whether each simplex's section of the plane (x (m, k, 3) its vertices, d (m, k)
        their distances) lies in the polygon (plane_split.sections_inside). Returns (m,)."""
        from tissuesim.mesh.cutting.plane_split import sections_inside

        return sections_inside(x, d, self.polygon, self.normal)

    def reach(self, q: np.ndarray) -> np.ndarray:
        """How far points q (n, 3) in the plane lie outside the polygon (0 inside): the largest
        distance outside one of its edge lines (the distance outside it, or less near a
        corner), as ``SweptCut.reach`` says of its triangles."""
        poly, n = self.polygon, self.normal
        centre = poly.mean(axis=0)
        out = np.zeros(len(q))
        for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
            outward = np.cross(b - a, n)
            norm = np.linalg.norm(outward)
            if norm == 0.0:
                continue
            outward /= norm
            if outward @ (centre - a) > 0.0:
                outward = -outward
            out = np.maximum(out, (q - a) @ outward)
        return out

    def triangles(self) -> np.ndarray:
        """The polygon as a fan of triangles (k - 2, 3, 3), each turning about the normal."""
        c = self.polygon
        tris = np.stack([np.broadcast_to(c[0], c[1:-1].shape), c[1:-1], c[2:]], axis=1)
        flip = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]) @ self.normal < 0.0
        tris[flip] = tris[flip][:, ::-1]
        return tris

    def covers(self, q: np.ndarray, tol: float) -> bool:
        """Whether points q (k, 3) in the plane lie in its convex polygon (within tol, m)."""
        poly, n = self.polygon, self.normal
        centre = poly.mean(axis=0)
        for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
            inward = np.cross(n, b - a)
            if inward @ (centre - a) < 0.0:
                inward = -inward
            inward = inward / np.linalg.norm(inward)
            if np.any((q - a) @ inward < -tol):
                return False
        return True
