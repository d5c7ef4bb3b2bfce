"""Constraint rows of a step's contact pairs (the "detect" stage of the predictor).

Pairs are the elements whose boxes, swept from the step's start V0 (bodies at x_n, obstacles
where they start) to the free motion V1 (bodies at x_free, obstacles at their targets) and
inflated by the ``keep`` distance, overlap (ipctk's broad phase), measured at V0, where the
surfaces are still apart and distances mean something; the closest points of each are computed
here in batches as a combination of the stencil's vertices, d = sum_k c_k v_k (a point-triangle
pair: v_p - (b0 v0 + b1 v1 + b2 v2); an edge-edge or point-edge pair alike), one pair per point
and other body (its nearest triangle) and edge pairs whose closest points are inside both edges;
with n = d / |d| at V0 frozen, the pair's gap is linear in the vertices,

    g(V) = n . sum_k c_k V_k,   g(V1) = the free motion's gap,

and its tangential slip over the step s(V) = T^T sum_k c_k (V_k - V0_k) with T two unit
tangents orthogonal to n (2D: one). Row r of J_V holds c_k n (then c_k t1, c_k t2) at vertex
k's coordinates. A pair whose free gap stays above the ``keep`` distance is left out: its
multiplier would be zero.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from tissuesim.contact.predict.broad_phase import compiled_candidates

__all__ = ["ContactRows", "detect_rows", "sides_kept", "sweep_candidates"]

#: pairs are kept where the step ends (``at``) within this many times the keep distance (2
#: let one grasp step and one drop step in 20 at 3e4 tetrahedra cross a surface)
AT_KEEP = 3.0


@dataclass(frozen=True)
class ContactRows:
    """m pairs, dimension d. ``J`` (m d, d n_vertices): rows per pair [normal, tangents...];
    ``gap_start`` (m,) n . d at V0 (m); ``gap_free`` (m,) at V1; ``slip_free`` (m, d - 1) the
    tangential motion of the free step (m); ``mu`` (m,) Coulomb coefficients; ``normals``
    (m, d) and ``tangents`` (m, d - 1, d); ``vertices`` (m, 4) stencil vertex ids (-1 unused);
    ``coefficients`` (m, 4); ``kinds`` (m,) 0 a point and a triangle, 1 two edges, 2 a point
    and an edge (2D); ``weights`` (m,) ipctk's area weights of the pairs (the barrier's
    force on a pair at distance d is its weight times ``barrier.force_magnitude(d^2, 0)``)."""

    J: sp.csr_matrix
    gap_start: np.ndarray
    gap_free: np.ndarray
    slip_free: np.ndarray
    mu: np.ndarray
    normals: np.ndarray
    tangents: np.ndarray
    vertices: np.ndarray
    coefficients: np.ndarray
    weights: np.ndarray
    kinds: np.ndarray

    def keys(self, group: np.ndarray) -> list[tuple]:
        """A name per pair that survives a step: a point's pair by the point and the body (or
        obstacle) it meets (its nearest triangle changes as it slides), two edges by their
        four vertices. Warm starts and learnt weights follow pairs by it."""
        other = group[np.maximum(self.vertices[:, 1], 0)]
        return [
            (1, *v) if k == 1 else (k, v[0], int(g))
            for k, v, g in zip(
                self.kinds.tolist(), self.vertices.tolist(), other.tolist(), strict=True
            )
        ]

    @property
    def n_pairs(self) -> int:
        return len(self.gap_start)

    @property
    def dim(self) -> int:
        return self.normals.shape[1]

    def free_values(self) -> np.ndarray:
        """(m, d) the free motion's [gap, slip...] per pair: the right-hand side of the
        contact problem before any contact force."""
        return np.column_stack([self.gap_free, self.slip_free])


def _candidates(contact, V0: np.ndarray, V1: np.ndarray, inflation: float):
    """(kind, ids) of the broad phase's candidates over the swept boxes V0 -> V1 inflated by
    ``inflation``: kind 0 a point and a triangle [p, a, b, c] (3D), 1 two edges [a, b, c, d]
    (3D), 2 a point and an edge [p, a, b, -1] (2D). ipctk hands candidates out one at a time;
    only their ids are read here, the geometry is batched (``_closest``); with numba the same
    pairs come as arrays from a compiled grid (``broad_phase.py``: a third of the time)."""
    parts = compiled_candidates(contact, V0, V1, inflation)
    if parts is not None:
        return parts
    ipctk = contact._ipctk
    cand = contact.candidates.held(V0, V1) if inflation <= 0.5 * contact.dhat else None
    if cand is None:
        cand = ipctk.Candidates()
        cand.build(contact.mesh, V0, V1, inflation, broad_phase=contact.broad_phase)
    E, F = contact.mesh.edges, contact.mesh.faces
    fv = np.array([(c.vertex_id, c.face_id) for c in cand.fv_candidates], dtype=np.int64)
    ee = np.array([(c.edge0_id, c.edge1_id) for c in cand.ee_candidates], dtype=np.int64)
    ev = np.array([(c.vertex_id, c.edge_id) for c in cand.ev_candidates], dtype=np.int64)
    parts = []
    if len(fv):
        parts.append((0, np.column_stack([fv[:, 0], F[fv[:, 1]]])))
    if len(ee):
        parts.append((1, np.column_stack([E[ee[:, 0]], E[ee[:, 1]]])))
    if len(ev) and V0.shape[1] == 2:
        parts.append((2, np.column_stack([ev[:, 0], E[ev[:, 1]], np.full(len(ev), -1)])))
    return parts


def sweep_candidates(contact, V0: np.ndarray, ends: list, inflation: float) -> dict:
    """{kind: [stencils]} of the sweeps from V0 to each of ``ends`` (``_candidates``): kept
    by the predictor so that the gaps can be linearised again without a broad phase."""
    parts: dict[int, list] = {}
    for V1 in ends:
        for kind, stencil in _candidates(contact, V0, V1, inflation):
            parts.setdefault(kind, []).append(stencil)
    return parts


def _segment_params(p, a, b):
    """Closest point of segments a b to points p: the clamped parameter (k,)."""
    ab = b - a
    t = np.einsum("kd,kd->k", p - a, ab) / np.maximum(np.einsum("kd,kd->k", ab, ab), 1e-300)
    return np.clip(t, 0.0, 1.0)


def _point_triangle(p, a, b, c):
    """Coefficients (k, 4) of d = p - (wa a + wb b + wc c), the closest point of triangle abc
    to p: inside, the plane's projection; else the closest of the three edges."""
    ab, ac, ap = b - a, c - a, p - a
    d00 = np.einsum("kd,kd->k", ab, ab)
    d01 = np.einsum("kd,kd->k", ab, ac)
    d11 = np.einsum("kd,kd->k", ac, ac)
    d20 = np.einsum("kd,kd->k", ap, ab)
    d21 = np.einsum("kd,kd->k", ap, ac)
    den = np.maximum(d00 * d11 - d01 * d01, 1e-300)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    u = 1.0 - v - w
    weights = np.column_stack([u, v, w])
    inside = (u >= 0) & (v >= 0) & (w >= 0)
    best = np.full(len(p), np.inf)
    out = np.zeros((len(p), 3))
    for i, j in ((0, 1), (1, 2), (2, 0)):
        corners = (a, b, c)
        t = _segment_params(p, corners[i], corners[j])
        q = corners[i] + t[:, None] * (corners[j] - corners[i])
        dist = np.einsum("kd,kd->k", p - q, p - q)
        better = dist < best
        best = np.where(better, dist, best)
        edge = np.zeros((len(p), 3))
        edge[:, i], edge[:, j] = 1.0 - t, t
        out[better] = edge[better]
    weights = np.where(inside[:, None], weights, out)
    return np.column_stack([np.ones(len(p)), -weights])


def _edge_edge(a, b, c, d):
    """Coefficients (k, 4) of d = (a + s (b - a)) - (c + t (d - c)) at the segments' closest
    points, and whether both parameters are interior (an end point's contact is a point's)."""
    u, v, w = b - a, d - c, a - c
    A = np.einsum("kd,kd->k", u, u)
    B = np.einsum("kd,kd->k", u, v)
    C = np.einsum("kd,kd->k", v, v)
    D = np.einsum("kd,kd->k", u, w)
    Ee = np.einsum("kd,kd->k", v, w)
    den = A * C - B * B
    parallel = den <= 1e-12 * np.maximum(A * C, 1e-300)
    s = np.where(parallel, 0.0, (B * Ee - C * D) / np.where(parallel, 1.0, den))
    s = np.clip(s, 0.0, 1.0)
    t = np.clip((B * s + Ee) / np.maximum(C, 1e-300), 0.0, 1.0)
    s = np.clip((B * t - D) / np.maximum(A, 1e-300), 0.0, 1.0)
    interior = ~parallel & (s > 1e-6) & (s < 1 - 1e-6) & (t > 1e-6) & (t < 1 - 1e-6)
    return np.column_stack([1.0 - s, s, -(1.0 - t), -t]), interior


def _stencils(contact, V0: np.ndarray, ends, inflation: float, at: np.ndarray, later=None):
    """(vertex ids (m, 4) with -1 unused, coefficients (m, 4), kinds (m,)) of the pairs the
    sweeps from V0 to each of ``ends`` (or ``sweep_candidates``' answer) can make, their
    closest points taken at ``at``: a point and the closest triangle of each other body (or
    obstacle) near it, two edges whose closest points are inside both, in 2D a point and its
    closest edge per body; ``later``: positions where two edges' closest points inside both
    also count (taken there)."""
    group = contact.group
    parts = ends if isinstance(ends, dict) else sweep_candidates(contact, V0, ends, inflation)
    ids, coefs, kinds = [], [], []
    for kind, stencils in parts.items():
        stencil = np.unique(np.vstack(stencils), axis=0) if len(stencils) > 1 else stencils[0]
        if kind == 1:
            coef, interior = _edge_edge(*(at[stencil[:, k]] for k in range(4)))
            if later is not None:
                # two edges that meet inside both only later in the step (a long edge swept
                # across a small instrument's): their closest points there
                coef_later, interior_later = _edge_edge(*(later[stencil[:, k]] for k in range(4)))
                coef = np.where(interior[:, None], coef, coef_later)
                interior = interior | interior_later
            stencil, coef = stencil[interior], coef[interior]
        elif kind == 0:
            coef = _point_triangle(*(at[stencil[:, k]] for k in range(4)))
        else:
            ab = stencil[:, :3]
            t = _segment_params(at[ab[:, 0]], at[ab[:, 1]], at[ab[:, 2]])
            coef = np.column_stack([np.ones(len(t)), -(1.0 - t), -t, np.zeros(len(t))])
        if kind != 1 and len(stencil):
            # one pair per point and other body: the nearest of its triangles (edges in 2D);
            # the others repeat its constraint (W singular, Gauss-Seidel slow)
            used = stencil >= 0
            safe = np.where(used, stencil, 0)
            dist = np.linalg.norm(np.einsum("mk,mkd->md", coef, at[safe]), axis=1)
            key = stencil[:, 0] * (group.max() + 1) + group[stencil[:, 1]]
            order = np.lexsort((dist, key))
            first = np.ones(len(order), dtype=bool)
            first[1:] = key[order][1:] != key[order][:-1]
            keep = order[first]
            stencil, coef = stencil[keep], coef[keep]
        ids.append(stencil)
        coefs.append(coef)
        kinds.append(np.full(len(stencil), kind))
    if not ids:
        return np.zeros((0, 4), dtype=np.int64), np.zeros((0, 4)), np.zeros(0, dtype=np.int64)
    return np.vstack(ids), np.vstack(coefs), np.concatenate(kinds)


def _weights(mesh, ids: np.ndarray, kinds: np.ndarray) -> np.ndarray:
    """The area weight IPC's barrier gives each pair (ipctk 1.6's area weighting, measured: a
    point and a triangle a quarter of the point's vertex area; two edges a quarter of the sum
    of their edge areas, estimated here from their vertices' areas). ``calibrate`` in
    ``predictor.py`` learns the weight the barrier really spreads over a pair."""
    if not len(ids):
        return np.zeros(0)
    areas = np.asarray(mesh.vertex_areas)
    point = 0.25 * areas[ids[:, 0]]
    edges = 0.25 * 0.5 * areas[np.maximum(ids, 0)].sum(axis=1)
    return np.where(kinds == 1, edges, point)


def _tangents(normals: np.ndarray) -> np.ndarray:
    """(m, d - 1, d): unit tangents orthogonal to each normal (a right-handed frame in 3D)."""
    m, d = normals.shape
    if d == 2:
        return np.stack([-normals[:, 1], normals[:, 0]], axis=1)[:, None, :]
    helper = np.zeros_like(normals)
    helper[np.arange(m), np.argmin(np.abs(normals), axis=1)] = 1.0
    t1 = np.cross(normals, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    return np.stack([t1, t2], axis=1)


def detect_rows(
    contact,
    V0: np.ndarray,
    V1: np.ndarray,
    keep: float,
    also: np.ndarray | None = None,
    at: np.ndarray | None = None,
    candidates: dict | None = None,
) -> ContactRows:
    """The pairs of ``contact`` (a ContactModel: its collision mesh, pair table, dhat) that the
    free motion V0 -> V1 (collision-mesh vertices, (n, d), obstacles included) can bring within
    ``keep`` (m) of each other, with their rows (module docstring); ``also``: further
    positions whose sweep from V0 adds candidates (a correction that moved vertices the free
    motion did not bring near); ``at``: where the closest points and normals are taken
    (default V0: the step's start; a first prediction's positions linearise the gaps where
    the step ends, which a probe sliding a millimetre over a face needs: the face's plane
    frozen at the start stands off its sphere by the slide squared over twice the radius).
    A pair whose closest-point vector at ``at`` points against the one at V0 (crossed by
    these coefficients) is left out. ``candidates``: ``sweep_candidates``' answer for these
    sweeps, when known (the broad phase is skipped)."""
    d = V0.shape[1]
    V0, V1 = np.asfortranarray(V0), np.asfortranarray(V1)
    ends = [V1] if also is None else [V1, np.asfortranarray(also)]
    if candidates is not None:
        ends = candidates
    geometry = V0 if at is None else np.asfortranarray(at)
    ids, coefs, kinds = _stencils(contact, V0, ends, keep, geometry, V1)
    weights = _weights(contact.mesh, ids, kinds)
    used = ids >= 0
    safe = np.where(used, ids, 0)
    vec0 = np.einsum("mk,mkd->md", coefs, V0[safe])
    vec_at = vec0 if at is None else np.einsum("mk,mkd->md", coefs, geometry[safe])
    length = np.linalg.norm(vec_at, axis=1)
    ok = (length > 0.0) & (np.einsum("md,md->m", vec_at, vec0) > 0.0)
    normals = vec_at[ok] / length[ok, None]
    ids, coefs, safe, used, weights = ids[ok], coefs[ok], safe[ok], used[ok], weights[ok]
    kinds = kinds[ok]
    vec1 = np.einsum("mk,mkd->md", coefs, V1[safe])
    gap_free = np.einsum("md,md->m", normals, vec1)
    near = gap_free < keep
    if at is not None:
        # and near where the step ends (a first prediction's positions): a probe pressing an
        # organ sweeps over 3-10x the pairs that carry force there, and W costs their square
        near &= length[ok] < AT_KEEP * keep
    ids, coefs, safe, used, weights = ids[near], coefs[near], safe[near], used[near], weights[near]
    kinds = kinds[near]
    gap_start = np.einsum("md,md->m", normals, vec0[ok])[near]
    normals, gap_free = normals[near], gap_free[near]
    tangents = _tangents(normals)
    slip = np.einsum("mtd,md->mt", tangents, vec1[near] - vec0[ok][near])
    m = len(ids)
    # entry (pair i, direction a, stencil vertex k, coordinate j): row i d + a, column
    # vertex_k d + j, value c_k (direction a)_j; direction 0 the normal, then the tangents
    directions = np.concatenate([normals[:, None, :], tangents], axis=1)  # (m, d, d)
    shape = (m, d, 4, d)
    rows = np.broadcast_to((np.arange(m)[:, None] * d + np.arange(d))[:, :, None, None], shape)
    cols = np.broadcast_to((safe[:, :, None] * d + np.arange(d))[:, None, :, :], shape)
    values = coefs[:, None, :, None] * directions[:, :, None, :]
    mask = np.broadcast_to(used[:, None, :, None], shape)
    J = sp.csr_matrix((values[mask], (rows[mask], cols[mask])), shape=(m * d, d * len(V0)))
    groups = contact.group
    first = groups[safe[:, 0]]
    last = groups[np.take_along_axis(safe, used.sum(axis=1)[:, None] - 1, axis=1)[:, 0]]
    mu = contact.table.mu[first, last] if m else np.zeros(0)
    return ContactRows(
        J=J,
        gap_start=gap_start,
        gap_free=gap_free,
        slip_free=slip,
        mu=np.asarray(mu, dtype=float),
        normals=normals,
        tangents=tangents,
        vertices=np.where(used, ids, -1),
        coefficients=coefs,
        weights=weights,
        kinds=kinds,
    )


def sides_kept(contact, V0: np.ndarray, V1: np.ndarray, slack: float) -> bool:
    """Whether no point passed through a triangle and no edge through an edge between V0 and
    V1, judged at the two ends: for every candidate pair of the swept boxes, a point that lies
    over its triangle at the end (its projection inside) is on the side of the triangle's
    plane it started on, and two edges whose closest points are inside both at the end keep
    the side of each other they started on; an end within ``slack`` (m) of the plane (or the
    other edge's line) counts as on either side (a point grazing a face's edge next to the
    face it meets lies a hair under the first face's plane). With the end free of
    intersection (exact test), this rules out a surface tunnelled through in the step."""
    V0, V1 = np.asfortranarray(V0), np.asfortranarray(V1)
    for kind, stencil in _candidates(contact, V0, V1, 0.0):
        if kind == 0:
            a0, a1 = (V[stencil[:, 1]] for V in (V0, V1))
            n0 = np.cross(V0[stencil[:, 2]] - a0, V0[stencil[:, 3]] - a0)
            n1 = np.cross(V1[stencil[:, 2]] - a1, V1[stencil[:, 3]] - a1)
            side0 = np.einsum("kd,kd->k", n0, V0[stencil[:, 0]] - a0)
            side1 = np.einsum("kd,kd->k", n1, V1[stencil[:, 0]] - a1)
            # the projection inside the triangle at both ends
            over = np.all(
                _point_triangle(*(V1[stencil[:, k]] for k in range(4)))[:, 1:] < 0, axis=1
            )
            over &= np.all(
                _point_triangle(*(V0[stencil[:, k]] for k in range(4)))[:, 1:] < 0, axis=1
            )
        elif kind == 1:
            a, b, c, d = (V0[stencil[:, k]] for k in range(4))
            n0 = np.cross(b - a, d - c)
            side0 = np.einsum("kd,kd->k", n0, a - c)
            _, over = _edge_edge(a, b, c, d)
            a, b, c, d = (V1[stencil[:, k]] for k in range(4))
            n1 = np.cross(b - a, d - c)
            side1 = np.einsum("kd,kd->k", n1, a - c)
            over &= _edge_edge(a, b, c, d)[1]  # closest points inside both edges at both ends
        else:
            continue
        beyond = np.abs(side1) > slack * np.linalg.norm(n1, axis=1)
        if np.any(over & beyond & (side0 * side1 < 0.0)):
            return False
    return True
