"""Frame weights w_i(p) and their gradients at sample points (Gilles et al., TOG 2011).

A frame-based model moves each sample point p (integration point or embedded display point) by a
blend of frame transforms, weighted by w_i(p). The weights must form a partition of unity
(sum_i w_i = 1) so that a rigid motion of all frames moves every point rigidly, and their spatial
gradients enter the deformation gradient F, so they are computed analytically.

Two kernels phi_i, both normalised in the Shepard way, w_i = phi_i / S with S = sum_j phi_j:

* ``"wendland"`` (default): phi_i(p) = psi(|p - xbar_i| / r_i) with the Wendland C2 function
  psi(s) = (1 - s)^4 (4 s + 1) for s < 1, else 0. Compactly supported, so each point only sees
  the few frames whose support radius r_i reaches it, and the rows are short.
* ``"shepard"``: phi_i(p) = 1 / (|p - xbar_i|^2 + eps^2), global inverse distance; every frame
  enters every row. eps is 1e-3 of the median frame spacing and keeps phi finite and smooth at a
  frame.

With grad S = sum_j grad phi_j the gradient is grad w_i = grad phi_i / S - phi_i grad S / S^2.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
from scipy.spatial import cKDTree

from tissuesim.errors import InputError
from tissuesim.validate import short

__all__ = ["ShapeKind", "ShapeFunctions", "PairFilter", "auto_radii", "shape_functions"]

ShapeKind = Literal["wendland", "shepard"]
#: keep_pair(point indices (m,), frame indices (m,)) -> (m,) bool: False drops the pair before
#: normalisation (a cut: the frame no longer acts on that point).
PairFilter = Callable[[np.ndarray, np.ndarray], np.ndarray]
_KINDS: tuple[str, ...] = get_args(ShapeKind)

# relative to the frames' bounding-box diagonal: closer frames count as one place
_DUPLICATE_TOL = 1e-12
# eps of the "shepard" kernel, relative to the median frame spacing
_SHEPARD_EPS = 1e-3


@dataclass(frozen=True, eq=False)
class ShapeFunctions:
    """Weights of the frames at sample points, padded to a fixed width k.

    frames:    (q, k) int64 frame indices; real entries first (sorted by frame index), padding
               entries repeat the row's first frame index so that gathers stay in range.
    weights:   (q, k) float64 w_i(p); 0 in padding. Each row sums to 1.
    gradients: (q, k, d) float64 dw_i/dp with respect to the rest position p; 0 in padding.
    count:     (q,) int64 number of real entries per row.
    radii:     (n_frames,) support radii used (np.inf for "shepard").
    kind:      the kernel, "wendland" or "shepard".
    """

    frames: np.ndarray
    weights: np.ndarray
    gradients: np.ndarray
    count: np.ndarray
    radii: np.ndarray
    kind: str

    @property
    def width(self) -> int:
        """Padded row width k (the largest number of frames reaching one point)."""
        return int(self.frames.shape[1])


def _fmt_point(x: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.4g}" for v in x) + ")"


def _as_coordinates(values, name: str, noun: str) -> np.ndarray:
    """(m, d) float64 with d in (2, 3) and finite entries; ``noun`` names a row in messages."""
    try:
        a = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be an (m, d) array of numbers: {exc}") from exc
    if a.ndim != 2 or a.shape[1] not in (2, 3):
        raise InputError(
            f"{name} has shape {a.shape}; expected a 2-D array (m, 2) or (m, 3) of coordinates"
        )
    bad = ~np.all(np.isfinite(a), axis=1)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise InputError(
            f"{noun} {i} has non-finite coordinates {_fmt_point(a[i])} "
            f"({int(bad.sum())} row(s) of {name} in total); give finite coordinates"
        )
    return a


def _check_same_width(frames: np.ndarray, other: np.ndarray, name: str) -> None:
    if other.shape[1] != frames.shape[1]:
        raise InputError(
            f"{name} are {other.shape[1]}-D but frame_positions are {frames.shape[1]}-D; "
            "give both with the same number of coordinates per row"
        )


def _nearest_other_frame(frames: np.ndarray) -> np.ndarray:
    """Distance (n,) from each frame to its nearest other frame; raises on duplicate frames."""
    n = frames.shape[0]
    if n < 2:
        return np.full(n, np.inf)
    dist, idx = cKDTree(frames).query(frames, k=2)
    # with coincident frames the query may list frame i second, so take the entry that is not i
    own = np.arange(n)
    other = np.where(idx[:, 0] == own, idx[:, 1], idx[:, 0])
    near = np.where(idx[:, 0] == own, dist[:, 1], dist[:, 0])
    diag = float(np.linalg.norm(frames.max(axis=0) - frames.min(axis=0)))
    dup = near <= _DUPLICATE_TOL * (diag if diag > 0 else 1.0)
    if np.any(dup):
        i = int(np.flatnonzero(dup)[0])
        a, b = sorted((i, int(other[i])))
        raise InputError(
            f"frames {a} and {b} are at the same place {_fmt_point(frames[a])} "
            f"({int(dup.sum())} frame(s) coincide with another); remove or move one of them"
        )
    return near


def _validate_frames(frame_positions) -> tuple[np.ndarray, np.ndarray]:
    frames = _as_coordinates(frame_positions, "frame_positions", "frame")
    if frames.shape[0] == 0:
        raise InputError("no frames: frame_positions is empty; give at least one frame position")
    return frames, _nearest_other_frame(frames)


def _auto_radii(
    frames: np.ndarray, near_frame: np.ndarray, samples: np.ndarray, factor: float
) -> np.ndarray:
    factor = float(factor)
    if not np.isfinite(factor) or factor <= 1.0:
        raise InputError(
            f"radius factor (radius_factor=) is {factor}; it must be a finite number > 1 so that "
            "every sample lies strictly inside the support of its nearest frame (default 1.5)"
        )
    n = frames.shape[0]
    reach = np.zeros(n)
    if samples.shape[0] > 0:
        dist, idx = cKDTree(frames).query(samples)
        np.maximum.at(reach, idx, dist)
    if n == 1:
        return np.array([factor * reach[0] if reach[0] > 0 else 1.0])
    return factor * np.maximum(near_frame, reach)


def auto_radii(frame_positions: np.ndarray, samples: np.ndarray, factor: float = 1.5) -> np.ndarray:
    """Support radii (n_frames,) that let every sample be reached by at least its nearest frame.

    r_i = factor * max(distance from frame i to its nearest other frame, largest distance from
    frame i to the samples whose nearest frame is i). The first term makes neighbouring supports
    overlap (smooth blending between frames), the second covers every sample (factor > 1 keeps it
    strictly inside). One frame alone: factor * largest distance to any sample, or 1.0 if that
    is 0.
    """
    frames, near = _validate_frames(frame_positions)
    pts = _as_coordinates(samples, "samples", "sample")
    _check_same_width(frames, pts, "samples")
    return _auto_radii(frames, near, pts, factor)


def _radii(radius, n: int) -> np.ndarray:
    try:
        r = np.array(radius, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"radius must be None, a positive number or an array of {n} positive numbers: {exc}"
        ) from exc
    if r.ndim == 0:
        r = np.full(n, float(r))
    elif r.shape != (n,):
        raise InputError(
            f"radius has shape {r.shape}; give a positive scalar for all frames, an array of "
            f"shape ({n},) with one radius per frame, or None for automatic radii"
        )
    bad = ~(np.isfinite(r) & (r > 0))
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise InputError(
            f"support radius of frame {i} is {r[i]}; radii must be finite and > 0 "
            f"({int(bad.sum())} bad radius value(s)); give positive radii or radius=None"
        )
    return r


def _normalise(
    phi: np.ndarray, gphi: np.ndarray, S: np.ndarray, gS: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Shepard normalisation of kernel values and their gradients (S, gS broadcast to phi)."""
    w = phi / S
    g = (gphi - w[..., None] * gS) / S[..., None]
    return w, g


def _wendland(
    frames: np.ndarray, points: np.ndarray, radii: np.ndarray, keep_pair: PairFilter | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pairs (point, frame, w, grad w) with phi > 0, grouped by point and sorted by frame."""
    q, d = points.shape
    n = frames.shape[0]
    if q == 0:
        return (np.zeros(0, np.int64),) * 2 + (np.zeros(0), np.zeros((0, d)))
    # candidates by ball query (one list per frame; slightly enlarged so rounding in the tree
    # loses nothing), then kept exactly where s = |p - xbar| / r < 1, i.e. phi > 0
    lists = cKDTree(points).query_ball_point(frames, r=radii * (1.0 + 1e-9))
    lengths = np.fromiter((len(v) for v in lists), dtype=np.int64, count=n)
    pt = np.concatenate([np.asarray(v, dtype=np.int64) for v in lists])
    fr = np.repeat(np.arange(n, dtype=np.int64), lengths)
    diff = points[pt] - frames[fr]
    r = radii[fr]
    s = np.sqrt(np.einsum("mi,mi->m", diff, diff)) / r
    keep = s < 1.0
    if keep_pair is not None:
        keep &= np.asarray(keep_pair(pt, fr), dtype=bool)
    pt, fr, diff, r, s = pt[keep], fr[keep], diff[keep], r[keep], s[keep]
    order = np.lexsort((fr, pt))
    pt, fr, diff, r, s = pt[order], fr[order], diff[order], r[order], s[order]

    t = 1.0 - s
    t3 = t**3
    phi = t3 * t * (4.0 * s + 1.0)
    gphi = (-20.0 * t3 / r**2)[:, None] * diff  # psi'(s) ds/dp, with no 1/|p - xbar| singularity
    S = np.bincount(pt, weights=phi, minlength=q)
    gS = np.stack([np.bincount(pt, weights=gphi[:, c], minlength=q) for c in range(d)], axis=1)
    # rows nobody reaches have S = 0; they never reach the division below (min_frames >= 1)
    w, g = _normalise(phi, gphi, S[pt], gS[pt])
    return pt, fr, w, g


def _report_unreached(
    frames: np.ndarray,
    points: np.ndarray,
    radii: np.ndarray,
    count: np.ndarray,
    min_frames: int,
    what: str,
) -> None:
    bad = count < min_frames
    if not np.any(bad):
        return
    i = int(np.flatnonzero(bad)[0])
    p = points[i]
    dist = np.sqrt(np.einsum("ni,ni->n", frames - p, frames - p))
    outside = dist / radii >= 1.0
    if not np.any(outside):  # only by rounding; fall back to all frames
        outside[:] = True
    j = int(np.flatnonzero(outside)[np.argmin(dist[outside])])
    nearest = "the nearest frame" if count[i] == 0 else "the nearest frame that does not reach it"
    total = int(bad.sum())
    raise InputError(
        f"{what} {i} at {_fmt_point(p)} is reached by {int(count[i])} frame(s), at least "
        f"{min_frames} needed; {nearest} is {j} at distance {dist[j]:.4g} with support radius "
        f"{radii[j]:.4g}. Increase the support radius (radius= or radius_factor=) or add a "
        f"frame near this point. "
        f"({total} of {points.shape[0]} {what}s are reached by fewer than {min_frames} frame(s).)"
    )


def shape_functions(
    frame_positions: np.ndarray,
    points: np.ndarray,
    *,
    kind: ShapeKind = "wendland",
    radius: float | np.ndarray | None = None,
    radius_factor: float = 1.5,
    min_frames: int = 1,
    what: str = "integration point",
    radii_from: np.ndarray | None = None,
    keep_pair: PairFilter | None = None,
) -> ShapeFunctions:
    """Frame weights and their rest-space gradients at ``points`` (q, d), frames at (n, d).

    radius ("wendland" only): None for automatic radii, auto_radii(frame_positions, radii_from
    if given else points, radius_factor), so that one set of radii can serve both integration
    and display points; a positive scalar for all frames; or (n_frames,) per frame.
    min_frames: every point must be reached by at least this many frames (a point reached by
    fewer has a degenerate or too rigid blend), else ValueError naming the first such point.
    what: the noun for a point in error messages.
    keep_pair: drops (point, frame) pairs before the Shepard normalisation, so the remaining
    weights still sum to 1 (used by cutting: no frame acts across a cut).
    """
    if kind not in _KINDS:
        raise InputError(
            f"unknown shape function kind {short(kind)}; known kinds: "
            f"{', '.join(map(repr, _KINDS))}"
        )
    if isinstance(min_frames, bool) or not isinstance(min_frames, int | np.integer):
        raise InputError(f"min_frames must be an integer >= 1, got {short(min_frames)}")
    min_frames = int(min_frames)
    if min_frames < 1:
        raise InputError(f"min_frames is {min_frames}; it must be >= 1 (frames per point)")
    frames, near = _validate_frames(frame_positions)
    pts = _as_coordinates(points, "points", what)
    _check_same_width(frames, pts, "points")
    n = frames.shape[0]
    q, d = pts.shape
    if min_frames > n:
        raise InputError(
            f"min_frames is {min_frames} but there are only {n} frame(s); "
            f"add frames or lower min_frames to at most {n}"
        )

    if kind == "shepard":
        if radius is not None:
            raise InputError(
                "radius= applies to the compactly supported 'wendland' kernel only; 'shepard' "
                "is global (every frame reaches every point): drop radius= or use kind='wendland'"
            )
        if n > 1:
            eps = _SHEPARD_EPS * float(np.median(near))
        else:
            diag = float(np.linalg.norm(np.ptp(pts, axis=0))) if q else 0.0
            eps = _SHEPARD_EPS * (diag if diag > 0 else 1.0)
        diff = pts[:, None, :] - frames[None, :, :]  # (q, n, d)
        phi = 1.0 / (np.einsum("qni,qni->qn", diff, diff) + eps * eps)
        gphi = -2.0 * (phi * phi)[..., None] * diff
        count = np.full(q, n, dtype=np.int64)
        if keep_pair is not None:
            pq, pf = (a.ravel() for a in np.meshgrid(np.arange(q), np.arange(n), indexing="ij"))
            kept = np.asarray(keep_pair(pq, pf), dtype=bool).reshape(q, n)
            phi, gphi, count = phi * kept, gphi * kept[..., None], kept.sum(axis=1)
            _report_unreached(frames, pts, np.full(n, np.inf), count, min_frames, what)
        w, g = _normalise(phi, gphi, phi.sum(axis=1)[:, None], gphi.sum(axis=1)[:, None, :])
        return ShapeFunctions(
            frames=np.broadcast_to(np.arange(n, dtype=np.int64), (q, n)).copy(),
            weights=w,
            gradients=g,
            count=count,
            radii=np.full(n, np.inf),
            kind=kind,
        )

    if radius is None:
        if radii_from is None:
            samples = pts
        else:
            samples = _as_coordinates(radii_from, "radii_from", "radii_from sample")
            _check_same_width(frames, samples, "radii_from samples")
        radii = _auto_radii(frames, near, samples, radius_factor)
    else:
        radii = _radii(radius, n)

    pt, fr, w, g = _wendland(frames, pts, radii, keep_pair)
    count = np.bincount(pt, minlength=q).astype(np.int64)
    _report_unreached(frames, pts, radii, count, min_frames, what)

    k = int(count.max()) if q else 0
    start = np.concatenate(([0], np.cumsum(count)[:-1])) if q else np.zeros(0, np.int64)
    col = np.arange(pt.shape[0]) - start[pt]
    out_frames = np.repeat(fr[start][:, None], k, axis=1) if q else np.zeros((0, 0), np.int64)
    out_frames[pt, col] = fr
    weights = np.zeros((q, k))
    weights[pt, col] = w
    gradients = np.zeros((q, k, d))
    gradients[pt, col] = g
    return ShapeFunctions(
        frames=out_frames,
        weights=weights,
        gradients=gradients,
        count=count,
        radii=radii,
        kind=kind,
    )
