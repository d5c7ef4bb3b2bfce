"""A follower pressure on a closed surface: a pressure p (Pa) that acts normal to the surface
where it is now (FEBio's pressure load with ``<linear>0</linear>``, its default), e.g. a
cavity's internal pressure or a fluid pressure around a body.

On a closed surface it is conservative: its work is p times the change of the enclosed volume,
so it is one more energy of the incremental potential. With the surface's triangles (a, b, c)
oriented outward from the material (as boundary facets are), the divergence theorem gives

    W(x) = p / 6 sum_faces x_a . (x_b x x_c),

which is +p times the body's volume for its outer surface (a positive p compresses it) and -p
times a cavity's volume for a cavity's wall (a positive p inflates it). Gradient per face:
dW/dx_a = p/6 (x_b x x_c), cyclically; Hessian blocks d2W/dx_a dx_b = -p/6 [x_c]_x (the cross
product matrix), d2W/dx_a dx_c = p/6 [x_b]_x, symmetric over the whole surface and indefinite
(Newton's shifts handle it). On an open surface the same load is not conservative (no energy;
an unsymmetric load stiffness), so an open surface is refused.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError

__all__ = ["FollowerPressure", "check_closed"]


def check_closed(facets: np.ndarray, where: str) -> None:
    """Refuse a triangle set that is not a closed, consistently oriented surface (the check
    of ``frames.surfaces.Surface``: every edge in two triangles that traverse it oppositely)."""
    from tissuesim.errors import MeshError
    from tissuesim.frames.surfaces import Surface

    facets = np.asarray(facets)
    if facets.ndim != 2 or facets.shape[1] != 3 or len(facets) == 0:
        raise InputError(f"{where}: a follower pressure needs a closed surface of triangles")
    try:
        Surface(np.zeros((int(facets.max()) + 1, 3)), facets, source=where).volume()
    except MeshError as exc:
        raise InputError(
            f"{exc}; a follower pressure is conservative only on a closed surface (a body's "
            "whole boundary, a cavity's wall): on an open one use a dead traction"
        ) from None


@dataclass(eq=False)
class FollowerPressure:
    """p(t) (Pa) on the closed, outward-oriented triangles ``facets`` (k, 3) of a 3D body."""

    facets: np.ndarray
    pressure: Callable[[float], float]
    name: str = "pressure"
    _positions: dict = field(default_factory=dict, repr=False)

    def energy(self, t: float) -> PressureEnergy:
        """The energy at time t (the pressure's value then)."""
        p = float(self.pressure(t))
        if not np.isfinite(p):
            raise InputError(f"pressure {self.name!r}: p({t:g}) = {p} is not finite")
        return PressureEnergy(self, p)

    def positions(self, pattern) -> np.ndarray:
        """Where each face's 9 x 9 block goes in ``pattern``'s data (k, 81), cached."""
        key = id(pattern)
        if key not in self._positions:
            dofs = (self.facets[:, :, None] * 3 + np.arange(3)).reshape(-1, 9)
            rows = np.repeat(dofs, 9, axis=1)
            cols = np.tile(dofs, (1, 9))
            self._positions = {key: pattern.positions(rows, cols)}
        return self._positions[key]


@dataclass(eq=False)
class PressureEnergy:
    """W = p/6 sum x_a . (x_b x x_c) at one pressure p; see the module docstring."""

    load: FollowerPressure
    p: float

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        f = self.load.facets
        X = x.reshape(-1, 3)[f]  # (k, 3 corners, 3)
        a, b, c = X[:, 0], X[:, 1], X[:, 2]
        acc.add_value(self.load.name, self.p / 6.0 * float(np.einsum("ki,ki->", a, np.cross(b, c))))
        if acc.order >= 1:
            g = self.p / 6.0 * np.stack([np.cross(b, c), np.cross(c, a), np.cross(a, b)], axis=1)
            acc.gradient += np.bincount(
                (f[:, :, None] * 3 + np.arange(3)).ravel(),
                weights=g.ravel(),
                minlength=acc.gradient.size,
            )
        if acc.order >= 2:
            H = np.zeros((len(f), 3, 3, 3, 3))  # [face, corner i, comp, corner j, comp]
            for i in range(3):  # d2/dx_i dx_j of x_i . (x_j x x_k), (i, j, k) cyclic
                j, k = (i + 1) % 3, (i + 2) % 3
                H[:, i, :, j, :] = -_cross_matrix(X[:, k])
                H[:, i, :, k, :] = _cross_matrix(X[:, j])
            H *= self.p / 6.0
            acc.hessian += np.bincount(
                self.load.positions(acc.pattern).ravel(),
                weights=H.reshape(len(f), 81).ravel(),
                minlength=acc.hessian.size,
            )


def _cross_matrix(v: np.ndarray) -> np.ndarray:
    """[v]_x (k, 3, 3): [v]_x w = v x w."""
    out = np.zeros((len(v), 3, 3))
    out[:, 0, 1], out[:, 0, 2] = -v[:, 2], v[:, 1]
    out[:, 1, 0], out[:, 1, 2] = v[:, 2], -v[:, 0]
    out[:, 2, 0], out[:, 2, 1] = -v[:, 1], v[:, 0]
    return out
