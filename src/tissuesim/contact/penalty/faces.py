"""Contact facets as FEBio's surface elements: bilinear quadrilaterals and linear triangles,
their shape functions in (r, s), and the points a penalty contact samples on them.

A facet is a row of 4 vertex indices; a triangle repeats its last corner (a, b, c, c), the
rows a wedge mesh's facet sets hold (``mesh/cells/wedge.py``). Quadrilateral corners sit at
(r, s) = (-1, -1), (1, -1), (1, 1), (-1, 1) and triangle corners at (0, 0), (1, 0), (0, 1), as
in FEBio's FEQuad4 / FETri3 surface elements. Sample points (FEBio's integration rules):
"gauss" takes 2 x 2 Gauss points on a quadrilateral (weights 1) and 3 points at (1/6, 1/6),
(2/3, 1/6), (1/6, 2/3) on a triangle (weights 1/6), as FEFacet2FacetSliding and
FESlidingElasticInterface integrate; "nodal" takes the corners (weights 1 and 1/6), as
FESlidingInterface (node-on-facet) does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError

__all__ = ["Facets", "SamplePoints", "shape", "shape_derivatives", "sample_points"]

_G = 1.0 / np.sqrt(3.0)
_RULES = {
    ("gauss", 4): (np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]]), np.ones(4)),
    ("gauss", 3): (
        np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]),
        np.full(3, 1 / 6),
    ),
    ("nodal", 4): (np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]), np.ones(4)),
    ("nodal", 3): (np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), np.full(3, 1 / 6)),
}
_QUAD_SIGNS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


@dataclass(frozen=True)
class Facets:
    """(k, 4) vertex indices and which rows are triangles (the 4th corner unused)."""

    corners: np.ndarray
    triangle: np.ndarray

    @classmethod
    def of(cls, facets: np.ndarray, where: str) -> Facets:
        f = np.asarray(facets, dtype=np.int64)
        if f.ndim != 2 or f.shape[1] not in (3, 4) or len(f) == 0:
            raise InputError(
                f"{where}: contact facets must be rows of 3 (triangles) or 4 (quadrilaterals) "
                f"vertex indices, got shape {f.shape}"
            )
        if f.shape[1] == 3:
            f = np.column_stack([f, f[:, 2]])
        return cls(f, f[:, 3] == f[:, 2])


def shape(r: np.ndarray, s: np.ndarray, triangle: np.ndarray) -> np.ndarray:
    """(n, 4) shape function values at (r, s); a triangle's 4th is 0."""
    quad = 0.25 * (1 + _QUAD_SIGNS[:, 0] * r[:, None]) * (1 + _QUAD_SIGNS[:, 1] * s[:, None])
    tri = np.column_stack([1 - r - s, r, s, np.zeros_like(r)])
    return np.where(triangle[:, None], tri, quad)


def shape_derivatives(r: np.ndarray, s: np.ndarray, triangle: np.ndarray):
    """(dH/dr, dH/ds, d2H/drds), each (n, 4); a triangle's are constant (the last zero)."""
    sr, ss = _QUAD_SIGNS[:, 0], _QUAD_SIGNS[:, 1]
    quad_r = 0.25 * sr * (1 + ss * s[:, None])
    quad_s = 0.25 * ss * (1 + sr * r[:, None])
    quad_rs = np.broadcast_to(0.25 * sr * ss, quad_r.shape)
    n = len(r)
    tri_r = np.broadcast_to(np.array([-1.0, 1.0, 0.0, 0.0]), (n, 4))
    tri_s = np.broadcast_to(np.array([-1.0, 0.0, 1.0, 0.0]), (n, 4))
    t = triangle[:, None]
    return np.where(t, tri_r, quad_r), np.where(t, tri_s, quad_s), np.where(t, 0.0, quad_rs)


@dataclass(frozen=True)
class SamplePoints:
    """Points on facets: each point's facet row, (r, s), shape values H (n, 4) and weight
    (the rule's weight; times the facet's area Jacobian where it is used)."""

    facet: np.ndarray
    rs: np.ndarray
    H: np.ndarray
    weight: np.ndarray


def sample_points(facets: Facets, rule: str) -> SamplePoints:
    """Every facet's points of the rule ("gauss" or "nodal"), facet by facet."""
    rows, rs, weights = [], [], []
    for n_corners, mask in ((4, ~facets.triangle), (3, facets.triangle)):
        idx = np.flatnonzero(mask)
        points, w = _RULES[(rule, n_corners)]
        rows.append(np.repeat(idx, len(points)))
        rs.append(np.tile(points, (len(idx), 1)))
        weights.append(np.tile(w, len(idx)))
    facet = np.concatenate(rows)
    order = np.argsort(facet, kind="stable")
    facet, rs_all, w_all = facet[order], np.concatenate(rs)[order], np.concatenate(weights)[order]
    H = shape(rs_all[:, 0], rs_all[:, 1], facets.triangle[facet])
    return SamplePoints(facet, rs_all, H, w_all)


def area_jacobians(x: np.ndarray, facets: Facets, points: SamplePoints) -> np.ndarray:
    """|x_r x x_s| at each sample point for vertex positions x (n, 3)."""
    tri = facets.triangle[points.facet]
    Hr, Hs, _ = shape_derivatives(points.rs[:, 0], points.rs[:, 1], tri)
    X = x[facets.corners[points.facet]]  # (n, 4, 3)
    xr = np.einsum("na,nad->nd", Hr, X)
    xs = np.einsum("na,nad->nd", Hs, X)
    return np.linalg.norm(np.cross(xr, xs), axis=1)
