"""The predictor's broad phase: the primitive pairs whose boxes, swept from V0 to V1 and
inflated, overlap, as index arrays.

ipctk's ``Candidates.build`` finds them with its BVH, but hands them to Python one object at
a time: an organ of 1e4 tetrahedra resting on a table has about 19,000 candidates a step (its
own surface's included, for self-contact), and reading them cost 10.6 ms a step, more than the
BVH (4.5 ms). ``box_grid.py`` finds them in a compiled uniform grid and returns arrays, with
ipctk 1.6's boxes (a vertex's spans its two positions, inflated by r and one ulp on every
side; an edge's or a face's is the union of its vertices'), its closed overlap test and its
filters (a point and a face, two edges, a point and an edge (2D) share no vertex; some vertex
pair of the two may collide: their bodies' pair is enabled in the pair table, which never
enables two obstacles), so it finds the same pairs (``tests/contact/``
``test_predicted_broad_phase.py``). The drop's candidates: 16.6 ms with ipctk, 6.1 ms here;
the grasp's 12.0 and 6.9.

Without numba (``tissuesim[fast]``), or with a vertex filter beyond the pair table (a cut
body's pairs that touch at rest, ``contact/cut/rest_proximity.py``), the caller uses ipctk's.
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["compiled_candidates"]


@functools.cache
def _kernel():
    """The compiled pair search (``box_grid.py``: numba, cached on disk), or None."""
    try:
        from tissuesim.contact.predict.box_grid import overlap_pairs, primitive_boxes
    except ImportError:  # no numba
        return None
    return overlap_pairs, primitive_boxes


def _pairs(kernel, lo_a, hi_a, lo_b, hi_b, same, a_ids, b_ids, group, enabled) -> np.ndarray:
    """(k, 2) int64 pairs of ``box_grid.overlap_pairs``, body by body: each enabled pair of
    bodies (or a body and an obstacle) in its own grid, sized to the second one's items (a
    probe's 1 mm faces and an organ's 10 mm ones in one grid cost the palpation 12 ms a
    step). The same inputs give the same pairs in the same order."""
    if not len(lo_a) or not len(lo_b):
        return np.zeros((0, 2), dtype=np.int64)
    ga, gb = group[a_ids[:, 0]], group[b_ids[:, 0]]
    found = []
    for i in np.unique(ga).tolist():
        a = np.flatnonzero(ga == i)
        for j in np.unique(gb).tolist():
            if not enabled[i, j] or (same and j < i):
                continue
            b = np.flatnonzero(gb == j)
            one = same and i == j  # a with itself: each pair once
            args = (lo_a[a], hi_a[a], lo_b[b], hi_b[b], one, a_ids[a], b_ids[b], group, enabled)
            out = np.empty((8 * (len(a) + len(b)), 2), dtype=np.int64)
            count = kernel(*args, out)
            if count > len(out):  # more than guessed: again with room for all
                out = np.empty((count, 2), dtype=np.int64)
                kernel(*args, out)
            found.append(np.column_stack([a[out[:count, 0]], b[out[:count, 1]]]))
    return np.vstack(found) if found else np.zeros((0, 2), dtype=np.int64)


def compiled_candidates(contact, V0: np.ndarray, V1: np.ndarray, inflation: float):
    """``rows._candidates``' answer, (kind, stencils) parts: kind 0 a point and a triangle
    [p, a, b, c] (3D), 1 two edges [a, b, c, d] (3D), 2 a point and an edge [p, a, b, -1]
    (2D); None when this search does not apply (no numba; a filter beyond the pair table)."""
    kernels = _kernel()
    if kernels is None or getattr(contact, "rest_filtered", False):
        return None
    kernel, primitive_boxes = kernels
    V0 = np.asarray(V0, dtype=float)
    V1 = np.asarray(V1, dtype=float)
    # ipctk's conservative inflation: one ulp outward (boxes of two faces that share a
    # coordinate computed two ways touch)
    lo = np.ascontiguousarray(np.nextafter(np.minimum(V0, V1) - inflation, -np.inf))
    hi = np.ascontiguousarray(np.nextafter(np.maximum(V0, V1) + inflation, np.inf))
    E = np.asarray(contact.mesh.edges, dtype=np.int64)
    F = np.asarray(contact.mesh.faces, dtype=np.int64)
    group = np.asarray(contact.group, dtype=np.int64)
    enabled = np.ascontiguousarray(contact.table.enabled, dtype=np.bool_)
    points = np.arange(len(V0), dtype=np.int64)[:, None]

    def boxes(ids):
        return primitive_boxes(lo, hi, ids)

    parts = []
    if V0.shape[1] == 3:
        lo_f, hi_f = boxes(F)
        fv = _pairs(kernel, lo, hi, lo_f, hi_f, False, points, F, group, enabled)
        if len(fv):
            parts.append((0, np.column_stack([fv[:, 0], F[fv[:, 1]]])))
        lo_e, hi_e = boxes(E)
        ee = _pairs(kernel, lo_e, hi_e, lo_e, hi_e, True, E, E, group, enabled)
        if len(ee):
            parts.append((1, np.column_stack([E[ee[:, 0]], E[ee[:, 1]]])))
    else:
        lo_e, hi_e = boxes(E)
        ev = _pairs(kernel, lo, hi, lo_e, hi_e, False, points, E, group, enabled)
        if len(ev):
            parts.append((2, np.column_stack([ev[:, 0], E[ev[:, 1]], np.full(len(ev), -1)])))
    return parts
