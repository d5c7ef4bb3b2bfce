"""Points embedded in a simplex mesh by barycentric coordinates (SOFA's barycentric mapping).

Each point is given, once, at rest, the simplex of ``mesh.simplices`` that holds it (a
tetrahedron in 3D, a triangle in 2D; for P2, Q1 and wedge meshes a simplex of their linear
subdivision or split, so every cell type is handled alike) and its barycentric coordinates
there; it then moves with the mesh as ``x_p = sum_a w_pa x[v_pa]``, one sparse matrix product
(``Embedding.positions``). The map reproduces any affine motion of the mesh exactly, outside
points included: barycentric coordinates are affine coordinates.

Points outside the mesh (a fine surface sticks out of a coarse mesh by up to an element) are
mapped to the simplex owning the closest boundary facet, with coordinates extrapolated from it
(some negative); ``outside`` and ``distance`` say which and how far.

Vectorised: KD-trees over the points and the simplex centroids give every pair within the
largest centroid-to-vertex radius (no simplex farther can hold the point), tested by their
coordinates where the point lies within that simplex's own radius; the outside points go
to ``locate.TriangleSoup`` (the boundary facets; in 2D the boundary edges as flat triangles in
z = 0). Flat simplices (a hexahedral split's fillers between two hexahedra) never hold a point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from tissuesim.errors import InputError
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries.boundary import facet_table
from tissuesim.mesh.queries.locate import _PAIRS_PER_CHUNK, TriangleSoup

__all__ = ["Embedding", "embed_points"]

#: a point is inside a simplex when all its barycentric coordinates are >= -this
TOLERANCE = 1e-10
#: a simplex is flat when |det(edges)| <= this * (longest edge)^d
FLAT = 1e-12
#: points per KD-tree pair search (about 60 candidate pairs each near a surface)
_POINTS_PER_CHUNK = 1 << 14


@dataclass(frozen=True, eq=False)
class Embedding:
    """Where each of q points sits in a mesh of n points (``embed_points``).

    cells (q,): the simplex of ``mesh.simplices`` that carries the point; vertices (q, d + 1)
    its vertex ids; weights (q, d + 1) the point's barycentric coordinates there (summing to 1,
    some negative for a point outside the mesh); outside (q,) bool; distance (q,): from the
    point to the mesh at rest (0 inside); size (q,): the carrying simplex's longest edge;
    matrix: the (q, n) sparse map, positions = matrix @ x.
    """

    cells: np.ndarray
    vertices: np.ndarray
    weights: np.ndarray
    outside: np.ndarray
    distance: np.ndarray
    size: np.ndarray
    matrix: sp.csr_matrix

    @property
    def n(self) -> int:
        return len(self.cells)

    def positions(self, x: np.ndarray) -> np.ndarray:
        """The points (q, d) where the mesh's points are at ``x`` (n, d)."""
        return np.asarray(self.matrix @ np.asarray(x, dtype=np.float64))

    def interpolate(self, values: np.ndarray) -> np.ndarray:
        """Point values of the mesh (n,) or (n, k) at the embedded points (q,) or (q, k)."""
        return np.asarray(self.matrix @ np.asarray(values, dtype=np.float64))


def _simplex_data(x: np.ndarray, simplices: np.ndarray):
    """(first vertices (m, d), inverse edge matrices (m, d, d), valid (m,), longest edges)."""
    v = x[simplices]  # (m, d + 1, d)
    d = v.shape[2]
    x0 = np.ascontiguousarray(v[:, 0])
    edges = v[:, 1:] - v[:, :1]  # (m, d, d): rows are the edges from vertex 0
    pairs = [(i, j) for i in range(d + 1) for j in range(i + 1, d + 1)]
    longest = np.max([np.linalg.norm(v[:, i] - v[:, j], axis=1) for i, j in pairs], axis=0)
    det = np.linalg.det(edges)
    valid = np.abs(det) > FLAT * longest**d
    inv = np.zeros_like(edges)
    # rows of inv(edges^T) are the gradients of barycentric coordinates 1..d
    inv[valid] = np.linalg.inv(np.transpose(edges[valid], (0, 2, 1)))
    return x0, inv, valid, longest


def _coordinates(inv, x0, t: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Barycentric coordinates (k, d + 1) of points p (k, d) in simplices t (k,)."""
    lam = np.einsum("kij,kj->ki", inv[t], p - x0[t])
    return np.column_stack([1.0 - lam.sum(axis=1), lam])


def _locate_inside(points, centroids, radii, inv, x0, valid) -> np.ndarray:
    """(q,) the simplex holding each point, -1 for points outside every simplex.

    Candidates: every (point, simplex) pair within the largest radius of each other, found by
    two KD-trees at once (``sparse_distance_matrix``, points in chunks to bound the memory),
    then those within the simplex's own radius tested by their coordinates."""
    q = len(points)
    ids = np.flatnonzero(valid)  # flat simplices never hold a point
    cell = np.full(q, -1, dtype=np.int64)
    if not len(ids) or not q:
        return cell
    tree = cKDTree(centroids[ids])
    upper = float(radii[ids].max()) * (1.0 + 1e-9)
    for s in range(0, q, _POINTS_PER_CHUNK):
        chunk = points[s : s + _POINTS_PER_CHUNK]
        pairs = cKDTree(chunk).sparse_distance_matrix(tree, upper, output_type="ndarray")
        r, t = pairs["i"].astype(np.int64), ids[pairs["j"]]
        keep = pairs["v"] <= radii[t] * (1.0 + 1e-9)
        r, t = r[keep], t[keep]
        for a in range(0, len(r), _PAIRS_PER_CHUNK):  # coordinates in chunks of pairs
            rr, tt = r[a : a + _PAIRS_PER_CHUNK], t[a : a + _PAIRS_PER_CHUNK]
            ok = _coordinates(inv, x0, tt, chunk[rr]).min(axis=1) >= -TOLERANCE
            rr, tt = rr[ok], tt[ok]
            free = cell[s + rr] < 0  # the first simplex found holds the point
            cell[s + rr[free]] = tt[free]
    return cell


def _closest_facets(x: np.ndarray, simplices: np.ndarray, points: np.ndarray):
    """(owning simplex (k,), distance (k,)) of the closest boundary facet to each point."""
    d = x.shape[1]
    facets, first, _, counts = facet_table(simplices)
    which = np.sort(first[counts == 1])  # index into the (m * (d + 1)) cell facets
    corners = x[facets[which]]  # (b, d, d)
    p = points
    if d == 2:  # boundary edges as flat triangles (a, b, b) in the plane z = 0
        corners = np.concatenate([corners, corners[:, 1:]], axis=1)
        corners = np.concatenate([corners, np.zeros((*corners.shape[:2], 1))], axis=2)
        p = np.column_stack([points, np.zeros(len(points))])
    tri, _, _, dist = TriangleSoup(corners).closest(p, with_points=False)
    return which[tri] // (d + 1), dist


def embed_points(mesh: Mesh, points: np.ndarray) -> Embedding:
    """Embed ``points`` (q, d), given at rest, in ``mesh`` (its rest positions); see the
    module docstring. Points outside the mesh take the simplex of the closest boundary facet
    with extrapolated coordinates (``Embedding.outside``, ``Embedding.distance``)."""
    if not isinstance(mesh, Mesh):
        raise InputError(f"embed_points: mesh must be a tissuesim Mesh, not {type(mesh).__name__}")
    d = mesh.dim
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != d or not np.isfinite(p).all():
        raise InputError(
            f"embed_points: points must be a (q, {d}) array of finite numbers for a {d}D "
            f"mesh, got shape {p.shape}"
        )
    x = np.asarray(mesh.points, dtype=np.float64)
    simplices = np.asarray(mesh.simplices, dtype=np.int64)
    x0, inv, valid, longest = _simplex_data(x, simplices)
    corners = x[simplices]
    centroids = corners.mean(axis=1)
    radii = np.sqrt(((corners - centroids[:, None]) ** 2).sum(axis=2).max(axis=1))
    cell = _locate_inside(p, centroids, radii, inv, x0, valid) if len(p) else np.zeros(0, int)
    outside = cell < 0
    distance = np.zeros(len(p))
    if outside.any():
        out = np.flatnonzero(outside)
        cell[out], distance[out] = _closest_facets(x, simplices, p[out])
    weights = _coordinates(inv, x0, cell, p) if len(p) else np.zeros((0, d + 1))
    vertices = simplices[cell]
    q, k = len(p), d + 1
    matrix = sp.csr_matrix(
        (weights.ravel(), vertices.ravel(), np.arange(0, q * k + 1, k)), shape=(q, len(x))
    )
    return Embedding(cell, vertices, weights, outside, distance, longest[cell], matrix)
