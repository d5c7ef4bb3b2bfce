"""What a run reports that a measurement can be compared with, and how it depends on the state:
a support's reaction force, and the displacement of marker vertices.

Each observation gives its values y(x) at the current state and their derivatives as two
linear maps over the system's DOFs: y depends on the positions x directly (displacements) or
through the step's gradient g(x) (a reaction sums g over the DOFs its set prescribes), so

    dy = X dx + R dg,

with X and R sparse selections (``rows(sim)``: (X, R) as dense (k, n_dofs) arrays are never
formed: they are index lists).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError

__all__ = ["Reaction", "Displacement", "Observation"]


def _fem_body(sim, name: str | None, what: str):
    names = [n for n, b in sim.bodies.items() if b.kind == "fem"]
    if name is None:
        if len(names) != 1:
            raise InputError(f"{what}: name the body (one of {names})")
        name = names[0]
    if name not in sim.bodies or sim.bodies[name].kind != "fem":
        raise InputError(f"{what}: no FEM body {name!r}; bodies: {names}")
    return name, sim.bodies[name], sim.system.names.index(name)


def _components(component, d: int, what: str) -> list[int]:
    if component is None:
        return list(range(d))
    comps = [component] if np.ndim(component) == 0 else list(component)
    if not all(isinstance(c, (int, np.integer)) and 0 <= c < d for c in comps):
        raise InputError(f"{what}: component must be in 0..{d - 1} (x, y, z), got {component!r}")
    return [int(c) for c in comps]


@dataclass(frozen=True)
class Reaction:
    """The force (N) the named support, prescribed set or grasper set ``name`` applies to its
    FEM body (``Simulation.forces()[name]``), its ``component`` (0, 1, 2; default all three)."""

    name: str
    component: int | tuple | None = None

    def rows(self, sim) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """(X rows, R rows): per value, the system DOFs its x-part and g-part sum."""
        what = f"Reaction({self.name!r})"
        for body_name, body in sim.bodies.items():
            if body.kind != "fem":
                continue
            names = [n for n, _ in body.conditions]
            if self.name not in names:
                continue
            k = names.index(self.name)
            j = sim.system.names.index(body_name)
            d = body.dim
            owner = body.reaction_owners()
            offset = sim.system.tangent_slices[j].start
            out = []
            for c in _components(self.component, d, what):
                vertices = np.flatnonzero(owner[:, c] == k)
                out.append(offset + vertices * d + c)
            return [np.zeros(0, int)] * len(out), out
        raise InputError(
            f"{what}: no support or prescribed set of that name on a FEM body; the run's "
            f"forces: {sorted(sim.forces())}"
        )


@dataclass(frozen=True)
class Displacement:
    """The displacement (m) of ``vertices`` of FEM body ``body`` (default: the only one), their
    ``component`` (default all): one value per vertex and component, vertex-major."""

    vertices: tuple | list | np.ndarray
    body: str | None = None
    component: int | tuple | None = None

    def rows(self, sim) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """(X rows, R rows): per value, the one system DOF it reads."""
        what = "Displacement"
        name, body, j = _fem_body(sim, self.body, what)
        v = np.asarray(self.vertices, dtype=np.int64).ravel()
        if v.size == 0 or v.min() < 0 or v.max() >= body.mesh.n_points:
            raise InputError(
                f"{what}: vertices must be indices 0..{body.mesh.n_points - 1} of body {name!r}"
            )
        d = body.dim
        offset = sim.system.tangent_slices[j].start
        comps = _components(self.component, d, what)
        out = [np.array([offset + i * d + c]) for i in v for c in comps]
        return out, [np.zeros(0, int)] * len(out)

    def rest(self, sim) -> np.ndarray:
        """The rest coordinates of the observed DOFs (what a displacement subtracts)."""
        name, body, _ = _fem_body(sim, self.body, "Displacement")
        v = np.asarray(self.vertices, dtype=np.int64).ravel()
        comps = _components(self.component, body.dim, "Displacement")
        return np.asarray(body.mesh.points)[v][:, comps].ravel()


Observation = Reaction | Displacement
