"""Dissection and tearing of the connective tissue: what a cut removes and what it severs.

Choices (docs/coupling.md):

* **A cut is a surface swept by the tool's blade** (a polyline at each time, ``CutTool``); each
  step between t_n and t_{n+1} adds the triangles between the two blade positions, in world
  coordinates.
* **The cut lives in the rest configuration.** The swept triangles (blade resampled finer than
  the tissue's spacing, in space and in time) are mapped back to rest coordinates through the
  tissue's deformation at the end of the step: each vertex w goes to X_s + F_s^-1 (w - p_s) with
  s the nearest integration point (first-order inverse). Shape functions live in the rest
  configuration, so the cut is permanent: it moves with the material afterwards.
* **Visibility criterion.** A frame stops acting on a point (integration or attachment point)
  when the rest segment between the frame's origin and the point crosses a rest cut triangle.
  Every pair within reach is tested against every new triangle once, so points that later
  move across an earlier part of the cut stay severed. Weights are renormalised over the frames
  that still see a point (Shepard), so they remain a partition of unity.
* **Kerf.** Points and frame origins closer than kerf / 2 to the swept triangles are removed:
  the blade destroys a thin layer of material.
* **Consolidation.** After a cut or a tear, a point that no frame sees is removed, and a frame
  that sees fewer than ``MIN_POINTS_PER_FRAME`` points is retired (all its pairs severed): it
  would have too little mass and stiffness to be determined. Repeated until nothing changes.
  Retired frames keep their place in the state vector and are held still (``FrameModel``
  orphans). Attachment points left without frames stop coupling.
* **Tearing**: integration points whose largest principal Green strain exceeds a threshold are
  removed (then consolidation).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from tissuesim.coupling.geometry import (
    point_triangle_distance,
    segments_hit_triangles,
    swept_blade_triangles,
)
from tissuesim.errors import InputError
from tissuesim.frames.shape_functions import shape_functions

__all__ = ["CutTool", "Dissection", "MIN_POINTS_PER_FRAME", "sweep_triangles"]

MIN_POINTS_PER_FRAME = 4


@dataclass(frozen=True, eq=False)
class CutTool:
    """A blade: ``blade(t)`` -> (k, 3) polyline in world coordinates (m), active for
    start <= t <= end. kerf: width of material the blade removes (m)."""

    blade: Callable[[float], np.ndarray]
    start: float
    end: float
    kerf: float
    name: str = "cut"

    def positions(self, t: float) -> np.ndarray:
        b = np.asarray(self.blade(t), dtype=float)
        if b.ndim != 2 or b.shape[1] != 3 or b.shape[0] < 2 or not np.all(np.isfinite(b)):
            raise InputError(
                f"cut {self.name!r}: blade({t:g}) must give a finite (k, 3) polyline with k >= 2 "
                f"points, got shape {b.shape}"
            )
        return b

    def blades(
        self, t0: float, t1: float, resolution: float, count: int | None = None
    ) -> np.ndarray | None:
        """Blade positions (n_times, k, 3) sweeping between t0 and t1 (clipped to
        [start, end]), or None when the tool is idle.

        Each blade is resampled to ``count`` points (default: edges <= ``resolution``) and the
        sweep is split in time so that no point travels farther than ``resolution`` per piece:
        the swept triangles are then small enough to follow the tissue's deformation when they
        are mapped to rest coordinates."""
        a, b = max(t0, self.start), min(t1, self.end)
        if b <= a:
            return None
        if count is None:
            count = len(_resample(self.positions(a), resolution))
        times = np.array([a, b])
        while True:
            blades = np.stack([_resample(self.positions(t), resolution, count) for t in times])
            travel = np.abs(np.diff(blades, axis=0)).max()
            if travel <= resolution or len(times) > 256:
                return blades
            times = np.linspace(a, b, 2 * len(times) - 1)


def sweep_triangles(blades: np.ndarray) -> np.ndarray:
    """Triangles (m, 3, 3) between consecutive blades (n, k, 3)."""
    return np.concatenate(
        [swept_blade_triangles(p, q) for p, q in zip(blades[:-1], blades[1:], strict=True)]
    )


def _resample(polyline: np.ndarray, resolution: float, count: int | None = None) -> np.ndarray:
    """The polyline with points evenly spaced along its length, edges <= resolution (or
    ``count`` points)."""
    seg = np.linalg.norm(np.diff(polyline, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = count or max(2, int(np.ceil(s[-1] / resolution)) + 1)
    u = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(u, s, polyline[:, i]) for i in range(3)])


@dataclass(eq=False)
class Dissection:
    """Which tissue points are alive and which (point, frame) pairs are severed.

    Points are identified by stable ids: integration points by their index in the original
    samples, attachment points by their index in the original attachment set of their organ.
    """

    n_frames: int
    n_points: int
    attachment_counts: list[int]
    alive: np.ndarray = field(init=False)
    attachment_alive: list[np.ndarray] = field(init=False)
    frame_alive: np.ndarray = field(init=False)
    severed: np.ndarray = field(init=False)  # keys point_id * n_frames + frame
    attachment_severed: list[np.ndarray] = field(init=False)
    cut_triangles: list[np.ndarray] = field(default_factory=list)
    events: list[dict] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.alive = np.ones(self.n_points, dtype=bool)
        self.attachment_alive = [np.ones(n, dtype=bool) for n in self.attachment_counts]
        self.frame_alive = np.ones(self.n_frames, dtype=bool)
        self.severed = np.zeros(0, dtype=np.int64)
        self.attachment_severed = [np.zeros(0, dtype=np.int64) for _ in self.attachment_counts]

    # -- filters -----------------------------------------------------------------------------
    def keep_pair(self, ids: np.ndarray, severed: np.ndarray):
        """keep_pair(point rows, frames) for points whose stable ids are ``ids``."""

        def keep(pt: np.ndarray, fr: np.ndarray) -> np.ndarray:
            key = ids[pt] * self.n_frames + fr
            return self.frame_alive[fr] & ~np.isin(key, severed)

        return keep

    def point_filter(self):
        return self.keep_pair(np.flatnonzero(self.alive), self.severed)

    def attachment_filter(self, organ_slot: int):
        ids = np.flatnonzero(self.attachment_alive[organ_slot])
        return self.keep_pair(ids, self.attachment_severed[organ_slot])

    # -- topology changes --------------------------------------------------------------------
    def cut(
        self,
        triangles: np.ndarray,
        kerf: float,
        frame_positions: np.ndarray,
        points: np.ndarray,
        attachment_points: list[np.ndarray],
        radii: np.ndarray,
    ) -> dict:
        """Apply one swept cut given in rest coordinates (``triangles`` (m, 3, 3)); all
        positions are rest ones (every original point, alive or not). Every (point, frame)
        pair within the frame's support whose rest segment crosses the triangles is severed,
        for good: later cuts only add triangles, so the cut surface is permanent."""
        half = 0.5 * kerf
        report = {"removed_points": 0, "severed_pairs": 0, "retired_frames": 0}
        near = point_triangle_distance(frame_positions, triangles) < half
        report["retired_frames"] = int(np.sum(near & self.frame_alive))
        self.frame_alive &= ~near

        # only what reaches the cut's bounding box can touch it: test those alone
        lo = triangles.reshape(-1, 3).min(axis=0) - half
        hi = triangles.reshape(-1, 3).max(axis=0) + half

        def apply(alive: np.ndarray, severed: np.ndarray, pts: np.ndarray):
            ids = np.flatnonzero(alive)
            gone = np.zeros(len(ids), dtype=bool)
            near = np.all((pts[ids] >= lo) & (pts[ids] <= hi), axis=1)
            if near.any():
                gone[near] = point_triangle_distance(pts[ids][near], triangles) < half
            alive[ids[gone]] = False
            ids = np.flatnonzero(alive)
            pt, fr = _candidates(frame_positions, pts[ids], radii)
            a, b = pts[ids][pt], frame_positions[fr]
            boxed = np.all((np.minimum(a, b) <= hi) & (np.maximum(a, b) >= lo), axis=1)
            hit = np.zeros(len(pt), dtype=bool)
            if boxed.any():
                hit[boxed] = segments_hit_triangles(a[boxed], b[boxed], triangles)
            new = ids[pt[hit]] * self.n_frames + fr[hit]
            fresh = np.setdiff1d(new, severed)
            return np.union1d(severed, fresh), int(np.sum(gone)), int(fresh.size)

        self.severed, removed, severed = apply(self.alive, self.severed, points)
        report["removed_points"] += removed
        report["severed_pairs"] += severed
        report["removed_attachments"] = 0
        for j, pts in enumerate(attachment_points):
            self.attachment_severed[j], removed, severed = apply(
                self.attachment_alive[j], self.attachment_severed[j], pts
            )
            report["removed_attachments"] += removed
            report["severed_pairs"] += severed
        self.cut_triangles.append(np.asarray(triangles, dtype=float))
        return report

    def tear(self, point_ids: np.ndarray) -> dict:
        self.alive[point_ids] = False
        return {"torn_points": int(len(point_ids))}

    def consolidate(
        self,
        frame_positions: np.ndarray,
        points: np.ndarray,
        attachment_points: list[np.ndarray],
        radii: np.ndarray,
        kind: str,
    ) -> dict:
        """Remove unseen points and retire under-used frames until stable (rest positions:
        the shape functions live in the rest configuration)."""
        removed_points = retired = 0
        while True:
            ids = np.flatnonzero(self.alive)
            pt, fr = _pairs(frame_positions, points[ids], radii, kind, self.point_filter())
            seen = np.bincount(pt, minlength=len(ids))
            blind = ids[seen == 0]
            per_frame = np.bincount(fr, minlength=self.n_frames)
            weak = self.frame_alive & (per_frame < MIN_POINTS_PER_FRAME)
            if not len(blind) and not weak.any():
                break
            self.alive[blind] = False
            self.frame_alive &= ~weak
            removed_points += len(blind)
            retired += int(weak.sum())
        removed_attachments = 0
        for j, pts in enumerate(attachment_points):
            ids = np.flatnonzero(self.attachment_alive[j])
            pt, _ = _pairs(frame_positions, pts[ids], radii, kind, self.attachment_filter(j))
            blind = ids[np.bincount(pt, minlength=len(ids)) == 0]
            self.attachment_alive[j][blind] = False
            removed_attachments += len(blind)
        return {
            "blind_points_removed": removed_points,
            "frames_retired": retired,
            "attachments_removed": removed_attachments,
        }


def _candidates(frames: np.ndarray, points: np.ndarray, radii: np.ndarray):
    """(point row, frame) pairs within the frames' support radii (all pairs for infinite
    radii, i.e. the global "shepard" kernel)."""
    if not len(points):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    if not np.all(np.isfinite(radii)):
        pt, fr = np.meshgrid(np.arange(len(points)), np.arange(len(frames)), indexing="ij")
        return pt.ravel(), fr.ravel()
    lists = cKDTree(points).query_ball_point(frames, r=radii)
    lengths = np.fromiter((len(v) for v in lists), dtype=np.int64, count=len(frames))
    pt = np.concatenate([np.asarray(v, dtype=np.int64) for v in lists])
    return pt, np.repeat(np.arange(len(frames), dtype=np.int64), lengths)


def _pairs(frames, points, radii, kind, keep) -> tuple[np.ndarray, np.ndarray]:
    """(row, frame) pairs with a non-zero weight after the filter; rows without any frame
    are simply absent."""
    if not len(points):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    radius = None if kind == "shepard" else radii
    sf = shape_functions(frames, points, kind=kind, radius=radius, min_frames=1)
    rows = np.repeat(np.arange(len(points)), sf.width).reshape(sf.frames.shape)
    real = sf.weights > 0
    pt, fr = rows[real], sf.frames[real]
    kept = np.asarray(keep(pt, fr), dtype=bool)
    return pt[kept], fr[kept]
