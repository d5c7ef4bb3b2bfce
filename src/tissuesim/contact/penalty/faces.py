"""Contact facets as FEBio's surface elements: linear and quadratic triangles and
quadrilaterals (tri3, quad4, tri6, quad8), their shape functions in (r, s), and the points a
penalty contact samples on them.

A facet is a row of vertex indices, corners first, then (quadratic facets) the midside nodes
in FEBio's order (between corners 0-1, 1-2, 2-3 / 2-0, 3-0); each row's ``kind`` is its number
of nodes (3, 4, 6, 8). Rows are padded to one width per surface (4, or 8 when a facet is
quadratic) by repeating their last node, with shape value 0: a triangle of a linear surface
is (a, b, c, c), the rows a wedge mesh's facet sets hold (``mesh/cells/wedge.py``).
Quadrilateral corners sit at (r, s) = (-1, -1), (1, -1), (1, 1), (-1, 1) (midsides between
them) and triangle corners at (0, 0), (1, 0), (0, 1), as in FEBio's FEQuad4 / FEQuad8 / FETri3
/ FETri6 surface elements. Sample points (FEBio's integration rules): "gauss" takes 2 x 2
Gauss points on a quad4, 3 x 3 on a quad8 (FEQuad8G9) and 3 points at (1/6, 1/6), (2/3, 1/6),
(1/6, 2/3) on a triangle (weights 1/6; FETri6G3 on a tri6), as FEFacet2FacetSliding and
FESlidingElasticInterface integrate; "nodal" takes the corners (weights 1 and 1/6), as
FESlidingInterface (node-on-facet) does, and on a quad8 its 8 nodes with the weight and area
Jacobian of Gauss point n of FEQuad8G9 at node n (FEStickyInterface's ``w[n] jac0(el, n)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError

__all__ = ["Facets", "SamplePoints", "shape", "shape_derivatives", "sample_points"]

TRIANGLES = (3, 6)
_G = 1.0 / np.sqrt(3.0)
_A = np.sqrt(0.6)
_G9 = (
    np.array([[r, s] for s in (-_A, 0.0, _A) for r in (-_A, 0.0, _A)]),
    np.array([a * b for b in (5, 8, 5) for a in (5, 8, 5)]) / 81.0,
)
_TRI3 = (np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]), np.full(3, 1 / 6))
_QUAD_SIGNS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
_QUAD8_NODES = np.array(
    [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [0, -1.0], [1.0, 0], [0, 1.0], [-1.0, 0]]
)
#: (rule, kind) -> (points (q, 2), weights (q,)[, where the area Jacobian is taken (q, 2)])
_RULES = {
    ("gauss", 4): (_G * _QUAD_SIGNS, np.ones(4)),
    ("gauss", 3): _TRI3,
    ("gauss", 8): _G9,
    ("gauss", 6): _TRI3,
    ("nodal", 4): (_QUAD_SIGNS, np.ones(4)),
    ("nodal", 3): (np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), np.full(3, 1 / 6)),
    ("nodal", 8): (_QUAD8_NODES, _G9[1][:8], _G9[0][:8]),
}


@dataclass(frozen=True)
class Facets:
    """(k, m) vertex indices (m = 4, or 8 with quadratic facets; rows padded by their last
    node) and each row's kind (its number of nodes: 3, 4, 6 or 8)."""

    nodes: np.ndarray
    kind: np.ndarray

    @property
    def triangle(self) -> np.ndarray:
        return np.isin(self.kind, TRIANGLES)

    @classmethod
    def of(cls, facets, where: str, kind: np.ndarray | None = None) -> Facets:
        """From rows of 3 / 4 corners (a triangle may repeat its last corner: (a, b, c, c)),
        or rows of 6 / 8 nodes (tri6, quad8; with ``kind`` a row may be padded)."""
        f = np.asarray(facets, dtype=np.int64)
        if f.ndim != 2 or f.shape[1] not in (3, 4, 6, 8) or len(f) == 0:
            raise InputError(
                f"{where}: contact facets must be rows of 3 or 4 corners, or 6 or 8 nodes "
                f"(quadratic triangles, quadrilaterals), got shape {f.shape}"
            )
        if kind is None:
            width = f.shape[1]
            kind = np.full(len(f), width)
            if width == 4:
                kind[f[:, 3] == f[:, 2]] = 3
        kind = np.asarray(kind, dtype=np.int64)
        width = 4 if kind.max() <= 4 else 8
        out = np.empty((len(f), width), dtype=np.int64)
        n = min(width, f.shape[1])
        out[:, :n] = f[:, :n]
        rows = np.arange(len(f))
        for j in range(width):  # pad each row past its kind with its last node
            past = kind <= j
            out[past, j] = f[rows[past], kind[past] - 1]
        return cls(out, kind)


def _quad4(r, s):
    sr, ss = _QUAD_SIGNS[:, 0], _QUAD_SIGNS[:, 1]
    H = 0.25 * (1 + sr * r[:, None]) * (1 + ss * s[:, None])
    Hr = 0.25 * sr * (1 + ss * s[:, None])
    Hs = 0.25 * ss * (1 + sr * r[:, None])
    zero = np.zeros_like(H)
    return H, Hr, Hs, zero, zero, np.broadcast_to(0.25 * sr * ss, H.shape)


def _tri3(r, s):
    n = len(r)
    H = np.column_stack([1 - r - s, r, s])
    zero = np.zeros((n, 3))
    Hr = np.broadcast_to(np.array([-1.0, 1.0, 0.0]), (n, 3))
    Hs = np.broadcast_to(np.array([-1.0, 0.0, 1.0]), (n, 3))
    return H, Hr, Hs, zero, zero, zero


def _quad8(r, s):
    """Serendipity: corners (1/4)(1 + r ri)(1 + s si)(r ri + s si - 1), midsides
    (1/2)(1 - r^2)(1 + s si) and (1/2)(1 + r ri)(1 - s^2)."""
    ri, si = _QUAD8_NODES[:, 0], _QUAD8_NODES[:, 1]
    R, S = r[:, None], s[:, None]
    a, b = 1 + R * ri, 1 + S * si  # (n, 8)
    corner = np.arange(8) < 4
    H = np.where(corner, 0.25 * a * b * (R * ri + S * si - 1), 0.0)
    Hr = np.where(corner, 0.25 * ri * b * (2 * R * ri + S * si), 0.0)
    Hs = np.where(corner, 0.25 * si * a * (R * ri + 2 * S * si), 0.0)
    Hrr = np.where(corner, 0.5 * b, 0.0)
    Hss = np.where(corner, 0.5 * a, 0.0)
    Hrs = np.where(corner, 0.25 * ri * si * (2 * R * ri + 2 * S * si + 1), 0.0)
    on_r = ~corner & (ri == 0)  # midsides of the edges s = -1, s = 1
    H = np.where(on_r, 0.5 * (1 - R**2) * b, H)
    Hr = np.where(on_r, -R * b, Hr)
    Hs = np.where(on_r, 0.5 * si * (1 - R**2), Hs)
    Hrr = np.where(on_r, -b, Hrr)
    Hrs = np.where(on_r, -R * si, Hrs)
    on_s = ~corner & (si == 0)  # midsides of the edges r = 1, r = -1
    H = np.where(on_s, 0.5 * a * (1 - S**2), H)
    Hr = np.where(on_s, 0.5 * ri * (1 - S**2), Hr)
    Hs = np.where(on_s, -S * a, Hs)
    Hss = np.where(on_s, -a, Hss)
    Hrs = np.where(on_s, -S * ri, Hrs)
    return H, Hr, Hs, Hrr, Hss, Hrs


def _tri6(r, s):
    """Corners L(2L - 1), midsides 4 L_i L_j (L = 1 - r - s, r, s)."""
    n = len(r)
    L = 1 - r - s
    H = np.column_stack([L * (2 * L - 1), r * (2 * r - 1), s * (2 * s - 1), 4 * L * r,
                         4 * r * s, 4 * s * L])  # fmt: skip
    z = np.zeros(n)
    Hr = np.column_stack([1 - 4 * L, 4 * r - 1, z, 4 * (L - r), 4 * s, -4 * s])
    Hs = np.column_stack([1 - 4 * L, z, 4 * s - 1, -4 * r, 4 * r, 4 * (L - s)])
    Hrr = np.broadcast_to(np.array([4.0, 4.0, 0.0, -8.0, 0.0, 0.0]), (n, 6))
    Hss = np.broadcast_to(np.array([4.0, 0.0, 4.0, 0.0, 0.0, -8.0]), (n, 6))
    Hrs = np.broadcast_to(np.array([4.0, 0.0, 0.0, -4.0, 4.0, -4.0]), (n, 6))
    return H, Hr, Hs, Hrr, Hss, Hrs


_SHAPES = {3: _tri3, 4: _quad4, 6: _tri6, 8: _quad8}


def _all(r: np.ndarray, s: np.ndarray, kind: np.ndarray, width: int):
    """(H, H_r, H_s, H_rr, H_ss, H_rs), each (n, width): a row's entries past its kind 0."""
    r, s, kind = np.asarray(r, float), np.asarray(s, float), np.asarray(kind)
    out = [np.zeros((len(r), width)) for _ in range(6)]
    for k, f in _SHAPES.items():
        rows = np.flatnonzero(kind == k)
        if len(rows):
            for o, v in zip(out, f(r[rows], s[rows]), strict=True):
                o[rows, :k] = v
    return out


def shape(r: np.ndarray, s: np.ndarray, kind: np.ndarray, width: int = 4) -> np.ndarray:
    """(n, width) shape function values at (r, s) of facets of the given kinds."""
    return _all(r, s, kind, width)[0]


def shape_derivatives(r: np.ndarray, s: np.ndarray, kind: np.ndarray, width: int = 4):
    """(dH/dr, dH/ds, d2H/dr2, d2H/ds2, d2H/drds), each (n, width)."""
    return tuple(_all(r, s, kind, width)[1:])


@dataclass(frozen=True)
class SamplePoints:
    """Points on facets: each point's facet row, (r, s), shape values H (n, m), weight (the
    rule's weight; times the facet's area Jacobian where it is used) and where that
    Jacobian is taken (``jacobian_rs``: (r, s) itself except for FEBio's quad8 nodal rule)."""

    facet: np.ndarray
    rs: np.ndarray
    H: np.ndarray
    weight: np.ndarray
    jacobian_rs: np.ndarray


def sample_points(facets: Facets, rule: str) -> SamplePoints:
    """Every facet's points of the rule ("gauss" or "nodal"), facet by facet."""
    rows, rs, weights, jrs = [], [], [], []
    for kind in np.unique(facets.kind):
        if (rule, int(kind)) not in _RULES:
            raise InputError(
                "node-on-facet and sticky contact (the nodal rule) do not take six-node "
                "triangles: use sliding-elastic or facet-on-facet on a tri6 surface"
            )
        idx = np.flatnonzero(facets.kind == kind)
        points, w, *at = _RULES[(rule, int(kind))]
        rows.append(np.repeat(idx, len(points)))
        rs.append(np.tile(points, (len(idx), 1)))
        weights.append(np.tile(w, len(idx)))
        jrs.append(np.tile(at[0] if at else points, (len(idx), 1)))
    facet = np.concatenate(rows)
    order = np.argsort(facet, kind="stable")
    facet = facet[order]
    rs_all = np.concatenate(rs)[order]
    H = shape(rs_all[:, 0], rs_all[:, 1], facets.kind[facet], facets.nodes.shape[1])
    return SamplePoints(facet, rs_all, H, np.concatenate(weights)[order],
                        np.concatenate(jrs)[order])  # fmt: skip


def area_jacobians(x: np.ndarray, facets: Facets, points: SamplePoints) -> np.ndarray:
    """|x_r x x_s| at each sample point's ``jacobian_rs`` for vertex positions x (n, 3)."""
    at = points.jacobian_rs
    Hr, Hs, *_ = shape_derivatives(at[:, 0], at[:, 1], facets.kind[points.facet],
                                   facets.nodes.shape[1])  # fmt: skip
    X = x[facets.nodes[points.facet]]  # (n, m, 3)
    xr = np.einsum("na,nad->nd", Hr, X)
    xs = np.einsum("na,nad->nd", Hs, X)
    return np.linalg.norm(np.cross(xr, xs), axis=1)


def with_midsides(mesh, facets: Facets) -> Facets:
    """A quadratic mesh's facets given by their corners, with the midside nodes of the cells'
    edges between consecutive corners appended (tri3 -> tri6 on 10-node tetrahedra, quad4 ->
    quad8 on 20- and 27-node hexahedra: a 27-node cell's face centre is left out); the facets
    as they are on a linear mesh or when they already hold their midsides."""
    if mesh.order != 2 or facets.kind.max() > 4:
        return facets
    from tissuesim.mesh.cells.quadratic import EDGES
    from tissuesim.mesh.cells.tensor_quadratic import HEX_EDGES

    cells = np.asarray(mesh.cells, dtype=np.int64)
    if mesh.simplicial:
        edges, mids = EDGES[3], cells[:, 4:10]
    else:
        edges, mids = HEX_EDGES, cells[:, 8:20]
    pairs = np.sort(cells[:, edges], axis=2).reshape(-1, 2)
    base = int(cells.max()) + 1
    keys = pairs[:, 0] * base + pairs[:, 1]
    order = np.argsort(keys, kind="stable")
    keys, mids = keys[order], mids.reshape(-1)[order]
    kind = facets.kind
    k = np.where(np.isin(kind, TRIANGLES), 3, 4)
    corners = facets.nodes[:, :4]
    nxt = np.where(k[:, None] == 3, corners[:, [1, 2, 0, 0]], corners[:, [1, 2, 3, 0]])
    p = np.sort(np.stack([corners, nxt], axis=2), axis=2)
    want = p[..., 0] * base + p[..., 1]
    pos = np.minimum(np.searchsorted(keys, want), keys.size - 1)
    found = keys[pos] == want
    edge = np.arange(4)[None] < k[:, None]
    if not np.all(found | ~edge):
        bad = int(np.flatnonzero(~np.all(found | ~edge, axis=1))[0])
        raise InputError(
            f"contact facet {corners[bad, : k[bad]].tolist()} is no face of the body's "
            f"{mesh.cell_type} cells: name facets by the corners of cell faces"
        )
    rows = np.concatenate([corners, mids[pos]], axis=1)  # (k, 8): 4 corners, 4 midsides
    rows = np.where(k[:, None] == 3, rows[:, [0, 1, 2, 4, 5, 6, 6, 6]], rows)
    return Facets.of(rows, "contact facets", kind=2 * k)
