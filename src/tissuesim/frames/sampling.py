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

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError, MeshError
from tissuesim.frames.surfaces import (  # re-exported: samplers and surfaces are used together
    Surface,
    _clearance,
    _count,
    _fmt,
    _positive,
    _vector3,
    box_surface,
    ellipsoid_surface,
    read_surface,
    surface_from_mesh,
    winding_number,
)
from tissuesim.mesh.checks import signed_volumes
from tissuesim.mesh.generators.common import _arguments
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import check_memory, positive_field

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

# Sub-sample points classified at once by the samplers.
_SAMPLES_PER_CHUNK = 1 << 18


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


# ----------------------------------------------------------------------------------------------
# argument checks


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
