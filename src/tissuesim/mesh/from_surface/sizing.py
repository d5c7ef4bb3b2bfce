"""The options of ``tetrahedralize`` beyond the size: the mesher's envelope and coarsening,
smoothing a staircase, and a requested element count (issue 41).

- ``epsilon`` / ``envelope``: how far fTetWild's boundary may lie from the input surface,
  relative to the bounding-box diagonal (fTetWild's ``-e``, pytetwild's ``epsilon``; default
  1e-3) or absolute in the surface's units. A staircase or a noisy surface with a tight envelope
  is meshed with small elements along every step, whatever the size; a wider envelope lets the
  mesher cut across them.
- ``coarsen``: fTetWild's ``--coarsen``: coarsen the output as far as the quality allows.
- ``target_elements``: a number of tetrahedra reached within ``ELEMENT_TOLERANCE`` (30 %). The
  count of fTetWild's mesh at edge length l (the envelope following l) is modelled as
  ``N = V / (FILL * sqrt(2) / 12 * l^3) + SURFACE * A / l^2``: the interior's tetrahedra plus
  the boundary layer's along the area A. The boundary term depends on how rough the surface is
  (measured in benchmarks/mesh_to_size.py: 12 A / l^2 on a smooth ellipsoid, 70 after smoothing
  a noisy staircase, 144 on the staircase itself), so the first size (``first_size``) takes a
  middle value, and each next one (``next_size``) recalibrates the boundary term on the pass
  closest to the request, or interpolates log(size) against log(count) once passes lie on
  both sides of it; at most ``MAX_PASSES`` passes.

Every bad value is an ``InputError`` of one line naming the option.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.from_surface import smoothing as _smoothing
from tissuesim.mesh.from_surface.smoothing import DEFAULT_SMOOTHING_ITERATIONS
from tissuesim.validate import short

__all__ = [
    "ELEMENT_TOLERANCE",
    "MAX_PASSES",
    "MeshingOptions",
    "meshing_options",
    "first_size",
    "next_size",
    "to_count",
]

#: a size that would make more tetrahedra than this (estimated), or a larger count, is refused
MAX_TETRAHEDRA = 5_000_000
#: a requested element count is reached when the count is within this fraction of it
ELEMENT_TOLERANCE = 0.3
#: the most meshing passes a requested element count may take (the first included)
MAX_PASSES = 4
#: the volume of the regular tetrahedron of edge l is REGULAR * l^3
REGULAR = math.sqrt(2.0) / 12.0
#: the count model (see above): fTetWild's interior tetrahedra at a target edge length l hold
#: on average FILL times the regular one's volume (1.9 fitted on the smooth ellipsoid of
#: mesh_to_size.py), and its boundary layer adds SURFACE * area / l^2 (12-144 measured; the
#: first estimate takes 40, later passes recalibrate it)
FILL = 1.9
SURFACE = 40.0
#: fTetWild's own default envelope, relative to the bounding-box diagonal (1/50 of its default
#: edge length, 0.05 of the diagonal)
DEFAULT_EPSILON = 1e-3
#: the envelope when none is given, as a fraction of the target edge length: it follows the
#: size, so that a coarser size gives a coarser mesh on a noisy surface too (fTetWild's fixed
#: 1e-3 of the diagonal kept a staircase's count nearly independent of the size)
ENVELOPE_PER_SIZE = 1.0 / 20.0
#: the options that only pytetwild (fTetWild) has
TETWILD_ONLY = ("epsilon", "envelope", "coarsen")


@dataclass(frozen=True)
class MeshingOptions:
    """Checked options of ``tetrahedralize`` (see the module's docstring)."""

    epsilon: float | None = None
    envelope: float | None = None
    coarsen: bool = False
    smoothing: str | None = None
    smoothing_iterations: int = DEFAULT_SMOOTHING_ITERATIONS
    target_elements: int | None = None

    def tetwild(self) -> list[str]:
        """The pytetwild-only options given (to refuse them for another mesher)."""
        given = [self.epsilon is not None, self.envelope is not None, self.coarsen]
        return [k for k, g in zip(TETWILD_ONLY, given, strict=True) if g]

    def relative_epsilon(self, diagonal: float, size: float) -> float:
        """The envelope relative to the bounding-box diagonal, as fTetWild takes it: epsilon,
        or envelope / diagonal, or by default ENVELOPE_PER_SIZE * size / diagonal."""
        if self.envelope is not None:
            return self.envelope / diagonal
        if self.epsilon is not None:
            return self.epsilon
        return min(ENVELOPE_PER_SIZE * size / diagonal, 0.1)


def _positive(name: str, value: object, what: str) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating):
        raise InputError(f"{name} must be a number ({what}), not {short(value)}")
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"{name} must be > 0 ({what}), not {value!r}")
    return float(value)


def meshing_options(
    *,
    size: float | None = None,
    epsilon: object = None,
    envelope: object = None,
    coarsen: object = False,
    smoothing: object = None,
    smoothing_iterations: object = DEFAULT_SMOOTHING_ITERATIONS,
    target_elements: object = None,
) -> MeshingOptions:
    """Check the options; an InputError of one line naming the first bad one."""
    eps = _positive("epsilon", epsilon, "the envelope relative to the bounding-box diagonal")
    if eps is not None and eps >= 0.5:
        raise InputError(
            f"epsilon must be below 0.5 (relative to the bounding-box diagonal; fTetWild's "
            f"default is {DEFAULT_EPSILON:g}), not {eps!r}; an absolute width is 'envelope'"
        )
    env = _positive("envelope", envelope, "the envelope's width in the surface's units")
    if eps is not None and env is not None:
        raise InputError(
            "give epsilon (relative to the bounding-box diagonal) or envelope (absolute), not both"
        )
    if not isinstance(coarsen, bool):
        raise InputError(f"coarsen must be true or false, not {short(coarsen)}")
    method = _smoothing.smoothing_method(smoothing)
    iterations = _smoothing.smoothing_iterations(smoothing_iterations)
    n = target_elements
    if n is not None:
        if isinstance(n, bool) or not isinstance(n, int | np.integer | float):
            raise InputError(f"target_elements must be a whole number >= 1, not {short(n)}")
        if isinstance(n, float) and not (math.isfinite(n) and n == int(n)):
            raise InputError(f"target_elements must be a whole number >= 1, not {n!r}")
        if n < 1:
            raise InputError(f"target_elements must be a whole number >= 1, not {n!r}")
        if n > MAX_TETRAHEDRA:
            raise InputError(f"target_elements must be at most {MAX_TETRAHEDRA:g}, not {n!r}")
        n = int(n)
        if size is not None:
            raise InputError(
                "give size (the edge length) or target_elements (the number of tetrahedra), "
                "not both: the size is chosen to reach the count"
            )
    return MeshingOptions(eps, env, coarsen, method, iterations, n)


def _count_size(volume: float, area: float, elements: float, fill: float, surface: float) -> float:
    """The edge length l at which the count model gives ``elements`` (its one positive root)."""
    roots = np.roots([volume / (fill * REGULAR), surface * area, 0.0, -float(elements)])
    x = max(r.real for r in roots if abs(r.imag) <= 1e-9 * abs(r) and r.real > 0)  # 1 / l
    return float(1.0 / x)


def first_size(volume: float, area: float, elements: int) -> float:
    """The first estimate of the edge length for ``elements`` tetrahedra: the count model with
    FILL and SURFACE (see the module's docstring)."""
    return _count_size(volume, area, elements, FILL, SURFACE)


def next_size(history: list[tuple[float, int]], elements: int, volume: float, area: float) -> float:
    """The next edge length towards ``elements`` tetrahedra from the (size, count) passes made.

    Passes on both sides of the request: log(size) interpolated in log(count) between the two
    closest to it. Otherwise the count model recalibrated on the pass closest to the request:
    its boundary term when that count exceeds the interior's alone (a rough surface), else its
    interior fill (no boundary term). The step is at most a factor 4 either way.
    """
    above = [p for p in history if p[1] > elements]
    below = [p for p in history if p[1] <= elements]
    if above and below:
        (h1, n1), (h2, n2) = min(above, key=lambda p: p[1]), max(below, key=lambda p: p[1])
        if n1 != n2 and n2 > 0:
            t = math.log(elements / n1) / math.log(n2 / n1)
            return math.exp(math.log(h1) + t * (math.log(h2) - math.log(h1)))
    h, n = min(history, key=lambda p: abs(math.log(max(p[1], 1) / elements)))
    interior = volume / (FILL * REGULAR * h**3)
    if n > 1.05 * interior:
        new = _count_size(volume, area, elements, FILL, (n - interior) * h**2 / area)
    else:  # fewer than the interior model alone: a coarser fill than FILL, no boundary term
        new = _count_size(volume, area, elements, volume / (REGULAR * h**3 * max(n, 1)), 0.0)
    return h * min(max(new / h, 0.25), 4.0)


def to_count(
    mesh_once: Callable[[float], tuple[Any, float]],
    elements: int,
    surface: Any,
    source: str,
) -> tuple[Any, float, float, list[dict[str, Any]]]:
    """Mesh ``surface`` (a ``Surface``) to about ``elements`` tetrahedra by
    ``mesh_once(size) -> (mesh, seconds)``.

    Returns the mesh closest to the request (in log ratio), its size, the mesher's seconds over
    all passes and the passes made (size, n_tets, seconds). The sizes stay below half the
    bounding-box diagonal. When no pass lands within ELEMENT_TOLERANCE in MAX_PASSES, a
    warning names the counts and the closest mesh is returned.
    """
    diagonal = surface.diagonal
    volume = abs(surface.volume) or float(np.prod(np.ptp(surface.points, axis=0)))
    x = surface.points[surface.faces]
    area = 0.5 * float(np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1).sum())
    h = min(first_size(volume, area, elements), 0.5 * diagonal)
    passes: list[dict[str, Any]] = []
    best: tuple[float, Any, float] | None = None
    total = 0.0
    for _ in range(MAX_PASSES):
        mesh, seconds = mesh_once(h)
        total += seconds
        passes.append({"size": h, "n_tets": mesh.n_cells, "seconds": round(seconds, 3)})
        miss = abs(math.log(mesh.n_cells / elements))
        if best is None or miss < best[0]:
            best = (miss, mesh, h)
        if abs(mesh.n_cells / elements - 1.0) <= ELEMENT_TOLERANCE:
            break
        made = [(p["size"], p["n_tets"]) for p in passes]
        h = min(next_size(made, elements, volume, area), 0.5 * diagonal)
        if any(abs(h / p["size"] - 1.0) < 1e-6 for p in passes):
            break  # at the largest size already: another pass would mesh the same again
    assert best is not None
    if abs(best[1].n_cells / elements - 1.0) > ELEMENT_TOLERANCE:
        counts = ", ".join(f"{p['n_tets']} at {p['size']:.3g}" for p in passes)
        warnings.warn(
            f"{source}: target_elements {elements} not reached within "
            f"{ELEMENT_TOLERANCE * 100:g} % in {len(passes)} passes (tetrahedra at size: "
            f"{counts}); "
            f"kept the closest, {best[1].n_cells} tetrahedra. The surface's detail sets a "
            f"floor: smooth a staircase (smoothing 'taubin'), widen the envelope (epsilon) "
            f"or coarsen",
            UserWarning,
            stacklevel=4,
        )
    return best[1], best[2], total, passes
