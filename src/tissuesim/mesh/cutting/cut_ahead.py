"""A cut made ahead of a blade that is in contact with the body it cuts: every cell the blade
will touch in the coming step is cut before the step, so the blade only ever moves in the
cut's kerf and never presses into tissue it has not cut.

The virtual node algorithm cuts whole cells. A blade cut after each step cuts the cells it has
swept through completely (the cut trails the blade's edge by at most one cell, and the blade
passes through the cells it is inside: it cannot be in contact with that body). A blade in
contact is ahead of that: before the step, the blade's positions over the step are known (a
prescribed motion, or a live drive's target), and each cell whose section of the cut's surface
comes within ``margin`` of what the blade will have swept by the step's end, carried on along
its motion by one more step's travel (at most a cell's edge: tissue moves while the step is
solved, and what meets the edge must have been cut, not pushed), or that holds a point of the
blade, is cut along that surface. The cut then leads the blade by at most that lead and one
cell, and its faces, each ``dhat`` inside its side (``contact/cut/surface.py``), leave the blade
a kerf to move in.
"""

from __future__ import annotations

import numpy as np

from tissuesim.mesh.cutting.planar_cut import PLANE_TOLERANCE, PlanarCut
from tissuesim.mesh.cutting.swept_cut import SweptCut

__all__ = ["LEAD_CELLS", "MARGIN", "cut_ahead", "lead", "touched_cells"]

#: a cell within this many dhat of the blade counts as touched (its barrier would act)
MARGIN = 2.0
#: the blade is carried on by its travel in a step, at most this many median cell edges
LEAD_CELLS = 1.0

#: points sampled along each blade edge, per smallest cell size (the edge's cells it crosses)
EDGE_SAMPLES_PER_CELL = 2.0
#: at most this many points along one blade edge
MAX_EDGE_SAMPLES = 512


def cut_ahead(
    swept: PlanarCut | SweptCut,
    x_cell: np.ndarray,
    blades: list[np.ndarray],
    margin: float,
    following: np.ndarray | None = None,
) -> PlanarCut | SweptCut:
    """The cut to make before a step: ``swept`` (what the blade will have swept by the step's
    end) grown over the sections of the cells (x_cell (m, k, 3), where their vertices are now)
    it touches (``touched_cells``) given the blade's positions ``blades`` over the step (each
    (2, 3) or (3, 3)) and ``margin`` (m), the blade carried on by one more step's travel
    along its motion (``lead``; ``following``: where the blade will be a step later, when its
    motion is known)."""
    swept, blades = lead(swept, x_cell, blades, following)
    hit, points, valid, d = touched_cells(swept, x_cell, blades, margin)
    if not hit.any():
        return swept
    if isinstance(swept, PlanarCut):
        extra = points[hit][valid[hit]]
        grown = PlanarCut.hull(np.concatenate([swept.polygon, extra]), swept.point, swept.normal)
        return swept if grown is None else grown
    more = _section_fans(points[hit], valid[hit], swept)
    return SweptCut(np.concatenate([swept.triangles, more])) if len(more) else swept


def _section_fans(points: np.ndarray, valid: np.ndarray, swept: SweptCut) -> np.ndarray:
    """Each cell's section (its valid ``points`` (m, P, 3)) as a fan of triangles about its
    centroid, ordered by angle in the plane of the swept triangle nearest to it and facing
    that triangle's side. Returns (t, 3, 3)."""
    count = valid.sum(axis=1)
    centre = (points * valid[..., None]).sum(axis=1) / np.maximum(count, 1)[:, None]
    normal = swept.normals[swept._nearest(centre)[0]]
    first = np.take_along_axis(points, np.argmax(valid, axis=1)[:, None, None], axis=1)[:, 0]
    u = first - centre
    w = np.cross(normal, u)
    rel = points - centre[:, None]
    angle = np.arctan2((rel * w[:, None]).sum(-1), (rel * u[:, None]).sum(-1))
    order = np.argsort(np.where(valid, angle, np.inf), axis=1)  # the valid points first
    ring = np.take_along_axis(points, order[..., None], axis=1)
    nxt = np.roll(np.arange(ring.shape[1]), -1)
    j = np.arange(ring.shape[1])
    # the edge from sorted point j to the next valid one (the last wraps to the first)
    after = np.where(j[None, :] + 1 < count[:, None], nxt[None, :], 0)
    b = np.take_along_axis(ring, after[..., None], axis=1)
    keep = (j[None, :] < count[:, None]) & (count[:, None] >= 3)
    tris = np.stack([np.broadcast_to(centre[:, None], ring.shape), ring, b], axis=2)[keep]
    flip = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    flip = (flip * np.repeat(normal, keep.sum(axis=1), axis=0)).sum(-1) < 0.0
    tris[flip] = tris[flip][:, [0, 2, 1]]
    return tris


def lead(
    swept: PlanarCut | SweptCut,
    x_cell: np.ndarray,
    blades: list[np.ndarray],
    following: np.ndarray | None = None,
) -> tuple[PlanarCut | SweptCut, list[np.ndarray]]:
    """``swept`` and ``blades`` with the blade carried on past the step's end by its travel in
    the next step, at most LEAD_CELLS of the cells' median edge: tissue moves while the step is
    solved, and what comes towards the blade's edge within that lead is cut already rather than
    pushed (a drooping lobe dragged its last bridge off the blade's plane with a lead of
    2 dhat). The lead is along the blade's motion only: no cell beside its path is cut. The
    next step's travel is the blade's move to ``following`` (where it will be a step later,
    when its motion is prescribed: a blade that stops leads by nothing), else its travel in
    this step (a live drive's next target is not known yet)."""
    first, last = blades[0], blades[-1]
    move = last - first if following is None else np.asarray(following, dtype=float) - last
    travel = float(np.linalg.norm(move, axis=1).max())
    if travel == 0.0 or not len(x_cell):
        return swept, blades
    edge = float(np.median(np.linalg.norm(x_cell[:, 1] - x_cell[:, 0], axis=1)))
    ahead = last + move * min(1.0, LEAD_CELLS * edge / travel)
    if isinstance(swept, PlanarCut):
        ahead = ahead - np.outer((ahead - swept.point) @ swept.normal, swept.normal)  # in plane
        grown = PlanarCut.hull(np.concatenate([swept.polygon, ahead]), swept.point, swept.normal)
        swept = swept if grown is None else grown
    else:
        more = SweptCut.from_blades([last, ahead]).triangles
        swept = SweptCut(np.concatenate([swept.triangles, more]))
    return swept, [*blades, ahead]


def touched_cells(
    swept: PlanarCut | SweptCut, x_cell: np.ndarray, blades: list[np.ndarray], margin: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Which cells (x_cell (m, k, 3)) the blade touches: those the cut's surface crosses whose
    section has a point within ``margin`` of the swept area (over it, along the surface), or
    that hold a point of the blade (its corners and points along its edges at every position
    in ``blades``) within ``margin``. Returns (touched (m,), the sections' points (m, P, 3),
    which of them are points (m, P), the vertex distances (m, k))."""
    d = swept.distances(x_cell)
    e = x_cell - x_cell[:, :1]
    size = np.sqrt((e * e).sum(axis=2).max(axis=1))
    d[np.abs(d) <= PLANE_TOLERANCE * size[:, None]] = 0.0
    m, k = d.shape
    crossed = (d.max(axis=1) > 0.0) & (d.min(axis=1) < 0.0)
    i, j = np.triu_indices(k, 1)
    di, dj = d[:, i], d[:, j]
    crosses = (di * dj < 0.0) & crossed[:, None]
    t = np.where(crosses, di / np.where(crosses, di - dj, 1.0), 0.0)
    points = np.concatenate(
        [x_cell, x_cell[:, i] + t[..., None] * (x_cell[:, j] - x_cell[:, i])], 1
    )
    valid = np.concatenate([(d == 0.0) & crossed[:, None], crosses], axis=1)
    reach = np.full(valid.shape, np.inf)
    reach[valid] = swept.reach(points[valid])
    hit = crossed & np.any(reach <= margin, axis=1)
    # only a cell the surface crosses counts: the others are not searched (0.03 s a step
    # over the whole organ of liver_instrument, a seventh of its run)
    c = np.flatnonzero(crossed)
    hit[c] |= _holding(x_cell[c], size[c], _blade_points(blades, size), margin)
    return hit, points, valid, d


def _blade_points(blades: list[np.ndarray], size: np.ndarray) -> np.ndarray:
    """The blade's corners and points along its edges (spaced by half the smallest cell),
    at every sampled position."""
    h = float(size[size > 0].min(initial=np.inf))
    pts = []
    for blade in blades:
        edges = ((0, 1),) if len(blade) == 2 else ((0, 1), (1, 2), (2, 0))
        for a, b in edges:
            length = float(np.linalg.norm(blade[b] - blade[a]))
            n = EDGE_SAMPLES_PER_CELL * length / h if np.isfinite(h) else 1.0
            n = int(np.clip(np.ceil(n), 1, MAX_EDGE_SAMPLES))
            s = np.linspace(0.0, 1.0, n + 1)[:, None]
            pts.append(blade[a] + s * (blade[b] - blade[a]))
    return np.concatenate(pts) if pts else np.zeros((0, 3))


def _holding(x_cell: np.ndarray, size: np.ndarray, points: np.ndarray, margin: float) -> np.ndarray:
    """Whether each tetrahedron (x_cell (m, 4, 3)) holds one of ``points`` within ``margin``
    (its barycentric coordinates all above -margin / its size). Returns (m,)."""
    from scipy.spatial import cKDTree

    m = len(x_cell)
    held = np.zeros(m, dtype=bool)
    if not len(points) or not m or x_cell.shape[1] != 4:
        return held
    centre = x_cell.mean(axis=1)
    radius = float(np.linalg.norm(x_cell - centre[:, None], axis=2).max()) + margin
    pairs = cKDTree(centre).query_ball_point(points, radius)
    cell = np.concatenate([np.asarray(p, dtype=np.int64) for p in pairs])
    point = np.repeat(np.arange(len(points)), [len(p) for p in pairs])
    if not len(cell):
        return held
    X = x_cell[cell]
    # barycentric coordinates by Cramer's rule on the edges from vertex 0 (a batched LAPACK
    # solve of 3 x 3 systems cost 5x more)
    e1, e2, e3 = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]
    r = points[point] - X[:, 0]
    c23 = np.cross(e2, e3)
    det = np.einsum("ij,ij->i", e1, c23)
    ok = np.abs(det) > 1e-300
    safe = np.where(ok, det, 1.0)[:, None]
    lam = (
        np.column_stack(
            [
                np.einsum("ij,ij->i", r, c23),
                np.einsum("ij,ij->i", e1, np.cross(r, e3)),
                np.einsum("ij,ij->i", e1, np.cross(e2, r)),
            ]
        )
        / safe
    )
    bary = np.column_stack([1.0 - lam.sum(axis=1), lam])
    inside = ok & np.all(bary >= -margin / np.maximum(size[cell], 1e-300)[:, None], axis=1)
    held[cell[inside]] = True
    return held
