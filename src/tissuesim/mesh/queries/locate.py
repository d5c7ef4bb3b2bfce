"""Point queries against a tetrahedral mesh: closest boundary point, inside test, distance.

Both queries are exact (up to rounding) and batched. Candidates come from a scipy cKDTree over
triangle (or tetrahedron) centroids: a point's k nearest centroids are tested, and the answer is
accepted once no untested simplex can do better, which a bounding-sphere argument decides: an
untested simplex has its centroid at least as far as the (k+1)-th nearest one, d_{k+1}, and
every point of it lies within R (the largest centroid-to-vertex distance of all simplices) of
its centroid. Points that are not settled are retried with 4 times as many candidates (only
the new ones are evaluated), up to all simplices. Typical queries near the surface settle with
the first 16 candidates; points far from it (compared with the triangle size) need more rounds,
up to brute force for points far outside a small mesh. Distance queries with a cap (``MeshLocator
.distance(points, max_distance)``) stop as soon as nothing untested can come that close.
Lengths are in the mesh's units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from tissuesim.errors import InputError
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries.boundary import _LOCAL_FACETS, boundary_from_table, facet_table
from tissuesim.validate import short

__all__ = [
    "ClosestPoints",
    "MeshLocator",
    "TriangleSoup",
    "closest_on_triangles",
    "closest_boundary_points",
    "inside_mesh",
    "distance_to_boundary",
]

# Point-simplex pairs evaluated at once (a few hundred bytes each).
_PAIRS_PER_CHUNK = 1 << 16
# Candidates tried first, and the growth factor of the retries.
_FIRST_CANDIDATES = 16
_GROWTH = 4
# A point is inside a tetrahedron when all its barycentric coordinates are >= -this.
_BARYCENTRIC_TOLERANCE = 1e-10
# A triangle is degenerate when |ab x ac| <= this * (longest edge)^2.
_DEGENERATE = 1e-12


def _edge_closest(apap, da, ee):
    """(t, squared distance) to the segment a + t e, t in [0, 1], from d = p - a.

    apap = d . d, da = d . e, ee = e . e (0 for a point); all (n,).
    """
    t = np.clip(np.divide(da, ee, out=np.zeros_like(da), where=ee > 0), 0.0, 1.0)
    return t, apap - 2.0 * t * da + t * t * ee


def _closest_vw(ap, ab, ac, bb, cc, bc, degenerate):
    """Barycentric (v, w) of the closest point a + v ab + w ac of triangles to points.

    ap = p - a, ab = b - a, ac = c - a: tuples of 3 component arrays (n,); bb = ab.ab,
    cc = ac.ac, bc = ab.ac, degenerate (n,) bool: all paired. Ericson's Voronoi regions,
    Real-Time Collision Detection 5.1.5, for every pair at once; degenerate triangles take the
    nearest of their three edges instead, as the segment or point they are.
    """
    d1 = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2]
    d2 = ac[0] * ap[0] + ac[1] * ap[1] + ac[2] * ap[2]
    d3, d4, d5, d6 = d1 - bb, d2 - bc, d1 - bc, d2 - cc  # ab.bp, ac.bp, ab.cp, ac.cp
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v, w = vb / denom, vc / denom  # face region
        # the regions in reverse order of precedence, so that the first that applies wins
        e = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        region = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)  # edge bc
        v, w = np.where(region, 1.0 - e, v), np.where(region, e, w)
        region = (vb <= 0) & (d2 >= 0) & (d6 <= 0)  # edge ac
        v, w = np.where(region, 0.0, v), np.where(region, d2 / (d2 - d6), w)
        region = (d6 >= 0) & (d5 <= d6)  # vertex c
        v, w = np.where(region, 0.0, v), np.where(region, 1.0, w)
        region = (vc <= 0) & (d1 >= 0) & (d3 <= 0)  # edge ab
        v, w = np.where(region, d1 / (d1 - d3), v), np.where(region, 0.0, w)
        region = (d3 >= 0) & (d4 <= d3)  # vertex b
        v, w = np.where(region, 1.0, v), np.where(region, 0.0, w)
        region = (d1 <= 0) & (d2 <= 0)  # vertex a
        v, w = np.where(region, 0.0, v), np.where(region, 0.0, w)
    bad = degenerate | ~(np.isfinite(v) & np.isfinite(w))
    if bad.any():
        k = np.flatnonzero(bad)
        apap = ap[0][k] ** 2 + ap[1][k] ** 2 + ap[2][k] ** 2
        bbk, cck, bck, d1k, d2k = bb[k], cc[k], bc[k], d1[k], d2[k]
        t_ab, e_ab = _edge_closest(apap, d1k, bbk)
        t_ac, e_ac = _edge_closest(apap, d2k, cck)
        # edge b -> c from b: (p - b).(c - b) = d2 - bc - d1 + bb, |p - b|^2 = apap - 2 d1 + bb
        t_bc, e_bc = _edge_closest(apap - 2 * d1k + bbk, d2k - bck - d1k + bbk, bbk + cck - 2 * bck)
        vk, wk = t_ab, np.zeros(len(k))
        use = e_ac < e_ab
        vk, wk, best = np.where(use, 0.0, vk), np.where(use, t_ac, wk), np.minimum(e_ab, e_ac)
        use = e_bc < best
        vk, wk = np.where(use, 1.0 - t_bc, vk), np.where(use, t_bc, wk)
        v, w = v.copy(), w.copy()
        v[k], w[k] = vk, wk
    v, w = np.clip(v, 0.0, 1.0), np.clip(w, 0.0, 1.0)
    over = v + w > 1.0
    s = np.where(over, v + w, 1.0)
    return v / s, w / s


def closest_on_triangles(
    p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Closest points of triangles (a, b, c) to points p, paired: all (n, 3).

    Returns (barycentric (n, 3) >= 0 summing to 1, positions (n, 3) = bary @ (a, b, c)). The
    Voronoi-region tests of Ericson, Real-Time Collision Detection 5.1.5, evaluated for every
    pair and merged in his order of precedence. Degenerate (zero-area) triangles get the closest
    point of their three edges instead, so they behave as the segment or point they are.
    """
    p, a, b, c = (np.asarray(x, dtype=np.float64) for x in (p, a, b, c))
    ab, ac, ap = (b - a).T, (c - a).T, (p - a).T
    bb, cc, bc = (ab * ab).sum(axis=0), (ac * ac).sum(axis=0), (ab * ac).sum(axis=0)
    v, w = _closest_vw(tuple(ap), tuple(ab), tuple(ac), bb, cc, bc, _degenerate(ab, ac, bb, cc, bc))
    bary = np.column_stack([np.maximum(1.0 - v - w, 0.0), v, w])
    return bary, a + v[:, None] * (b - a) + w[:, None] * (c - a)


def _degenerate(ab, ac, bb, cc, bc) -> np.ndarray:
    """(n,) bool: |ab x ac| <= _DEGENERATE * (longest edge)^2, from (3, n) edge components."""
    area2 = (np.cross(ab.T, ac.T) ** 2).sum(axis=1)
    longest = np.maximum(np.maximum(bb, cc), bb + cc - 2.0 * bc)
    return area2 <= (_DEGENERATE * longest) ** 2


def _query(tree: cKDTree, x: np.ndarray, k: int, upper: float) -> tuple[np.ndarray, np.ndarray]:
    """k nearest (distances, indices) as (q, k) arrays; missing ones: inf and tree.n."""
    d, i = tree.query(x, k=k, distance_upper_bound=upper, workers=-1)
    return d.reshape(len(x), k), i.reshape(len(x), k)


def _points(func: str, points) -> np.ndarray:
    try:
        p = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{func}: points must be a (q, 3) array of numbers: {exc}") from exc
    if p.ndim == 1 and p.shape == (3,):
        raise InputError(f"{func}: points must have shape (q, 3); for one point use [point]")
    if p.ndim != 2 or p.shape[1] != 3:
        raise InputError(f"{func}: points must have shape (q, 3), got {p.shape}")
    if not np.isfinite(p).all():
        i = int(np.flatnonzero(~np.isfinite(p).all(axis=1))[0])
        raise InputError(f"{func}: point {i} is not finite: {p[i].tolist()}")
    return p


class TriangleSoup:
    """Closest-point queries against triangles (m, 3, 3) with a cKDTree over their centroids.

    Triangles need not be connected or non-degenerate. Build once, query many times; the
    per-triangle constants of the closest-point kernel are precomputed.
    """

    def __init__(self, triangles: np.ndarray) -> None:
        tri = np.ascontiguousarray(triangles, dtype=np.float64)
        if tri.ndim != 3 or tri.shape[1:] != (3, 3) or len(tri) == 0:
            raise InputError(f"triangles must have shape (m, 3, 3) with m >= 1, got {tri.shape}")
        self.triangles = tri
        self.centroids = tri.mean(axis=1)
        self.radii = np.sqrt(((tri - self.centroids[:, None]) ** 2).sum(axis=2).max(axis=1))
        self.radius = float(self.radii.max())
        self.tree = cKDTree(self.centroids)
        self.a = np.ascontiguousarray(tri[:, 0].T)  # (3, m) components
        self.ab = np.ascontiguousarray((tri[:, 1] - tri[:, 0]).T)
        self.ac = np.ascontiguousarray((tri[:, 2] - tri[:, 0]).T)
        self.bb = (self.ab**2).sum(axis=0)
        self.cc = (self.ac**2).sum(axis=0)
        self.bc = (self.ab * self.ac).sum(axis=0)
        self.degenerate = _degenerate(self.ab, self.ac, self.bb, self.cc, self.bc)

    @property
    def m(self) -> int:
        return len(self.triangles)

    def _pairs(self, x: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(v (n,), w (n,), distance (n,)) from points x (n, 3) to triangles t (n,), paired."""
        ap = tuple(x[:, i] - self.a[i][t] for i in range(3))
        ab = tuple(self.ab[i][t] for i in range(3))
        ac = tuple(self.ac[i][t] for i in range(3))
        v, w = _closest_vw(ap, ab, ac, self.bb[t], self.cc[t], self.bc[t], self.degenerate[t])
        d2 = sum((v * ab[i] + w * ac[i] - ap[i]) ** 2 for i in range(3))
        return v, w, np.sqrt(d2)

    def _result(self, t: np.ndarray, v: np.ndarray, w: np.ndarray):
        """(barycentric (n, 3), positions (n, 3)) of the closest points a + v ab + w ac."""
        bary = np.column_stack([np.maximum(1.0 - v - w, 0.0), v, w])
        return bary, np.einsum("nk,nki->ni", bary, self.triangles[t])

    def closest(
        self, points: np.ndarray, max_distance: float = np.inf, with_points: bool = True
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(triangle (q,), barycentric (q, 3), positions (q, 3), distance (q,)) per point.

        Exact for points within ``max_distance``; farther ones get triangle -1, NaN barycentric
        and positions, and distance inf. A finite max_distance also ends the search early: only
        triangles whose bounding sphere comes within it are candidates. with_points False
        leaves barycentric and positions NaN (for distance-only queries).
        """
        q = len(points)
        tri_id = np.full(q, -1, dtype=np.int64)
        v_out, w_out = np.full(q, np.nan), np.full(q, np.nan)
        dist = np.full(q, np.inf)
        self._search(points, float(max_distance), tri_id, v_out, w_out, dist)
        bary = np.full((q, 3), np.nan)
        pos = np.full((q, 3), np.nan)
        found = np.flatnonzero(tri_id >= 0)
        if not with_points:  # distances only: skip the (q, 3) results
            return tri_id, bary, pos, dist
        bary[found], pos[found] = self._result(tri_id[found], v_out[found], w_out[found])
        return tri_id, bary, pos, dist

    def _search(self, points, max_distance, tri_id, v_out, w_out, dist) -> None:
        """Fill the outputs for the points within max_distance (all if inf); others untouched.

        Rounds of k nearest centroids (k = 16, 64, ... up to m), evaluating only the new
        candidates of each round. A point is settled when no untested triangle can be nearer
        than its best (d_{k+1} - radius >= best), or, for a finite max_distance, when no untested
        triangle can come within max_distance (d_{k+1} > max_distance + radius).
        """
        m = self.m
        reach = (max_distance + self.radius) * (1.0 + 1e-12) + 1e-300
        q = len(points)
        best_d = np.full(q, np.inf)
        best_t = np.full(q, -1, dtype=np.int64)
        best_v, best_w = np.zeros(q), np.zeros(q)
        pending = np.arange(q)
        done_k, k = 0, min(_FIRST_CANDIDATES, m)
        while len(pending):
            last = k >= m
            dd, ii = _query(self.tree, points[pending], k if last else k + 1, reach)
            rows = max(1, _PAIRS_PER_CHUNK // (k - done_k))
            for s in range(0, len(pending), rows):
                c = ii[s : s + rows, done_k:k]  # this round's new candidates
                n = len(c)
                r, j = np.nonzero(c < m)
                t = c[r, j]
                # skip triangles surely beyond max_distance or the best so far: their centroid
                # is farther than that plus their own radius
                limit = np.minimum(best_d[pending[s + r]], max_distance) * (1.0 + 1e-12)
                keep = dd[s + r, done_k + j] - self.radii[t] <= limit
                r, j, t = r[keep], j[keep], t[keep]
                if len(r) == 0:
                    continue
                v, w, d = self._pairs(points[pending[s + r]], t)
                dense = np.full(c.shape, np.inf)
                dense[r, j] = d
                win = np.argmin(dense, axis=1)  # ties: the nearest centroid
                at = np.arange(n)
                slot = np.full(c.shape, -1, dtype=np.int64)
                slot[r, j] = np.arange(len(r))
                better = np.flatnonzero(dense[at, win] < best_d[pending[s : s + n]])
                k_ = slot[better, win[better]]
                i_ = pending[s + better]
                best_d[i_], best_t[i_], best_v[i_], best_w[i_] = d[k_], t[k_], v[k_], w[k_]
            settled = np.full(len(pending), last)
            if not last:
                settled |= best_d[pending] <= dd[:, k] - self.radius
                settled |= dd[:, k] > reach  # inf when missing
            pending = pending[~settled]
            done_k, k = k, min(k * _GROWTH, m)
        found = np.flatnonzero(best_d <= max_distance)
        tri_id[found], v_out[found], w_out[found] = best_t[found], best_v[found], best_w[found]
        dist[found] = best_d[found]


@dataclass(frozen=True, eq=False)
class ClosestPoints:
    """Closest points of a mesh's boundary to query points (q of them).

    cells (q,) int64: the tetrahedron owning the boundary triangle the closest point lies on
        (an index into ``mesh.simplices``: for quadratic meshes a tetrahedron of the linear
        subdivision).
    barycentric (q, 4): the closest point's coordinates in that tetrahedron (>= 0, summing to
    1, 0 at the vertex opposite the triangle), so it moves with the mesh as
    sum_a barycentric[:, a] * x[cells[:, a]]. positions (q, 3): the closest points.
    distance (q,): unsigned distances from the query points to them.
    """

    cells: np.ndarray
    barycentric: np.ndarray
    positions: np.ndarray
    distance: np.ndarray


class MeshLocator:
    """Search structures of one tetrahedral mesh, built once for repeated point queries.

    The module functions build one per call; keep a MeshLocator when querying the same mesh
    (same rest positions) several times. Boundary triangles and tetrahedra are indexed lazily;
    after the first boundary query, ``facets`` (k, 3) holds the outward boundary triangles (as
    ``boundary_facets``), ``facet_cell`` (k,) their tetrahedra.
    """

    def __init__(self, mesh: Mesh, func: str = "MeshLocator") -> None:
        if not isinstance(mesh, Mesh):
            raise InputError(f"{func}: mesh must be a tissuesim Mesh, got {type(mesh).__name__}")
        if mesh.dim != 3 or mesh.simplices.shape[1] != 4:
            raise InputError(
                f"{func}: {mesh.source} is a {mesh.dim}D mesh; tetrahedra are needed: use "
                f"tissuesim.mesh.box, ellipsoid or a tetrahedral mesh file"
            )
        self.mesh = mesh
        self._soup: TriangleSoup | None = None
        self._tets: tuple[cKDTree, np.ndarray, np.ndarray, np.ndarray] | None = None

    def _boundary(self) -> TriangleSoup:
        if self._soup is None:
            table = facet_table(self.mesh.simplices)
            facets, first, _, counts = table
            which = np.sort(first[counts == 1])  # index into the (m * 4) cell facets
            self.facets = boundary_from_table(*table)  # (k, 3) outward boundary triangles
            self.facet_cell = which // 4  # owning tetrahedron
            self.facet_local = _LOCAL_FACETS[3][which % 4]  # (k, 3) local vertex ids in it
            self._soup = TriangleSoup(self.mesh.points[self.facets])
        return self._soup

    def closest_boundary_points(self, points: np.ndarray) -> ClosestPoints:
        """See ``closest_boundary_points``."""
        p = _points("closest_boundary_points", points)
        soup = self._boundary()
        tri, bary, pos, dist = soup.closest(p)
        b4 = np.zeros((len(p), 4))
        np.put_along_axis(b4, self.facet_local[tri], bary, axis=1)
        return ClosestPoints(self.facet_cell[tri].astype(np.int64), b4, pos, dist)

    def distance(self, points: np.ndarray, max_distance: float = np.inf) -> np.ndarray:
        """Unsigned distance (q,) to the boundary; inf where it exceeds ``max_distance``."""
        p = _points("distance_to_boundary", points)
        if not (isinstance(max_distance, int | float | np.floating) and max_distance >= 0):
            raise InputError(
                f"distance_to_boundary: max_distance must be a number >= 0 (inf for no cap), "
                f"got {short(max_distance)}"
            )
        return self._boundary().closest(p, max_distance, with_points=False)[3]

    def _tet_index(self) -> tuple[cKDTree, np.ndarray, np.ndarray, np.ndarray]:
        """(tree of centroids, radii (n,), inverse edge matrices (n, 3, 3), first vertices)."""
        if self._tets is None:
            x = self.mesh.points[self.mesh.simplices]  # (n, 4, 3)
            centroids = x.mean(axis=1)
            radii = np.sqrt(((x - centroids[:, None]) ** 2).sum(axis=2).max(axis=1))
            # rows of inv are the gradients of barycentric coordinates 1..3
            inv = np.linalg.inv(np.transpose(x[:, 1:] - x[:, :1], (0, 2, 1)))
            self._tets = (cKDTree(centroids), radii, inv, np.ascontiguousarray(x[:, 0]))
        return self._tets

    def inside(self, points: np.ndarray) -> np.ndarray:
        """See ``inside_mesh``."""
        p = _points("inside_mesh", points)
        tree, radii, inv, x0 = self._tet_index()
        n = self.mesh.simplices.shape[0]
        result = np.zeros(len(p), dtype=bool)
        # a tetrahedron containing x has its centroid within its radius of x
        upper = float(radii.max()) * (1.0 + 1e-9)
        pending = np.arange(len(p))
        done_k, k = 0, min(8, n)
        while len(pending):
            last = k >= n
            dd, ii = _query(tree, p[pending], k if last else k + 1, upper)
            hit = np.zeros(len(pending), dtype=bool)
            rows = max(1, _PAIRS_PER_CHUNK // (k - done_k))
            for s in range(0, len(pending), rows):
                c = ii[s : s + rows, done_k:k]  # this round's new candidates
                r, j = np.nonzero(c < n)
                t = c[r, j]
                keep = dd[s + r, done_k + j] <= radii[t] * (1.0 + 1e-9)
                r, t = r[keep], t[keep]
                if len(r) == 0:
                    continue
                lam = np.einsum("kij,kj->ki", inv[t], p[pending[s + r]] - x0[t])
                ok = (lam >= -_BARYCENTRIC_TOLERANCE).all(axis=1)
                ok &= lam.sum(axis=1) <= 1.0 + _BARYCENTRIC_TOLERANCE
                hit[s + r[ok]] = True
            # settled: found, or every tetrahedron that could hold the point was tested
            settled = hit | last
            if not last:
                settled |= ~np.isfinite(dd[:, k])
            result[pending[hit]] = True
            pending = pending[~settled]
            done_k, k = k, min(k * _GROWTH, n)
        return result


def closest_boundary_points(mesh: Mesh, points: np.ndarray) -> ClosestPoints:
    """Closest points of the boundary surface of tetrahedral ``mesh`` to ``points`` (q, 3).

    Exact (point-triangle closest points by Voronoi regions over KD-tree candidates, settled by
    the bounding-sphere test in the module docstring, not by a fixed candidate count). Each
    result also names the owning tetrahedron and the barycentric coordinates in it, so the
    point can follow the deformed mesh. Ties (equally close triangles) go to one of them.
    """
    return MeshLocator(mesh, "closest_boundary_points").closest_boundary_points(points)


def inside_mesh(mesh: Mesh, points: np.ndarray) -> np.ndarray:
    """(q,) bool: whether each of ``points`` (q, 3) lies in a tetrahedron of ``mesh``.

    Point location: the tetrahedra whose centroids are nearest each point are tested with
    barycentric coordinates (closed, tolerance 1e-10, so points on the boundary count as
    inside); the search widens until it finds one or until every tetrahedron whose bounding
    sphere could contain the point has been tested. No surface orientation or watertightness is
    assumed, and points far from the mesh are rejected by the KD-tree alone.
    """
    return MeshLocator(mesh, "inside_mesh").inside(points)


def distance_to_boundary(mesh: Mesh, points: np.ndarray) -> np.ndarray:
    """Unsigned distance (q,) from ``points`` (q, 3) to the boundary surface of ``mesh``.

    Same exact search as ``closest_boundary_points``; positive inside the mesh too (combine with
    ``inside_mesh`` for a signed distance).
    """
    return MeshLocator(mesh, "distance_to_boundary").distance(points)
