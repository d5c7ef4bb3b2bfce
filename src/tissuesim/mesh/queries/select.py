"""Select vertices and boundary facets of a Mesh by plane, box or tag.

Vertex selections return sorted unique (k,) int64 vertex ids; facet selections return (k, d) int64
boundary facets oriented outward ((k, 4) quad faces for hexahedra; for wedges (k, 4) rows of
quads and triangles, a triangle as (a, b, c, c), ``mesh/cells/wedge.py``). An empty selection raises
MeshError stating what was asked and the mesh's bounding box. Default tolerances are 1e-6 times
the bounding-box diagonal.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries.boundary import boundary_facets

__all__ = [
    "vertices_on_plane",
    "vertices_in_box",
    "vertices_tagged",
    "boundary_vertices",
    "facets_on_plane",
    "facets_in_box",
    "facets_tagged",
    "all_boundary_facets",
]

_AXES = "xyz"
_BOUNDARY_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _bbox_text(mesh: Mesh) -> str:
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    box = " x ".join(f"[{a:.6g}, {b:.6g}]" for a, b in zip(lo, hi, strict=True))
    return f"mesh {mesh.source} has bounding box {box}"


def _tolerance(mesh: Mesh, tolerance: float | None) -> float:
    if tolerance is None:
        return 1e-6 * float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    if not tolerance >= 0:
        raise MeshError(f"tolerance must be >= 0, got {tolerance}")
    return float(tolerance)


def _nonempty(result: np.ndarray, mesh: Mesh, asked: str) -> np.ndarray:
    if len(result) == 0:
        raise MeshError(f"no {asked}; {_bbox_text(mesh)}")
    return result


def _axis(mesh: Mesh, axis: int) -> int:
    if not isinstance(axis, int | np.integer) or not 0 <= axis < mesh.dim:
        raise MeshError(f"axis must be an integer in 0..{mesh.dim - 1} for a {mesh.dim}D mesh")
    return int(axis)


def _box_mask(mesh: Mesh, lower, upper, tolerance) -> tuple[np.ndarray, str]:
    lo = np.asarray(lower, dtype=np.float64)
    hi = np.asarray(upper, dtype=np.float64)
    if lo.shape != (mesh.dim,) or hi.shape != (mesh.dim,):
        raise MeshError(f"lower and upper must each have {mesh.dim} coordinates")
    tol = _tolerance(mesh, tolerance)
    inside = ((mesh.points >= lo - tol) & (mesh.points <= hi + tol)).all(axis=1)
    return inside, f"box {lo.tolist()} to {hi.tolist()} (tolerance {tol:.3g})"


def _boundary(mesh: Mesh) -> np.ndarray:
    """Read-only boundary facets of ``mesh``, computed once per mesh."""
    facets = _BOUNDARY_CACHE.get(mesh)
    if facets is None:
        if mesh.simplicial:
            facets = boundary_facets(mesh.corners)
        else:  # edges of quadrilaterals, quad faces (k, 4) of hexahedra and wedges
            from tissuesim.mesh.cells.tensor import boundary_faces

            facets = boundary_faces(mesh.cells, mesh.dim)
        facets.flags.writeable = False
        _BOUNDARY_CACHE[mesh] = facets
    return facets


def all_boundary_facets(mesh: Mesh) -> np.ndarray:
    """All boundary facets (k, d) of ``mesh``, oriented outward."""
    return _nonempty(_boundary(mesh).copy(), mesh, "boundary facets")


def boundary_vertices(mesh: Mesh) -> np.ndarray:
    """Sorted ids (k,) of the vertices on the boundary of ``mesh`` (with the midside nodes of
    boundary facets for quadratic meshes)."""
    facets = _boundary(mesh)
    if mesh.order == 2:
        from tissuesim.mesh.cells.quadratic import quadratic_facets

        facets = quadratic_facets(mesh, facets)
    return _nonempty(np.unique(facets), mesh, "boundary vertices")


def vertices_on_plane(
    mesh: Mesh, axis: int, value: float, tolerance: float | None = None
) -> np.ndarray:
    """Sorted ids (k,) of vertices with |x[axis] - value| <= tolerance (same units as points)."""
    axis, tol = _axis(mesh, axis), _tolerance(mesh, tolerance)
    ids = np.flatnonzero(np.abs(mesh.points[:, axis] - value) <= tol)
    return _nonempty(
        ids, mesh, f"vertices on the plane {_AXES[axis]} = {value} (tolerance {tol:.3g})"
    )


def vertices_in_box(
    mesh: Mesh, lower: Sequence[float], upper: Sequence[float], tolerance: float | None = None
) -> np.ndarray:
    """Sorted ids (k,) of vertices with lower - tol <= x <= upper + tol in every coordinate."""
    inside, text = _box_mask(mesh, lower, upper, tolerance)
    return _nonempty(np.flatnonzero(inside), mesh, f"vertices in the {text}")


def _available(mesh: Mesh) -> str:
    groups = (("point sets", mesh.point_sets), ("facet sets", mesh.facet_sets))
    groups += (("cell sets", mesh.cell_sets),)
    return "; ".join(f"{g}: {sorted(s) or 'none'}" for g, s in groups)


def vertices_tagged(mesh: Mesh, tag: str) -> np.ndarray:
    """Sorted ids (k,) of the point set ``tag``, else the vertices of that facet set (with its
    facets' midside and face-centre nodes on a quadratic mesh) or cell set."""
    if tag in mesh.point_sets:
        ids = np.unique(np.asarray(mesh.point_sets[tag], dtype=np.int64))
    elif tag in mesh.facet_sets:
        facets = np.asarray(mesh.facet_sets[tag], dtype=np.int64).reshape(-1, mesh.facet_nodes)
        if mesh.order == 2:
            from tissuesim.mesh.cells.quadratic import quadratic_facets

            facets = quadratic_facets(mesh, facets)
        ids = np.unique(facets[facets >= 0])
    elif tag in mesh.cell_sets:
        ids = np.unique(mesh.cells[np.asarray(mesh.cell_sets[tag], dtype=np.int64)])
    else:
        raise MeshError(f"mesh {mesh.source} has no set named {tag!r}; {_available(mesh)}")
    return _nonempty(ids, mesh, f"vertices in the set {tag!r}")


def facets_on_plane(
    mesh: Mesh, axis: int, value: float, tolerance: float | None = None
) -> np.ndarray:
    """Boundary facets (k, d) whose vertices all satisfy |x[axis] - value| <= tolerance."""
    axis, tol = _axis(mesh, axis), _tolerance(mesh, tolerance)
    on = np.abs(mesh.points[:, axis] - value) <= tol
    bf = _boundary(mesh)
    text = f"boundary facets on the plane {_AXES[axis]} = {value} (tolerance {tol:.3g})"
    return _nonempty(bf[on[bf].all(axis=1)], mesh, text)


def facets_in_box(
    mesh: Mesh, lower: Sequence[float], upper: Sequence[float], tolerance: float | None = None
) -> np.ndarray:
    """Boundary facets (k, d) whose vertices all lie in the box (see ``vertices_in_box``)."""
    inside, text = _box_mask(mesh, lower, upper, tolerance)
    bf = _boundary(mesh)
    return _nonempty(bf[inside[bf].all(axis=1)], mesh, f"boundary facets in the {text}")


def facets_tagged(mesh: Mesh, tag: str) -> np.ndarray:
    """Facet set ``tag`` (k, d), else boundary facets with all vertices in point set ``tag``."""
    if tag in mesh.facet_sets:  # (k, 4) for hexahedra and wedges
        facets = np.asarray(mesh.facet_sets[tag], dtype=np.int64).reshape(-1, mesh.facet_nodes)
    elif tag in mesh.point_sets:
        bf = _boundary(mesh)
        facets = bf[np.isin(bf, mesh.point_sets[tag]).all(axis=1)]
    else:
        raise MeshError(
            f"mesh {mesh.source} has no facet set or point set named {tag!r}; {_available(mesh)}"
        )
    return _nonempty(facets, mesh, f"facets in the set {tag!r}")
