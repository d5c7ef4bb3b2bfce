"""Where to put frames: a regular grid, or farthest-point sampling of the body's points."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from tissuesim.errors import InputError
from tissuesim.validate import check_memory

__all__ = ["grid_frames", "farthest_point_frames"]


def grid_frames(
    lower: Sequence[float], upper: Sequence[float], counts: Sequence[int]
) -> np.ndarray:
    """Frames on a regular grid: ``counts[a]`` positions from lower to upper along axis a
    (ends included; one count puts the frames at the middle). Returns (n, 3)."""
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    counts = [int(c) for c in counts]
    if lo.shape != (3,) or hi.shape != (3,) or len(counts) != 3:
        raise InputError("grid_frames: lower, upper and counts need 3 entries each")
    if min(counts) < 1:
        raise InputError(f"grid_frames: counts must be >= 1, not {counts}")
    check_memory(math.prod(counts) * 1000.0, f"grid_frames {counts}", "Use fewer frames.")
    if np.any(hi < lo):
        raise InputError(f"grid_frames: upper {hi.tolist()} is below lower {lo.tolist()}")
    axes = [
        np.linspace(lo[a], hi[a], counts[a]) if counts[a] > 1 else np.array([0.5 * (lo[a] + hi[a])])
        for a in range(3)
    ]
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    return np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)


def farthest_point_frames(points: np.ndarray, n: int, first: int = 0) -> np.ndarray:
    """n frames at points (k, 3) chosen by farthest-point sampling from points[first]
    (Gilles et al. 2011 start from such a sampling): evenly spread over any shape."""
    P = np.asarray(points, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] == 0:
        raise InputError(f"farthest_point_frames: points must be (k, 3), not shape {P.shape}")
    if not 1 <= n <= P.shape[0]:
        raise InputError(f"farthest_point_frames: n must be in 1..{P.shape[0]}, not {n}")
    chosen = [int(first)]
    dist = np.linalg.norm(P - P[first], axis=1)
    for _ in range(n - 1):  # n is small (frames), each pass is vectorised over the points
        i = int(np.argmax(dist))
        chosen.append(i)
        dist = np.minimum(dist, np.linalg.norm(P - P[i], axis=1))
    return P[chosen].copy()
