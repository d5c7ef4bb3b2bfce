"""``Simulation.add_rigid_wall`` (a mixin): a FEM body's facet surface pressed out of a plane
by a penalty or augmented Lagrangian, as FEBio's rigid wall (``contact/penalty/rigid_wall.py``),
built into the system with the penalty contact pairs. The barrier's plane obstacle
(``add_obstacle`` with ``contact.obstacles.plane``) keeps the surface off the plane with a
guarantee; this wall lets it in by force / penalty, as FEBio does."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError
from tissuesim.validate import short

__all__ = ["RigidWallCalls", "RigidWallSpec", "carry_wall_state"]


@dataclass(frozen=True)
class RigidWallSpec:
    name: str
    body: str
    facets: object
    normal: np.ndarray  # unit
    distance: float
    penalty: float
    offset: Callable[[float], float]
    augmented: bool
    tolerance: float
    max_augmentations: int
    penalty_scale: Callable[[float], float] | None = None


class RigidWallCalls:
    """Mixed into ``Simulation`` (which sets ``self.rigid_walls = []``)."""

    def add_rigid_wall(
        self,
        body: str,
        plane,
        *,
        penalty: float,
        facets=None,
        offset: float | Callable[[float], float] = 0.0,
        augmented: bool = False,
        tolerance: float = 0.0,
        max_augmentations: int = 10,
        penalty_scale: Callable[[float], float] | None = None,
        name: str | None = None,
    ) -> str:
        """A rigid wall: the plane a x + b y + c z = d (``plane`` = (a, b, c, d); the surface
        stays on the side (a, b, c) points to), moved along its unit normal by ``offset`` (m:
        a number or a function of t), pressing each vertex of body ``body``'s ``facets`` (a
        facet set name, (k, 3) or (k, 4) vertex indices, or None: its whole boundary) with
        the pressure ``penalty`` x penetration (Pa/m) over the vertex's share of the surface
        (FEBio's rigid wall). ``augmented``: FEBio's augmented Lagrangian, augmenting at each
        converged solution while the multipliers' norm changes by ``tolerance`` (relative) or
        more, at most ``max_augmentations`` times a step. ``penalty_scale``: a function of t
        the penalty is multiplied by (FEBio's penalty on a load curve). Its force on the body
        is reported by ``forces()`` under ``name`` (default ``rigid_wall<n>``). Returns the
        name."""
        if body not in self.bodies or self.bodies[body].kind != "fem":
            raise InputError(
                f"add_rigid_wall: {short(body)} is not a FEM body; FEM bodies: "
                f"{sorted(n for n, b in self.bodies.items() if b.kind == 'fem') or 'none'}"
            )
        p = np.asarray(plane, dtype=float) if _numbers(plane) else None
        if p is None or p.shape != (4,) or not np.all(np.isfinite(p)):
            raise InputError(
                f"add_rigid_wall: plane = {short(plane)}: give four numbers a, b, c, d"
            )
        size = float(np.linalg.norm(p[:3]))
        if size == 0.0:
            raise InputError("add_rigid_wall: plane's normal (a, b, c) is zero")
        for key, value, positive in (("penalty", penalty, True), ("tolerance", tolerance, False)):
            ok = isinstance(value, int | float) and not isinstance(value, bool)
            ok = ok and np.isfinite(value) and (value > 0 if positive else value >= 0)
            if not ok:
                raise InputError(
                    f"add_rigid_wall: {key} = {short(value)}: give a "
                    f"{'positive' if positive else 'non-negative'} number"
                )
        if (
            isinstance(max_augmentations, bool)
            or not isinstance(max_augmentations, int)
            or (max_augmentations < 0)
        ):
            raise InputError(
                f"add_rigid_wall: max_augmentations = {short(max_augmentations)}: give a whole "
                "number >= 0"
            )
        if callable(offset):
            move = offset
        elif (
            isinstance(offset, int | float) and not isinstance(offset, bool) and np.isfinite(offset)
        ):
            move = _constant(float(offset))
        else:
            raise InputError(
                f"add_rigid_wall: offset = {short(offset)}: give a number (m) or a function of t"
            )
        if penalty_scale is not None and not callable(penalty_scale):
            raise InputError(
                f"add_rigid_wall: penalty_scale = {short(penalty_scale)}: give a function of t"
            )
        name = self._claim_force_name(name, f"rigid_wall{len(self.rigid_walls) + 1}")
        spec = RigidWallSpec(name, body, facets, p[:3] / size, float(p[3] / size),
                             float(penalty), move, bool(augmented), float(tolerance),
                             int(max_augmentations), penalty_scale)  # fmt: skip
        self.rigid_walls.append(spec)
        self._system_dirty = True
        return name

    def _rigid_wall_energies(self, system) -> list:
        """The system's RigidWall energies, set up at rest (the offset at the system's load
        time)."""
        from tissuesim.contact.pairs import contact_facets
        from tissuesim.contact.penalty.faces import Facets
        from tissuesim.contact.penalty.rigid_wall import RigidWall, node_areas

        walls = []
        for spec in self.rigid_walls:
            if spec.body not in system.names:
                continue
            j = system.names.index(spec.body)
            mesh = system.bodies[j].mesh
            if mesh.dim != 3:
                raise InputError(f"rigid wall {spec.name!r}: body {spec.body!r} is not 3D")
            if isinstance(spec.facets, str) and spec.facets in mesh.facet_sets:
                rows = np.asarray(mesh.facet_sets[spec.facets])
            elif spec.facets is None or isinstance(spec.facets, str):
                rows = contact_facets(spec.body, mesh, spec.facets)
            else:
                rows = np.asarray(spec.facets)
            facets = Facets.of(rows, f"rigid wall {spec.name!r}, body {spec.body!r}")
            if facets.nodes.max() >= mesh.n_points or facets.nodes.min() < 0:
                raise InputError(
                    f"rigid wall {spec.name!r}: body {spec.body!r} has {mesh.n_points} "
                    "vertices; a facet names one outside 0..n-1"
                )
            nodes, areas = node_areas(mesh.points, facets)
            walls.append(
                RigidWall(
                    spec.name,
                    j,
                    nodes,
                    areas,
                    spec.normal,
                    spec.distance,
                    spec.penalty,
                    spec.offset,
                    lambda s=system: s.load_time,
                    spec.augmented,
                    spec.tolerance,
                    spec.max_augmentations,
                )  # fmt: skip
            )
            if spec.penalty_scale is not None:
                walls[-1].scale = spec.penalty_scale
        return walls


def carry_wall_state(old: list, new: list) -> None:
    """Keep each wall's multipliers across a system rebuild where its nodes are the same."""
    from tissuesim.contact.penalty.rigid_wall import RigidWall

    by_name = {w.name: w for w in old if isinstance(w, RigidWall)}
    for wall in new:
        before = by_name.get(wall.name)
        if isinstance(wall, RigidWall) and before is not None:
            if np.array_equal(before.nodes, wall.nodes):
                wall.multipliers = before.multipliers


def _numbers(value) -> bool:
    try:
        return np.asarray(value).dtype.kind in "iuf"
    except (TypeError, ValueError):
        return False


def _constant(value: float) -> Callable[[float], float]:
    return lambda t: value
