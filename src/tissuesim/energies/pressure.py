"""A follower pressure: a pressure p (Pa) that acts normal to the surface where it is now
(FEBio's pressure load with ``<linear>0</linear>``, its default), e.g. a cavity's internal
pressure, a fluid pressure around a body, or a pressure on one face of a block.

On a closed surface it is conservative: its work is p times the change of the enclosed volume,
so it is one more energy of the incremental potential. With the surface's triangles (a, b, c)
oriented outward from the material (as boundary facets are), the divergence theorem gives

    W(x) = p / 6 sum_faces x_a . (x_b x x_c),

which is +p times the body's volume for its outer surface (a positive p compresses it) and -p
times a cavity's volume for a cavity's wall (a positive p inflates it). Gradient per face:
dW/dx_a = p/6 (x_b x x_c), cyclically; Hessian blocks d2W/dx_a dx_b = -p/6 [x_c]_x (the cross
product matrix), d2W/dx_a dx_c = p/6 [x_b]_x, symmetric over the whole surface and indefinite
(Newton's shifts handle it). On an open surface (and on the quadrilateral faces of hexahedra)
the same load is not conservative (no energy; an unsymmetric load stiffness): it is lagged
instead, re-lagged until it settles (``energies/pressure_lag.py``). ``follower_pressure``
decides per surface: closed triangles take the energy, every other surface the lag.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError

__all__ = ["FollowerPressure", "check_closed", "follower_pressure"]


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
            f"{exc}; a follower pressure has an energy only on a closed surface (a body's "
            "whole boundary, a cavity's wall)"
        ) from None


def is_closed(facets: np.ndarray) -> bool:
    """Whether triangles close a consistently oriented surface (``check_closed`` passes)."""
    try:
        check_closed(facets, "")
    except InputError:
        return False
    return True


def follower_pressure(mesh, facets, pressure, name: str, body: str) -> FollowerPressure:
    """A follower pressure p (Pa; a number or a callable t -> p) on boundary facets of a 3D
    body of ``mesh`` (P1 tetrahedra: triangles (k, 3); Q1 hexahedra and hexahedra20: quad
    faces (k, 4), the latter's taken with their midside nodes (k, 8)), given
    in any vertex order; they are matched to the boundary and oriented outward. Closed
    triangles take the energy, every other surface is lagged."""
    from tissuesim.mesh.queries.boundary import boundary_facets, match_facets
    from tissuesim.validate import indices

    where = f"add_follower_pressure {name!r}"
    if mesh.dim != 3 or mesh.cell_type not in ("tetra", "hexahedron", "hexahedron20"):
        raise InputError(
            f"{where}: body {body!r} has {mesh.cell_type} cells; a follower pressure acts on "
            "the boundary triangles of P1 tetrahedra or the quad faces of Q1 hexahedra and "
            "hexahedra20"
        )
    width = 3 if mesh.simplicial else 4
    shape = "triangles" if width == 3 else "quadrilaterals (the hexahedra's faces)"
    ids = indices(facets, f"{where}: facets", mesh.n_points)
    facets = ids.reshape(np.shape(facets)) if ids.size else ids.reshape(0, width)
    if facets.ndim != 2 or facets.shape[1] != width or len(facets) == 0:
        raise InputError(f"{where}: facets must be (k, {width}) vertex indices of {shape}")
    if width == 3:
        boundary = boundary_facets(mesh.cells)
    else:
        from tissuesim.mesh.cells.tensor import boundary_faces

        boundary = boundary_faces(mesh.cells[:, :8], 3)  # a hexahedron20's by its corners
    row = match_facets(boundary, facets)
    if np.any(row < 0):
        raise InputError(
            f"{where}: facet {facets[row < 0][0].tolist()} is not a boundary "
            f"{'triangle' if width == 3 else 'face'} of body {body!r}; a pressure acts on the "
            "body's boundary"
        )
    facets = np.asarray(boundary[row], dtype=np.int64)  # outward, whatever order was given
    if len(np.unique(row)) < len(row):
        raise InputError(f"{where}: a facet is given twice")
    if mesh.cell_type == "hexahedron20":  # quad8 faces (lagged, energies/pressure_lag.py)
        from tissuesim.mesh.cells.tensor_quadratic import full_facets

        facets = full_facets(mesh, facets)
    if callable(pressure):
        value = pressure
    else:
        p = float(pressure)
        if not np.isfinite(p):
            raise InputError(f"{where}: pressure must be a finite number (Pa), not {p}")

        def value(t: float, p: float = p) -> float:
            return p

    return FollowerPressure(facets, value, name, closed=width == 3 and is_closed(facets))


@dataclass(eq=False)
class FollowerPressure:
    """p(t) (Pa) on the outward-oriented facets (k, 3) or (k, 4) of a 3D body: an energy on a
    closed surface of triangles (``closed``), lagged on any other."""

    facets: np.ndarray
    pressure: Callable[[float], float]
    name: str = "pressure"
    closed: bool = True
    _positions: dict = field(default_factory=dict, repr=False)

    def energy(self, t: float):
        """The step's energy at time t (the pressure's value then): ``PressureEnergy`` on a
        closed surface, else ``pressure_lag.LaggedPressureEnergy`` (no lag yet)."""
        p = float(self.pressure(t))
        if not np.isfinite(p):
            raise InputError(f"pressure {self.name!r}: p({t:g}) = {p} is not finite")
        if self.closed:
            return PressureEnergy(self, p)
        from tissuesim.energies.pressure_lag import LaggedPressureEnergy

        return LaggedPressureEnergy(self, p)

    def positions(self, pattern) -> np.ndarray:
        """Where each facet's (3m x 3m) block goes in ``pattern``'s data (k, 9 m^2), cached."""
        key = id(pattern)
        if key not in self._positions:
            n = 3 * self.facets.shape[1]
            dofs = (self.facets[:, :, None] * 3 + np.arange(3)).reshape(-1, n)
            rows = np.repeat(dofs, n, axis=1)
            cols = np.tile(dofs, (1, n))
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
