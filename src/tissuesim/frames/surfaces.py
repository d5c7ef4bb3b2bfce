"""Closed triangle surfaces of frame bodies: the outward surfaces of simple solids (a box, an
ellipsoid), read from a file or taken from a tetrahedral mesh's boundary. They show the body
(their vertices are embedded in the frames) and bound regions through the generalised winding
number, which ``sampling.sample_surface`` fills with integration points. Lengths are in the
caller's units."""

from __future__ import annotations

import numbers
import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError, MeshError
from tissuesim.mesh.generators.common import _arguments
from tissuesim.mesh.io import _load
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries.boundary import boundary_facets
from tissuesim.validate import regular_file, short

__all__ = [
    "Surface",
    "read_surface",
    "box_surface",
    "ellipsoid_surface",
    "surface_from_mesh",
    "winding_number",
]


def _vector3(func: str, name: str, value, positive: bool = False) -> np.ndarray:
    try:
        v = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{func}: {name} must be 3 numbers (x, y, z), got {short(value)}") from exc
    if v.shape != (3,) or not np.isfinite(v).all():
        raise InputError(f"{func}: {name} must be 3 finite numbers (x, y, z), got {short(value)}")
    if positive and not (v > 0).all():
        raise InputError(
            f"{func}: {name} must all be > 0, got {_fmt(v)}; give the half-lengths of the "
            f"solid along x, y and z"
        )
    return v


def _positive(func: str, name: str, value, hint: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"{func}: {name} must be a number > 0, got {short(value)}; {hint}")
    v = float(value)
    if not (np.isfinite(v) and v > 0):
        raise InputError(f"{func}: {name} must be finite and > 0, got {short(value)}; {hint}")
    return v


def _count(func: str, name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise InputError(f"{func}: {name} must be an integer >= {minimum}, got {short(value)}")
    return int(value)


# Point-triangle pairs evaluated at once (about 200 bytes each; small chunks stay in cache).
_PAIRS_PER_CHUNK = 1 << 15


def _fmt(v: np.ndarray) -> str:
    return "[" + ",".join(f"{float(x):g}" for x in v) + "]"


@dataclass(frozen=True, eq=False)
class Surface:
    """A triangle surface: points (n, 3) float64, triangles (m, 3) int64 vertex ids, source.

    Closed surfaces made here are outward oriented: (b - a) x (c - a) points out of the solid.
    """

    points: np.ndarray
    triangles: np.ndarray
    source: str = "<arrays>"

    def __post_init__(self) -> None:
        try:
            points = np.array(self.points, dtype=np.float64)
            tri = np.asarray(self.triangles)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{self.source}: points and triangles must be arrays: {exc}") from exc
        if points.ndim != 2 or points.shape[1] != 3 or not np.isfinite(points).all():
            raise InputError(
                f"{self.source}: surface points must be an (n, 3) array of finite numbers, "
                f"got shape {points.shape}"
            )
        if tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0:
            raise InputError(
                f"{self.source}: triangles must have shape (m, 3) with m >= 1, got {tri.shape}"
            )
        if not np.issubdtype(tri.dtype, np.integer):
            if not np.issubdtype(tri.dtype, np.floating) or not (np.round(tri) == tri).all():
                raise InputError(
                    f"{self.source}: triangles must hold integer vertex ids, got {tri.dtype}"
                )
        tri = np.array(tri, dtype=np.int64)
        if tri.min() < 0 or tri.max() >= len(points):
            raise InputError(
                f"{self.source}: triangle vertex ids must lie in [0, {len(points) - 1}], got "
                f"ids from {int(tri.min())} to {int(tri.max())}"
            )
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "triangles", tri)

    def _check_closed(self) -> None:
        """Raise unless every edge is shared by exactly 2 triangles traversing it oppositely."""
        t = self.triangles
        directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        n = np.int64(len(self.points))
        lo, hi = directed.min(axis=1), directed.max(axis=1)
        edges, counts = np.unique(lo * n + hi, return_counts=True)
        bad = counts != 2
        if bad.any():
            key = int(edges[bad][0])
            raise MeshError(
                f"{self.source}: surface is not closed: {int(bad.sum())} of {len(edges)} edges are "
                f"used by a number of triangles other than 2 (e.g. edge ({key // n}, {key % n}) "
                f"used by {int(counts[bad][0])}); a closed surface is needed to enclose a "
                f"volume: fill its holes or remesh it watertight"
            )
        keys, counts = np.unique(directed[:, 0] * n + directed[:, 1], return_counts=True)
        if (counts != 1).any():
            key = int(keys[counts != 1][0])
            raise MeshError(
                f"{self.source}: surface is inconsistently oriented: {int((counts != 1).sum())} "
                f"edges are traversed the same way by both their triangles (e.g. "
                f"{key // n} -> {key % n}); orient all triangles consistently (all outward)"
            )

    def volume(self) -> float:
        """Enclosed volume by the divergence theorem, sum over triangles of a . (b x c) / 6.

        Negative when the triangles face inward. Raises MeshError (a ValueError) if the surface
        is not closed or not consistently oriented, since the volume is then meaningless.
        """
        self._check_closed()
        x = self.points[self.triangles]
        # centring keeps the sum accurate for surfaces far from the origin
        x = x - self.points.mean(axis=0)
        return float(np.einsum("mi,mi->m", x[:, 0], np.cross(x[:, 1], x[:, 2])).sum() / 6.0)


def winding_number(surface: Surface, points: np.ndarray) -> np.ndarray:
    """Generalised winding number (q,) of ``surface`` around ``points`` (q, 3).

    Sum over triangles of their solid angle (van Oosterom-Strackee) / 4 pi: 1 inside and 0
    outside a closed outward surface (-1 inside an inward one), fractional near holes, so
    ``> 0.5`` is a robust inside test. Costs q * m arctan2 calls, in chunks to bound memory.
    """
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise InputError(f"winding_number: points must have shape (q, 3), got {p.shape}")
    tri = surface.points[surface.triangles]  # (m, 3, 3)
    A, B, C = (np.ascontiguousarray(tri[:, v].T) for v in range(3))  # (3, m) each
    w = np.empty(len(p))
    per_chunk = max(1, _PAIRS_PER_CHUNK // len(tri))
    for start in range(0, len(p), per_chunk):
        q = p[start : start + per_chunk]
        # contiguous component arrays (k, m): much faster than (k, m, 3) with einsum/cross
        ax, ay, az = (A[i] - q[:, i, None] for i in range(3))
        bx, by, bz = (B[i] - q[:, i, None] for i in range(3))
        cx, cy, cz = (C[i] - q[:, i, None] for i in range(3))
        la = np.sqrt(ax * ax + ay * ay + az * az)
        lb = np.sqrt(bx * bx + by * by + bz * bz)
        lc = np.sqrt(cx * cx + cy * cy + cz * cz)
        det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        den = (
            la * lb * lc
            + (ax * bx + ay * by + az * bz) * lc
            + (bx * cx + by * cy + bz * cz) * la
            + (cx * ax + cy * ay + cz * az) * lb
        )
        w[start : start + per_chunk] = np.arctan2(det, den).sum(axis=1)
    return w / (2.0 * np.pi)


def _clearance(surface: Surface, points: np.ndarray) -> np.ndarray:
    """Lower bound (q,) on the distance from ``points`` to the surface.

    Per triangle the larger of the distance to its plane and the distance to its bounding
    sphere (centroid, farthest vertex); both never exceed the distance to the triangle.
    """
    tri = surface.points[surface.triangles]
    centre = tri.mean(axis=1)
    radius = np.sqrt(((tri - centre[:, None]) ** 2).sum(axis=2).max(axis=1))
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
    offset = np.einsum("mi,mi->m", normal, tri[:, 0])
    out = np.empty(len(points))
    per_chunk = max(1, _PAIRS_PER_CHUNK // len(tri))
    for start in range(0, len(points), per_chunk):
        q = points[start : start + per_chunk]
        plane = np.abs(q @ normal.T - offset)
        dx, dy, dz = (centre[:, i] - q[:, i, None] for i in range(3))
        sphere = np.sqrt(dx * dx + dy * dy + dz * dz) - radius
        out[start : start + per_chunk] = np.maximum(plane, sphere).min(axis=1)
    return out


def read_surface(path: str | os.PathLike[str]) -> Surface:
    """Read the triangles of any file meshio reads (.stl, .obj, .ply, .vtu, .msh, ...).

    Other cell types are ignored, so the boundary triangles of a volume mesh file work too.
    Raises MeshError (a ValueError) naming the file if it is missing, unreadable or has no
    triangles.
    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise MeshError(f"{path}: no such surface file; check the path (cwd is {os.getcwd()})")
    try:
        regular_file(path, "surface file")  # a FIFO or device would block the reader
    except InputError as exc:
        raise MeshError(str(exc)) from None
    m = _load(path)
    blocks = [np.asarray(b.data) for b in m.cells if b.type == "triangle" and len(b.data)]
    if not blocks:
        found = ", ".join(f"{b.type} ({len(b.data)})" for b in m.cells) or "none"
        raise MeshError(
            f"{path}: no triangles; cell types found: {found}. A surface needs linear "
            f"'triangle' cells: export the surface as a triangle mesh (e.g. .stl)"
        )
    points = np.asarray(m.points, dtype=np.float64)
    if points.ndim == 2 and points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    return Surface(points, np.concatenate(blocks), source=path)


def box_surface(
    lower: Sequence[float],
    upper: Sequence[float],
    divisions: Sequence[int] = (2, 2, 8),
) -> Surface:
    """Closed outward surface of the box [lower, upper], each face a grid of triangles.

    divisions (nx, ny, nz): segments along each axis, shared by the faces so edges conform.
    """
    lo, hi, div = _arguments("box_surface", lower, upper, divisions, 3)
    lo, hi, n = np.asarray(lo), np.asarray(hi), np.asarray(div)
    shape = tuple(int(k) + 1 for k in n)  # grid vertices along x, y, z
    gx, gy, gz = np.indices(shape).reshape(3, -1)
    vid = np.arange(np.prod(shape)).reshape(shape)
    triangles = []
    for axis in range(3):
        i, j = (axis + 1) % 3, (axis + 2) % 3  # e_i x e_j = e_axis
        for side in (0, n[axis]):
            sl = [slice(None)] * 3
            sl[axis] = side
            face = vid[tuple(sl)]  # remaining axes in increasing order
            face = face.T if i > j else face  # now face[u, v]: u along axis i, v along axis j
            v00, v10 = face[:-1, :-1].ravel(), face[1:, :-1].ravel()
            v11, v01 = face[1:, 1:].ravel(), face[:-1, 1:].ravel()
            t = np.concatenate([np.column_stack([v00, v10, v11]), np.column_stack([v00, v11, v01])])
            triangles.append(t if side else t[:, ::-1])
    triangles = np.concatenate(triangles)
    used, triangles = np.unique(triangles, return_inverse=True)
    points = lo + (hi - lo) * np.column_stack([gx, gy, gz])[used] / n
    source = f"box_surface {_fmt(lo)}-{_fmt(hi)} divisions {tuple(int(k) for k in n)}"
    return Surface(points, triangles.reshape(-1, 3), source)


def _icosphere(refinement: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit sphere (points, outward triangles) from an icosahedron split ``refinement`` times."""
    g = (1.0 + 5.0**0.5) / 2.0
    points = np.array(
        [[-1, g, 0], [1, g, 0], [-1, -g, 0], [1, -g, 0], [0, -1, g], [0, 1, g],
         [0, -1, -g], [0, 1, -g], [g, 0, -1], [g, 0, 1], [-g, 0, -1], [-g, 0, 1]],
        dtype=np.float64,
    )  # fmt: skip
    tri = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]],
        dtype=np.int64,
    )  # fmt: skip
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    for _ in range(refinement):
        # midpoints of the 3 edges of every triangle, one new vertex per unique edge
        e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
        key = e.min(axis=1) * len(points) + e.max(axis=1)
        unique, first, inverse = np.unique(key, return_index=True, return_inverse=True)
        mid = points[e[first]].mean(axis=1)
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m01, m12, m20 = len(points) + inverse.reshape(3, -1)
        a, b, c = tri.T
        tri = np.concatenate(
            [
                np.column_stack([a, m01, m20]),
                np.column_stack([b, m12, m01]),
                np.column_stack([c, m20, m12]),
                np.column_stack([m01, m12, m20]),
            ]
        )
        points = np.concatenate([points, mid])
    x = points[tri]
    inward = np.einsum("mi,mi->m", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x.sum(1)) < 0
    tri[inward] = tri[inward, ::-1]
    return points, tri


def ellipsoid_surface(
    center: Sequence[float],
    semi_axes: Sequence[float],
    refinement: int = 3,
) -> Surface:
    """Closed outward surface of an axis-aligned ellipsoid: an icosphere scaled by semi_axes.

    refinement: times each icosahedron triangle is split in 4 (20 * 4^refinement triangles). The
    polyhedron is inscribed, so its volume is a little below 4/3 pi a b c (about 1% at 3).
    """
    func = "ellipsoid_surface"
    c = _vector3(func, "center", center)
    r = _vector3(func, "semi_axes", semi_axes, positive=True)
    refinement = _count(func, "refinement", refinement, 0)
    points, tri = _icosphere(refinement)
    source = f"ellipsoid_surface center {_fmt(c)} semi_axes {_fmt(r)} refinement {refinement}"
    return Surface(c + points * r, tri, source)


def surface_from_mesh(mesh: Mesh) -> Surface:
    """Outward boundary triangles of a tetrahedral mesh, with only the vertices they use."""
    if not isinstance(mesh, Mesh):
        raise InputError(
            f"surface_from_mesh: mesh must be a tissuesim Mesh, got {type(mesh).__name__}"
        )
    if mesh.dim != 3 or mesh.cells.shape[1] != 4:
        raise InputError(
            f"surface_from_mesh: {mesh.source} is a {mesh.dim}D mesh; its boundary is not a "
            f"triangle surface: give a tetrahedral (3D) mesh"
        )
    facets = boundary_facets(mesh.cells)
    used, triangles = np.unique(facets, return_inverse=True)
    return Surface(mesh.points[used], triangles.reshape(-1, 3), f"boundary of {mesh.source}")
