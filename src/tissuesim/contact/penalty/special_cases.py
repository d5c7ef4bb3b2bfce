"""FEBio's special cases of the closest-point projection (``FEClosestPointProjection::
ProjectSpecial``, on with ``HandleSpecialCases(true)``: node-on-facet, facet-on-facet, tied
node-on-facet / facet-on-facet and sticky contacts; not sliding-elastic, which casts rays).

A point whose projection lands on no facet (within the search tolerance) is projected, as
FEBio does, onto an *interior* edge of the target surface (one with a facet on both sides) that
holds the surface's node closest to the point, q = (1 - l) a + l b with l in [0, 1] the
segment's closest point, when that is closer than the node; else onto the closest node itself,
q = that node, unless the node lies on the surface's boundary (an edge with one facet): then
the point is out of contact. tissuesim takes the node only where it is the closest point
(the point not ahead of it along any of its edges; FEBio takes it wherever no edge does).
The point keeps a facet that holds q (for its stencil and the side) and q's (r, s) on it.
With the special cases a point is on a facet only where its projection is strictly on it
(``pair.py``): FEBio's search-tolerance band, where the extended facet's gap differs from the
edge's and the energy would jump at the band's edge (co15 stopped there at t = 0.04 s), is
kept only for points that no edge or node takes (the surface's rim).

FEBio's gap there is nu_F . (q - x) with nu_F the facet's normal, which jumps where the point
passes from the edge's region into the other facet's (by |q - x| (1 - cos) of the facets'
angle). tissuesim takes the distance to the edge or node instead, signed by that normal,

    g = sign(nu_F . (q - x)) |q - x|,

which equals nu_F . (q - x) where the region meets either facet's (q - x is normal to the
facet there): the gap, its gradient in x and so the energy are continuous across a concave
valley or a convex ridge. With nu = (q - x) / g and J = dq/dy - dx/dy at fixed l (the stencil's
weights w = (-Hs, Hm) times I, as for a facet), the envelope theorem on D = |q - x|^2 / 2 gives

    dg/dy = J^T nu,
    d2D = J^T J - u u^T / |e|^2     (edge: e = b - a, u = J^T e + c, c = -d at a, +d at b,
                                     d = q - x; a node: d2D = J^T J),
    d2g = (d2D - dg dg^T) / g.

Only linear facets (tri3, quad4) take these cases (on a quadratic facet's curved edge q is
not the segment's point); a surface with quadratic facets keeps FEBio's plain projection.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from tissuesim.contact.penalty.faces import TRIANGLES, Facets, shape
from tissuesim.contact.penalty.projection import gap_derivatives

__all__ = ["Topology", "Special", "special_contacts", "nearest_feature", "in_order", "contact_gaps"]

_TRI_CORNERS = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
_QUAD_CORNERS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


@dataclass(frozen=True)
class Topology:
    """A linear facet surface's edges and nodes, for the special cases."""

    nodes: np.ndarray  # (v,) the surface's vertex indices (in its body)
    edge_nodes: np.ndarray  # (E, 2) local node indices of interior edges
    edge_facet: np.ndarray  # (E,) a facet holding the edge
    edge_slots: np.ndarray  # (E, 2) the edge's nodes' corner slots in that facet
    node_edges: np.ndarray  # (v, V) interior edges at each node (-1: none)
    node_facet: np.ndarray  # (v,) a facet holding the node
    node_slot: np.ndarray  # (v,) its corner slot there
    boundary: np.ndarray  # (v,) the node lies on a boundary edge
    neighbours: np.ndarray  # (v, V) the nodes an edge joins to each node (-1: none)

    @classmethod
    def of(cls, facets: Facets) -> Topology | None:
        """The surface's topology; None when it has quadratic facets."""
        kind = facets.kind
        if not np.all(np.isin(kind, (3, 4))):
            return None
        tri = np.isin(kind, TRIANGLES)
        nodes, local = np.unique(facets.nodes[:, :4], return_inverse=True)
        local = local.reshape(len(kind), -1)
        rows, slots_a, slots_b = [], [], []
        for k in range(4):  # edge k: corners k, k + 1 (a triangle has 3)
            f = np.flatnonzero(~tri) if k == 3 else np.arange(len(kind))
            nxt = (k + 1) % np.where(tri[f], 3, 4)
            rows.append(f)
            slots_a.append(np.full(len(f), k))
            slots_b.append(nxt)
        f = np.concatenate(rows)
        sa, sb = np.concatenate(slots_a), np.concatenate(slots_b)
        a, b = local[f, sa], local[f, sb]
        key = np.sort(np.column_stack([a, b]), axis=1)
        uniq, first, inverse, count = np.unique(
            key, axis=0, return_index=True, return_inverse=True, return_counts=True
        )
        inverse = inverse.ravel()
        interior = count >= 2
        v = len(nodes)
        boundary = np.zeros(v, bool)
        boundary[uniq[~interior].ravel()] = True
        inner = np.flatnonzero(interior)
        edge_nodes = np.column_stack([a[first[inner]], b[first[inner]]])
        edge_facet = f[first[inner]]
        edge_slots = np.column_stack([sa[first[inner]], sb[first[inner]]])
        ends = edge_nodes.ravel()
        ids = np.repeat(np.arange(len(inner)), 2)
        order = np.argsort(ends, kind="stable")
        counts = np.bincount(ends, minlength=v)
        width = max(int(counts.max()) if len(counts) else 0, 1)
        node_edges = -np.ones((v, width), dtype=np.int64)
        start = np.concatenate([[0], np.cumsum(counts)[:-1]])
        pos = np.arange(len(ends)) - np.repeat(start, counts)
        node_edges[ends[order], pos] = ids[order]
        both = np.concatenate([uniq, uniq[:, ::-1]])
        both = both[np.lexsort((both[:, 1], both[:, 0]))]
        nb_count = np.bincount(both[:, 0], minlength=v)
        nb_start = np.concatenate([[0], np.cumsum(nb_count)[:-1]])
        neighbours = -np.ones((v, max(int(nb_count.max()), 1)), dtype=np.int64)
        neighbours[both[:, 0], np.arange(len(both)) - nb_start[both[:, 0]]] = both[:, 1]
        node_facet = np.empty(v, dtype=np.int64)
        node_slot = np.empty(v, dtype=np.int64)
        corners = np.where(tri[:, None], np.arange(4) % 3, np.arange(4))  # (k, 4)
        fl = np.repeat(np.arange(len(kind)), 4)[::-1]
        node_facet[local[fl, corners.ravel()[::-1]]] = fl  # the lowest facet wins
        node_slot[local[fl, corners.ravel()[::-1]]] = corners.ravel()[::-1]
        return cls(nodes, edge_nodes, edge_facet, edge_slots, node_edges, node_facet,
                   node_slot, boundary, neighbours)  # fmt: skip


@dataclass(frozen=True)
class Special:
    """Which contacts are special: ``rows`` (into the contacts), their edge's corner slots
    (``slots`` (n, 2); a node: both the node's) and the edge parameter ``l``."""

    rows: np.ndarray
    slots: np.ndarray
    l: np.ndarray  # noqa: E741

    @classmethod
    def none(cls) -> Special:
        return cls(np.zeros(0, int), np.zeros((0, 2), int), np.zeros(0))


def special_contacts(x: np.ndarray, P: np.ndarray, facets: Facets, topo: Topology):
    """FEBio's edge and node projections of points x (n, 3) that found no facet, onto the
    surface ``facets`` with body positions P: (which of x (i,), their facet, (r, s), corner
    slots (i, 2), edge parameter l)."""
    nodes = P[topo.nodes]
    d_node, c = cKDTree(nodes).query(x, k=1)
    E = topo.node_edges[c]  # (n, V)
    rows = np.arange(len(x))
    if E.shape[1] and len(topo.edge_nodes):
        has = E >= 0
        Es = np.where(has, E, 0)
        a = nodes[topo.edge_nodes[Es, 0]]
        b = nodes[topo.edge_nodes[Es, 1]]
        e = b - a
        ee = np.einsum("nvd,nvd->nv", e, e)
        ok = has & (ee > 0)
        lam = np.einsum("nvd,nvd->nv", e, x[:, None] - a) / np.where(ok, ee, 1.0)
        q = a + lam[..., None] * e
        D2 = np.einsum("nvd,nvd->nv", x[:, None] - q, x[:, None] - q)
        ok &= (lam >= 0.0) & (lam <= 1.0) & (D2 < d_node[:, None] ** 2)
        D2 = np.where(ok, D2, np.inf)
        best = np.argmin(D2, axis=1)
        on_edge = np.isfinite(D2[rows, best])
        edge, l_edge = Es[rows, best], lam[rows, best]
    else:  # a surface without interior edges (a single facet): nodes only
        on_edge = np.zeros(len(x), bool)
        edge, l_edge = np.zeros(len(x), int), np.zeros(len(x))
    # the node only where it is the closest point: x not ahead of it along any of its edges
    # (FEBio takes it whenever no edge does: beside a boundary edge, whose nodes may be
    # farther than an interior one, that made the gap jump from the facet's to the node's)
    nb = topo.neighbours[c]
    ahead = np.einsum("nvd,nd->nv", nodes[np.where(nb >= 0, nb, 0)] - nodes[c][:, None],
                      x - nodes[c])  # fmt: skip
    cone = np.all((nb < 0) | (ahead <= 0.0), axis=1)
    on_node = ~on_edge & ~topo.boundary[c] & cone
    which = np.flatnonzero(on_edge | on_node)
    edge_rows = on_edge[which]
    facet = np.where(edge_rows, topo.edge_facet[edge[which]], topo.node_facet[c[which]])
    node_slot = topo.node_slot[c[which]]
    slots = np.where(
        edge_rows[:, None], topo.edge_slots[edge[which]], np.column_stack([node_slot] * 2)
    )
    l = np.where(edge_rows, l_edge[which], 0.0)  # noqa: E741
    corners = np.where(
        np.isin(facets.kind[facet], TRIANGLES)[:, None, None],
        np.pad(_TRI_CORNERS, ((0, 1), (0, 0)))[None],
        _QUAD_CORNERS[None],
    )
    ix = np.arange(len(which))
    rs = (1 - l)[:, None] * corners[ix, slots[:, 0]] + l[:, None] * corners[ix, slots[:, 1]]
    return which, facet, rs, slots, l


def nearest_feature(x, X, rs, kind, Xc, rsc, kindc) -> np.ndarray:
    """Which special projections (points x (n, 3) at (r, s) on facets X) are not farther than
    the point's candidate facets (Xc, rsc, kindc: k per point, flattened) with the projection
    clamped onto each: beside a boundary edge an edge or node farther off than the facet is
    not the closest point, and the gap would jump there from the facet's to its distance."""
    if len(x) == 0:
        return np.zeros(0, bool)
    H = shape(rs[:, 0], rs[:, 1], kind, X.shape[1])
    d_special = np.linalg.norm(np.einsum("na,nad->nd", H, X) - x, axis=1)
    r = rsc.copy()
    tri = np.isin(kindc, TRIANGLES)
    r = np.where(tri[:, None], np.maximum(r, 0.0), np.clip(r, -1.0, 1.0))
    over = tri & (r.sum(axis=1) > 1.0)
    r[over] /= r[over].sum(axis=1)[:, None]
    q = np.einsum("na,nad->nd", shape(r[:, 0], r[:, 1], kindc, Xc.shape[1]), Xc)
    d = np.linalg.norm(q - np.repeat(x, len(rsc) // len(x), axis=0), axis=1)
    return d_special <= d.reshape(len(x), -1).min(axis=1) * (1.0 + 1e-9)


def in_order(pts, facet, rs, special: Special):
    """The contacts sorted by point (``friction.py`` searches them), ``special`` along."""
    order = np.argsort(pts, kind="stable")
    where = np.empty_like(order)
    where[order] = np.arange(len(order))
    special = Special(where[special.rows], special.slots, special.l)
    return pts[order], facet[order], rs[order], special


def contact_gaps(x, Hs, X, rs, kind, special: Special | None, order: int):
    """``projection.gap_derivatives``'s (g, nu, Hm[, dg/dy[, d2g/dy2]]) for contacts of which
    ``special`` are edge or node projections (module docstring)."""
    out = gap_derivatives(x, Hs, X, rs, kind, order)
    if special is None or len(special.rows) == 0:
        return out
    i = special.rows
    Hm = out[2][i]
    d = np.einsum("na,nad->nd", Hm, X[i]) - x[i]
    dist = np.linalg.norm(d, axis=1)
    live = dist > 1e-14 * np.max(np.abs(X[i]), axis=(1, 2))  # at q itself: the facet's gap
    i, d, dist, Hm = i[live], d[live], dist[live], Hm[live]
    sgn = np.where(np.einsum("nd,nd->n", out[1][i], d) < 0, -1.0, 1.0)
    g = sgn * dist
    nu = d / g[:, None]
    out[0][i], out[1][i] = g, nu
    if order < 1:
        return out
    w = np.concatenate([-Hs[i], Hm], axis=1)
    out[3][i] = w[:, :, None] * nu[:, None, :]
    if order < 2:
        return out
    n, width = len(i), w.shape[1]
    k = width - Hm.shape[1]
    JJ = np.einsum("na,nb,ij->naibj", w, w, np.eye(3)).reshape(n, 3 * width, 3 * width)
    slots = special.slots[live]
    edge = slots[:, 0] != slots[:, 1]
    if edge.any():
        ix = np.arange(n)[edge]
        sa, sb = k + slots[edge, 0], k + slots[edge, 1]
        Xi = X[i[edge]]
        e = Xi[np.arange(len(ix)), sb - k] - Xi[np.arange(len(ix)), sa - k]  # b - a
        u = (w[edge][:, :, None] * e[:, None, :]).copy()  # J^T e
        u[np.arange(len(ix)), sa] -= d[edge]
        u[np.arange(len(ix)), sb] += d[edge]
        u = u.reshape(len(ix), 3 * width)
        JJ[ix] -= u[:, :, None] * u[:, None, :] / np.sum(e * e, axis=1)[:, None, None]
    dg = out[3][i].reshape(n, 3 * width)
    out[4][i] = (JJ - dg[:, :, None] * dg[:, None, :]) / g[:, None, None]
    return out
