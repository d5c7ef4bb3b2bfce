"""Who touches whom, and with what friction: the contact surface of each body and the table of
pairs (body-body, body-itself, body-obstacle) with their switch and Coulomb coefficient.

Each collision-mesh vertex belongs to one group (a body's contact surface or an obstacle).
``PairTable`` holds, per pair of groups, whether they collide and their mu: the scene-wide mu,
then an obstacle's own ``friction``, then an explicit ``ContactPair``, the last one winning.
Obstacles never collide with each other or themselves: both sides are prescribed, and as
unknowns of the moving-obstacle solve (kinematic.py) such a pair would fight the motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError
from tissuesim.validate import real, short

__all__ = ["ContactPair", "PairTable", "contact_facets"]


@dataclass(frozen=True)
class ContactPair:
    """Contact between ``a`` and ``b`` (body or obstacle names; a == b: a body with itself):
    ``enabled`` False leaves the pair out; ``friction`` its Coulomb mu (None: the default)."""

    a: str
    b: str
    enabled: bool = True
    friction: float | None = None

    def __post_init__(self) -> None:
        for side in (self.a, self.b):
            if not isinstance(side, str) or not side:
                raise InputError(
                    f"contact pair: names must be non-empty strings, not {short(side)}"
                )
        if not isinstance(self.enabled, bool):
            raise InputError(f"contact pair {self.a}-{self.b}: enabled must be true or false")
        if self.friction is not None:
            object.__setattr__(
                self,
                "friction",
                real(self.friction, f"contact pair {self.a}-{self.b} friction", low=0.0),
            )


def contact_facets(name: str, mesh, surface) -> np.ndarray:
    """The boundary facets (k, d: triangles in 3D, edges in 2D) of body ``name`` that take part
    in contact: its whole boundary (``surface`` None), a facet set of its mesh by name, or a
    (k, d) array of vertex indices; a hexahedral mesh's quad faces (k, 4) are split in two (a
    quadratic one's into the 6 or 8 triangles of its split, a quad8 / quad9 mesh's edges into
    2 segments), a wedge mesh's (k, 4) facets into triangles as its split has them (a triangle
    (a, b, c, c) is one, ``mesh/cells/wedge.py``)."""
    from tissuesim.mesh.queries.boundary import boundary_facets

    if surface is None:
        return boundary_facets(mesh.simplices)
    if isinstance(surface, str):
        if surface not in mesh.facet_sets:
            known = ", ".join(sorted(mesh.facet_sets)) or "none"
            raise InputError(
                f"contact surface of {name!r}: its mesh has no facet set {short(surface)} "
                f"(facet sets: {known}); name one, or give the triangles as vertex indices"
            )
        tri = np.asarray(mesh.facet_sets[surface])
    else:
        try:
            tri = np.asarray(surface)
            width = (mesh.dim, mesh.facet_nodes)
            ok = tri.ndim == 2 and tri.shape[1] in width and tri.dtype.kind in "iu"
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise InputError(
                f"contact surface of {name!r}: give a facet set name or a (k, {mesh.dim}) integer "
                f"array of vertex indices, not {short(surface)}"
            )
        if tri.size and (tri.min() < 0 or tri.max() >= mesh.n_points):
            raise InputError(
                f"contact surface of {name!r}: vertex indices must lie in 0..{mesh.n_points - 1}"
            )
    if len(tri) == 0:
        raise InputError(f"contact surface of {name!r} has no triangles")
    if not mesh.simplicial and mesh.order == 2 and tri.shape[1] == mesh.facet_nodes:
        # quadratic quadrilaterals / hexahedra: each facet as the simplices of the mesh's split
        from tissuesim.mesh.cells.tensor_quadratic import facet_simplices

        try:
            return facet_simplices(mesh, tri).astype(np.int64)
        except InputError as exc:
            raise InputError(f"contact surface of {name!r}: {exc}") from None
    if mesh.cell_type == "wedge" and tri.shape[1] == 4:  # quads and collapsed triangles
        from tissuesim.mesh.cells.wedge import facet_triangles

        tri = facet_triangles(tri)
    if mesh.facet_nodes == 4 and tri.shape[1] == 4:  # quad faces of hexahedra: 2 triangles each
        from tissuesim.mesh.cells.tensor import split_faces

        tri = split_faces(tri)
    if tri.shape[1] != mesh.dim:
        kind = "triangles (a 3D mesh's facets)" if mesh.dim == 3 else "edges (a 2D mesh's facets)"
        raise InputError(f"contact surface of {name!r} must be {kind}")
    return tri.astype(np.int64)


def _not_both_in(ipctk, group: np.ndarray, groups: list[int]):
    """A filter that accepts a vertex pair unless both its vertices are in ``groups`` (their
    vertices share one patch label, every other vertex its own)."""
    labels = np.arange(1, len(group) + 1, dtype=np.int32)
    labels[np.isin(group, groups)] = 0
    return ipctk.make_vertex_patches_filter(labels.reshape(-1, 1))


class PairTable:
    """Per pair of groups (bodies first, then obstacles): enabled and mu; see the module
    docstring."""

    def __init__(self, bodies: list[str], obstacles: list, friction: float, pairs) -> None:
        self.names = [*bodies, *(ob.name for ob in obstacles)]
        n, nb = len(self.names), len(bodies)
        self._n_obstacles = len(obstacles)
        index = {name: i for i, name in enumerate(self.names)}
        self.enabled = np.ones((n, n), dtype=bool)
        self.enabled[nb:, nb:] = False
        self.mu = np.full((n, n), float(friction))
        for k, ob in enumerate(obstacles):
            if getattr(ob, "friction", None) is not None:
                self.mu[nb + k, :] = self.mu[:, nb + k] = ob.friction
        for pair in pairs:
            for side in (pair.a, pair.b):
                if side not in index:
                    raise InputError(
                        f"contact pair {pair.a}-{pair.b}: no body or obstacle {side!r} "
                        f"(known: {', '.join(self.names)})"
                    )
            i, j = index[pair.a], index[pair.b]
            if i >= nb and j >= nb:
                raise InputError(
                    f"contact pair {pair.a}-{pair.b}: two obstacles never collide (both are "
                    "prescribed); pair an obstacle with a body"
                )
            self.enabled[i, j] = self.enabled[j, i] = pair.enabled
            if pair.friction is not None:
                self.mu[i, j] = self.mu[j, i] = pair.friction
        self.mu[~self.enabled] = 0.0

    @property
    def filtered(self) -> bool:
        """Whether some pair is off (always so with an obstacle: obstacles never collide)."""
        return not bool(self.enabled.all())

    def collision_filter(self, ipctk, group: np.ndarray, n_vertices: int):
        """An ipctk CollisionFilter that accepts a vertex pair iff its groups collide: the
        obstacles' vertices (the last ones) never meet each other; a disabled pair (A, B) is
        "not both in A u B, or both in A, or both in B" (A == B: "not both in A")."""
        nb = len(self.names) - self._n_obstacles
        first_obstacle = int(np.searchsorted(group, nb)) if self._n_obstacles else n_vertices
        result = ipctk.make_static_obstacle_filter(first_obstacle)
        for i in range(nb):
            for j in range(i, len(self.names)):
                if self.enabled[i, j]:
                    continue
                if i == j:
                    result = result & _not_both_in(ipctk, group, [i])
                else:
                    allowed = (
                        _not_both_in(ipctk, group, [i, j])
                        | ~_not_both_in(ipctk, group, [i])
                        | ~_not_both_in(ipctk, group, [j])
                    )
                    result = result & allowed
        return result

    def pair_filter(self, ipctk, group: np.ndarray, i: int, j: int):
        """An ipctk CollisionFilter that accepts only vertex pairs between groups i and j
        (i != j): the collisions through which one body pushes another."""
        return (
            ~_not_both_in(ipctk, group, [i, j])
            & _not_both_in(ipctk, group, [i])
            & _not_both_in(ipctk, group, [j])
        )

    def body_pairs(self) -> list[tuple[int, int]]:
        """The enabled pairs (i < j) of two different bodies (no obstacle)."""
        nb = len(self.names) - self._n_obstacles
        return [(i, j) for i in range(nb) for j in range(i + 1, nb) if self.enabled[i, j]]

    @property
    def uniform_mu(self) -> float | None:
        """The one mu of every enabled pair, or None if they differ."""
        values = np.unique(self.mu[self.enabled])
        return float(values[0]) if len(values) == 1 else (0.0 if len(values) == 0 else None)

    @property
    def has_friction(self) -> bool:
        return bool((self.mu[self.enabled] > 0).any())

    def describe(self) -> list[dict]:
        """Every pair but obstacle-obstacle: names, enabled, friction."""
        nb = len(self.names) - int(self._n_obstacles)
        return [
            {
                "pair": [self.names[i], self.names[j]],
                "enabled": bool(self.enabled[i, j]),
                "friction": float(self.mu[i, j]),
            }
            for i in range(len(self.names))
            for j in range(i, len(self.names))
            if i < nb
        ]
