"""Integration points (rest positions with volume weights) and display surfaces for frame models.

A meshless frame-based model integrates its elastic energy with a quadrature over points placed
inside the body; each point carries the volume of the region it stands for (its mass is
density * volume). The samplers here build such points for a box, an ellipsoid, the inside of a
closed triangle surface, or a tetrahedral mesh, always with volumes summing to the exact volume
of the region, so the total mass of the body does not depend on the sampling resolution.

Surfaces (outward triangle meshes of simple solids, or read from a file) show the body: their
vertices are embedded in the frames. They also define regions for ``sample_surface`` through the
generalised winding number. Lengths are in the caller's units, volumes in those units cubed.
"""

from __future__ import annotations

import numbers
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError, MeshError
from tissuesim.mesh.boundary import boundary_facets
from tissuesim.mesh.checks import signed_volumes
from tissuesim.mesh.generators import _arguments
from tissuesim.mesh.io import _load
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import check_memory, positive_field, regular_file, short

__all__ = [
    "IntegrationPoints",
    "Surface",
    "sample_box",
    "sample_ellipsoid",
    "sample_surface",
    "sample_mesh",
    "read_surface",
    "box_surface",
    "ellipsoid_surface",
    "surface_from_mesh",
    "winding_number",
]

# Point-triangle pairs evaluated at once (about 200 bytes each; small chunks stay in cache).
_PAIRS_PER_CHUNK = 1 << 15
# Sub-sample points classified at once by the samplers.
_SAMPLES_PER_CHUNK = 1 << 18


def _fmt(v: np.ndarray) -> str:
    return "[" + ",".join(f"{float(x):g}" for x in v) + "]"


@dataclass(frozen=True, eq=False)
class IntegrationPoints:
    """Quadrature points of a body at rest: the energy integral is sum_i volumes[i] * psi(x_i).

    points: (q, 3) float64 rest positions. volumes: (q,) float64 > 0, summing to the volume of
    the sampled region. source: what was sampled and how, used in error messages.
    """

    points: np.ndarray
    volumes: np.ndarray
    source: str = "<arrays>"

    def __post_init__(self) -> None:
        try:
            points = np.array(self.points, dtype=np.float64)
            volumes = np.array(self.volumes, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{self.source}: points and volumes must be numbers: {exc}") from exc
        if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
            raise InputError(
                f"{self.source}: points must have shape (q, 3) with q >= 1, got {points.shape}"
            )
        if volumes.shape != (len(points),):
            raise InputError(
                f"{self.source}: volumes must have shape ({len(points)},), one per point, "
                f"got {volumes.shape}"
            )
        if not np.isfinite(points).all():
            i = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
            raise InputError(f"{self.source}: point {i} is not finite: {points[i].tolist()}")
        bad = ~(np.isfinite(volumes) & (volumes > 0))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise InputError(
                f"{self.source}: volumes must be finite and > 0; volume {i} is "
                f"{float(volumes[i])!r} ({int(bad.sum())} bad): drop empty points or give them "
                f"their region's volume"
            )
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "volumes", volumes)

    @property
    def n(self) -> int:
        """Number of integration points q."""
        return int(self.points.shape[0])

    @property
    def volume(self) -> float:
        """Total volume sum(volumes): the volume of the sampled region."""
        return float(self.volumes.sum())

    def masses(self, density: float | np.ndarray) -> np.ndarray:
        """Masses (q,) = density * volumes, the lumped mass each point carries.

        density: one value for a homogeneous body or (q,) values, one per point; all finite > 0.
        """
        rho = positive_field(density, "density", self.n, "kg/m^3", entry="integration point")
        return rho * self.volumes


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


# ----------------------------------------------------------------------------------------------
# argument checks


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


_SPACING_HINT = "give the distance between neighbouring integration points in length units"


# ----------------------------------------------------------------------------------------------
# regular grids


#: bytes per cell of a sampling grid while it is built (index grids, centres, volumes)
SAMPLE_GRID_BYTES = 200


def _grid(lower: np.ndarray, upper: np.ndarray, spacing: float):
    """(divisions (3,), cell size h (3,), cell centres (N, 3), x fastest) of [lower, upper]."""
    extent = upper - lower
    counts = np.maximum(1.0, np.round(extent / spacing))
    check_memory(
        float(np.prod(counts)) * SAMPLE_GRID_BYTES,
        f"a sampling grid of spacing {spacing:g} ({np.prod(counts):.3g} cells)",
        "Use a larger spacing.",
    )
    divisions = counts.astype(np.int64)
    h = extent / divisions
    iz, iy, ix = (g.ravel() for g in np.indices(divisions[::-1]))
    centres = lower + (np.column_stack([ix, iy, iz]) + 0.5) * h
    return divisions, h, centres


def cell_points(
    sub: np.ndarray, mask: np.ndarray, inside: Callable[[np.ndarray], np.ndarray]
) -> np.ndarray:
    """One point per cell (k,) from its sub-samples sub (k, s, 3) and their inside mask (k, s),
    every cell with at least one inside: the centroid of the inside sub-samples, or, where the
    region is not convex and that centroid falls outside, the inside sub-sample nearest to it."""
    count = mask.sum(axis=1)
    centroid = np.einsum("ks,ksi->ki", mask.astype(np.float64), sub) / count[:, None]
    cut = np.flatnonzero(count < mask.shape[1])
    if len(cut):
        outside = ~inside(centroid[cut])
        if outside.any():
            k = cut[outside]
            d2 = ((sub[k] - centroid[k, None, :]) ** 2).sum(axis=2)
            d2[~mask[k]] = np.inf
            centroid[k] = sub[k, np.argmin(d2, axis=1)]
    return centroid


def _sample_cells(
    centres: np.ndarray,
    h: np.ndarray,
    subsamples: int,
    inside: Callable[[np.ndarray], np.ndarray],
    whole: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """(points, fractions) of the grid cells around ``centres`` that contain inside sub-samples.

    Each cell's inside fraction is counted on a subsamples^3 sub-grid; its point is the centroid
    of its inside sub-samples, or, if the region is not convex there and that centroid falls
    outside, the inside sub-sample nearest to it. ``whole`` (N,) optionally marks cells known to
    be entirely inside (1) or outside (0); -1 means classify the sub-samples.
    """
    s = subsamples
    check_memory(8 * 3 * 4.0 * s**3, f"{s}^3 sub-samples per cell", "Use fewer subsamples.")
    j = (np.arange(s) + 0.5) / s - 0.5
    oz, oy, ox = (g.ravel() for g in np.meshgrid(j, j, j, indexing="ij"))
    offsets = np.column_stack([ox, oy, oz]) * h  # (s^3, 3), centred on the cell centre
    if whole is None:
        whole = np.full(len(centres), -1, dtype=np.int8)
    points = centres.copy()
    fractions = (whole == 1).astype(np.float64)
    todo = np.flatnonzero(whole < 0)
    per_chunk = max(1, _SAMPLES_PER_CHUNK // len(offsets))
    for start in range(0, len(todo), per_chunk):
        cells = todo[start : start + per_chunk]
        sub = centres[cells, None, :] + offsets[None]  # (k, s^3, 3)
        mask = inside(sub.reshape(-1, 3)).reshape(len(cells), len(offsets))
        count = mask.sum(axis=1)
        some = count > 0
        cells, sub, mask, count = cells[some], sub[some], mask[some], count[some]
        centroid = cell_points(sub, mask, inside)
        points[cells] = centroid
        fractions[cells] = count / len(offsets)
    keep = fractions > 0
    return points[keep], fractions[keep]


def _scaled(
    points: np.ndarray,
    fractions: np.ndarray,
    h: np.ndarray,
    exact: float,
    source: str,
    spacing: float,
) -> IntegrationPoints:
    if len(points) == 0:
        raise InputError(
            f"{source}: no sub-sample fell inside the region; spacing {spacing:g} is too coarse "
            f"for it: use a smaller spacing or more subsamples"
        )
    volumes = fractions * float(np.prod(h))
    volumes *= exact / volumes.sum()
    return IntegrationPoints(points, volumes, source)


# ----------------------------------------------------------------------------------------------
# samplers


def sample_box(lower: Sequence[float], upper: Sequence[float], spacing: float) -> IntegrationPoints:
    """One point at the centre of each cell of a regular grid over the box [lower, upper].

    divisions = max(1, round(extent / spacing)) per axis, so the cells are close to ``spacing``
    but fit the box exactly; every volume is the cell volume, summing to the box volume.
    """
    lo, hi, _ = _arguments("sample_box", lower, upper, (1, 1, 1), 3)
    spacing = _positive("sample_box", "spacing", spacing, _SPACING_HINT)
    lo, hi = np.asarray(lo), np.asarray(hi)
    divisions, h, centres = _grid(lo, hi, spacing)
    volumes = np.full(len(centres), float(np.prod(hi - lo)) / len(centres))
    return IntegrationPoints(centres, volumes, f"box {_fmt(lo)}-{_fmt(hi)} spacing {spacing:g}")


def sample_ellipsoid(
    center: Sequence[float],
    semi_axes: Sequence[float],
    spacing: float,
    subsamples: int = 4,
) -> IntegrationPoints:
    """Points in the axis-aligned ellipsoid sum(((x - center) / semi_axes)^2) <= 1.

    Grid cells (as in ``sample_box``) over the bounding box; each cell's inside fraction is
    estimated on a subsamples^3 sub-grid and cells with a fraction > 0 are kept, with their point
    at the centroid of their inside sub-samples and volume fraction * cell volume. All volumes are
    then scaled by (4/3 pi a b c) / sum, so the total is the exact ellipsoid volume (the boundary
    cells' fractions carry an O(spacing / subsamples) error that this spreads over all points).
    """
    func = "sample_ellipsoid"
    c = _vector3(func, "center", center)
    r = _vector3(func, "semi_axes", semi_axes, positive=True)
    spacing = _positive(func, "spacing", spacing, _SPACING_HINT)
    subsamples = _count(func, "subsamples", subsamples, 1)
    _, h, centres = _grid(c - r, c + r, spacing)

    def inside(x: np.ndarray) -> np.ndarray:
        return (((x - c) / r) ** 2).sum(axis=1) <= 1.0

    points, fractions = _sample_cells(centres, h, subsamples, inside, None)
    source = f"ellipsoid center {_fmt(c)} semi_axes {_fmt(r)} spacing {spacing:g}"
    exact = 4.0 / 3.0 * np.pi * float(np.prod(r))
    return _scaled(points, fractions, h, exact, source, spacing)


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


def sample_surface(surface: Surface, spacing: float, subsamples: int = 4) -> IntegrationPoints:
    """Points inside a closed outward triangle surface, sampled as in ``sample_ellipsoid``.

    A sub-sample is inside where the generalised winding number is > 0.5. Cells whose centre is
    farther from every triangle than half the cell diagonal lie entirely on one side, so only
    cells the surface may cut get their sub-samples tested (same result, much cheaper). Volumes
    are scaled so they sum to ``surface.volume()`` exactly. Raises ValueError for an open or
    inward surface, or when no sub-sample falls inside (spacing too coarse). Cost: about
    (cells the surface cuts) * subsamples^3 * triangles arctan2 evaluations.
    """
    func = "sample_surface"
    if not isinstance(surface, Surface):
        raise InputError(f"{func}: surface must be a Surface, got {type(surface).__name__}")
    spacing = _positive(func, "spacing", spacing, _SPACING_HINT)
    subsamples = _count(func, "subsamples", subsamples, 1)
    exact = surface.volume()
    if not exact > 0:
        raise MeshError(
            f"{surface.source}: enclosed volume is {exact:g} <= 0: the triangles are oriented "
            f"inward; flip them (triangles[:, ::-1]) so their normals point out of the solid"
        )
    used = surface.points[np.unique(surface.triangles)]
    _, h, centres = _grid(used.min(axis=0), used.max(axis=0), spacing)
    whole = np.full(len(centres), -1, dtype=np.int8)
    clear = _clearance(surface, centres) > 0.5 * float(np.linalg.norm(h)) * (1.0 + 1e-9)
    whole[clear] = winding_number(surface, centres[clear]) > 0.5

    def inside(x: np.ndarray) -> np.ndarray:
        return winding_number(surface, x) > 0.5

    points, fractions = _sample_cells(centres, h, subsamples, inside, whole)
    source = f"inside of {surface.source} spacing {spacing:g}"
    return _scaled(points, fractions, h, exact, source, spacing)


def sample_mesh(mesh: Mesh, spacing: float | None = None) -> IntegrationPoints:
    """Integration points from a tetrahedral mesh, summing exactly to the mesh volume.

    spacing None: one point per tetrahedron at its centroid, with its volume (exact for fields
    linear on each tetrahedron). With a spacing: tetrahedra are grouped by the grid cell (of that
    spacing, anchored at the mesh's bounding-box minimum) containing their centroid; each group
    gives one point at its volume-weighted centroid carrying the group's volume, which decouples
    the number of points from the mesh resolution.
    """
    func = "sample_mesh"
    if not isinstance(mesh, Mesh):
        raise InputError(f"{func}: mesh must be a tissuesim Mesh, got {type(mesh).__name__}")
    if mesh.dim != 3 or mesh.cells.shape[1] != 4:
        raise InputError(
            f"{func}: {mesh.source} is a {mesh.dim}D mesh; 3D tetrahedra are needed: use "
            f"tissuesim.mesh.box or a tetrahedral mesh file"
        )
    volumes = signed_volumes(mesh.points, mesh.cells)
    centroids = mesh.points[mesh.cells].mean(axis=1)
    if spacing is None:
        return IntegrationPoints(centroids, volumes, f"tetrahedra of {mesh.source}")
    spacing = _positive(func, "spacing", spacing, _SPACING_HINT + ", or None for one per tet")
    index = np.floor((centroids - mesh.points.min(axis=0)) / spacing).astype(np.int64)
    index = np.maximum(index, 0)
    _, group = np.unique(index, axis=0, return_inverse=True)
    group = group.reshape(-1)
    vol = np.bincount(group, weights=volumes)
    points = (
        np.column_stack([np.bincount(group, weights=volumes * centroids[:, k]) for k in range(3)])
        / vol[:, None]
    )
    return IntegrationPoints(points, vol, f"tetrahedra of {mesh.source} spacing {spacing:g}")


# ----------------------------------------------------------------------------------------------
# surfaces


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
