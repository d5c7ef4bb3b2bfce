"""Two FEM bodies glued where they touch: a stiff zero-length coupling energy between the
points of one body's boundary facets that lie on the other body.

Choice (as ``attachment.py`` for the tissue): a penalty energy, not a constraint. At points s on
body a's boundary triangles that touch body b (every vertex of the triangle within ``distance``
of b's boundary), a carries the point as y_s = sum_i a_si x_i (barycentric in a's tetrahedron)
and b as w_s = sum_j b_sj x_j (barycentric at the closest point of b's boundary). The energy

    W = sum_s k_s / 2 |y_s - w_s - d_s|^2,   d_s = the rest offset (zero where they touch),

is zero at rest and quadratic in (x_a, x_b): its Hessian G^T K G (x) I_3, with G = [A, -B], is
constant, one entry block per (a-vertex, b-vertex) pair that shares a point. k_s = stiffness
per m^2 times the point's share of the contact area. The force b exerts on a (the sum of
-dW/dx_a, N) is reported under the tie's name.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from tissuesim.errors import InputError

__all__ = ["Tie", "TiePoints", "tie_bodies", "tie_points"]


@dataclass(frozen=True, eq=False)
class Tie:
    """Points (S,) tied between FEM bodies ``a`` and ``b`` (names; indices in a system are
    looked up when it is built). cells_*/barycentric_*: where each body carries the points;
    offset (S, 3): rest offset; stiffness (S,) N/m."""

    name: str
    a: str
    b: str
    points: np.ndarray
    cells_a: np.ndarray
    barycentric_a: np.ndarray
    cells_b: np.ndarray
    barycentric_b: np.ndarray
    offset: np.ndarray
    stiffness: np.ndarray

    @property
    def n(self) -> int:
        return int(self.points.shape[0])

    def matrix(self, cells_a, cells_b, start_a: int, start_b: int, n_dofs: int) -> sp.csr_matrix:
        """G (3 S, n_dofs): G c = y - w, over the system's DOFs."""
        S = self.n
        rows = np.repeat(np.arange(S), 4)
        va = cells_a[self.cells_a].ravel()
        vb = cells_b[self.cells_b].ravel()
        blocks = []
        for comp in range(3):
            r = np.concatenate([rows, rows]) * 3 + comp
            c = np.concatenate([start_a + 3 * va + comp, start_b + 3 * vb + comp])
            v = np.concatenate([self.barycentric_a.ravel(), -self.barycentric_b.ravel()])
            blocks.append(sp.coo_matrix((v, (r, c)), shape=(3 * S, n_dofs)))
        return sp.csr_matrix(sum(blocks))


class TiePoints(NamedTuple):
    """Where two meshes are glued (``tie_points``): the points (S, 3), each body's cells and
    barycentric coordinates there, the rest offset (S, 3) and each point's area (S,) m^2."""

    points: np.ndarray
    cells_a: np.ndarray
    barycentric_a: np.ndarray
    cells_b: np.ndarray
    barycentric_b: np.ndarray
    offset: np.ndarray
    area: np.ndarray


def tie_points(a: str, mesh_a, b: str, mesh_b, *, distance: float) -> TiePoints:
    """The points of ``mesh_a``'s boundary triangles that touch ``mesh_b`` (all three vertices
    within ``distance`` m of b's boundary), no farther apart than a's median boundary edge, and
    where each body carries them: the closest-point search, a pure function of the meshes
    (a study's worker keeps it, ``sweep/cache.py``)."""
    from tissuesim.coupling.tissue import _facet_samples
    from tissuesim.mesh.queries.boundary import boundary_facets
    from tissuesim.mesh.queries.locate import closest_boundary_points, distance_to_boundary

    for mesh, who in ((mesh_a, a), (mesh_b, b)):
        if mesh.dim != 3:
            raise InputError(f"attach: body {who!r} is {mesh.dim}D; ties join 3D bodies")
    facets = boundary_facets(mesh_a.simplices)
    near = distance_to_boundary(mesh_b, mesh_a.points) <= distance
    touching = facets[near[facets].all(axis=1)]
    if not len(touching):
        gap = float(distance_to_boundary(mesh_b, mesh_a.points).min())
        raise InputError(
            f"attach {a!r} to {b!r}: no boundary triangle of {a!r} lies within distance "
            f"{distance:g} m of {b!r} (the closest vertex is {gap:.3g} m away); move the bodies "
            "together or give a larger distance"
        )
    P = mesh_a.points[touching]
    spacing = float(np.median(np.linalg.norm(P - np.roll(P, 1, axis=1), axis=2)))
    points, area = _facet_samples(mesh_a.points, touching, spacing)
    on_a = closest_boundary_points(mesh_a, points)
    on_b = closest_boundary_points(mesh_b, points)
    return TiePoints(
        points,
        on_a.cells,
        on_a.barycentric,
        on_b.cells,
        on_b.barycentric,
        on_a.positions - on_b.positions,
        area,
    )


def tie_bodies(
    name: str,
    a: str,
    mesh_a,
    b: str,
    mesh_b,
    *,
    distance: float,
    stiffness_per_area: float,
) -> Tie:
    """Tie ``mesh_a``'s boundary triangles that touch ``mesh_b`` (``tie_points``) to b, each
    point's stiffness ``stiffness_per_area`` times its area."""
    found = tie_points(a, mesh_a, b, mesh_b, distance=distance)
    return Tie(
        name,
        a,
        b,
        found.points,
        found.cells_a,
        found.barycentric_a,
        found.cells_b,
        found.barycentric_b,
        found.offset,
        stiffness_per_area * found.area,
    )
