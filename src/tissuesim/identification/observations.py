"""What a run reports that a measurement can be compared with, and how it depends on the state:
a support's reaction force, an obstacle's contact force, the displacement of marker vertices,
the distance of measured surface points (a point cloud) from the deformed body's boundary, and
FEBio's logged quantities (node and element data by FEBio's names, a surface's enclosed
volume).

Each observation gives, at a converged state x with the step's gradient g, its values y and
their derivatives as two sparse (k, n_dofs) matrices: y depends on the positions directly
(displacements, distances) or through the gradient (a reaction sums g over the DOFs its set
prescribes), so dy = X dx + R dg (``linearize(sim, x, g)`` -> (y, X, R)). The FEBio ones
(``NodeData``, ``ElementData``, ``EnclosedVolume``) are functions of the state and the
parameters, ``values(sim, x)``, differentiated by ``sensitivity.py`` along each parameter's
sensitivity (an element's stress also depends on the law's parameters directly).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from tissuesim.errors import InputError

__all__ = [
    "Reaction", "Displacement", "SurfaceDistance", "NodeData", "ElementData", "EnclosedVolume",
    "RigidForce", "ContactForce", "Observation", "linearize",
]  # fmt: skip


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


@dataclass(frozen=True)
class SurfaceDistance:
    """The distance (m) from each of ``points`` (k, 3: a measured point cloud of the deformed
    surface, e.g. a surface scan) to the boundary of FEM body ``body``'s deformed mesh (its
    tetrahedra; P2 bodies by their linear sub-tetrahedra): k values, each compared with 0
    where measured. Its derivative moves the closest point with the mesh (the barycentric
    weights held), along the unit vector from it to the measured point."""

    points: tuple | list | np.ndarray
    body: str | None = None

    def linearize(self, sim, x: np.ndarray, g: np.ndarray):
        """(distances (k,), X (k, n) sparse, R zero) at the state x."""
        import dataclasses

        from tissuesim.mesh.queries.locate import closest_boundary_points

        name, body, j = _fem_body(sim, self.body, "SurfaceDistance")
        p = np.asarray(self.points, dtype=float).reshape(-1, 3)
        s = sim.system
        d = body.dim
        xb = x[s.tangent_slices[j]].reshape(-1, d)
        deformed = dataclasses.replace(body.mesh, points=xb)
        found = closest_boundary_points(deformed, p)
        tets = deformed.simplices[found.cells]  # (k, 4) vertices
        diff = p - found.positions
        dist = np.linalg.norm(diff, axis=1)
        unit = np.where(dist[:, None] > 0, -diff / np.where(dist > 0, dist, 1.0)[:, None], 0.0)
        offset = s.tangent_slices[j].start
        rows = np.repeat(np.arange(len(p)), 4 * d)
        cols = (offset + tets[:, :, None] * d + np.arange(d)).ravel()
        vals = (found.barycentric[:, :, None] * unit[:, None, :]).ravel()
        n = s.n_dofs
        X = sp.csr_matrix((vals, (rows, cols)), shape=(len(p), n))
        return dist, X, sp.csr_matrix((len(p), n))


def _at_state(sim, x: np.ndarray, read):
    """read(sim) with the simulation's state's positions set to x (restored after)."""
    import dataclasses

    kept = sim._state
    sim._state = dataclasses.replace(kept, x=x)
    try:
        return read(sim)
    finally:
        sim._state = kept


@dataclass(frozen=True)
class NodeData:
    """FEBio's node_data ``variable`` (``x, y, z``: the current position; ``ux, uy, uz``: the
    displacement) at ``vertices`` of FEM body ``body`` (default: the only one), one value per
    vertex. (A reaction force is ``Reaction``: it depends on the step's gradient.)"""

    variable: str
    vertices: tuple | list | np.ndarray
    body: str | None = None
    explicit = False  # the parameters act through the state only

    def values(self, sim, x: np.ndarray) -> np.ndarray:
        from tissuesim.io.logfiles import LogRequest, node_values

        if self.variable not in ("x", "y", "z", "ux", "uy", "uz"):
            raise InputError(
                f"NodeData: variable {self.variable!r} is not one of x, y, z, ux, uy, uz"
            )
        name, body, _ = _fem_body(sim, self.body, "NodeData")
        rows = _rows(self.vertices, body.mesh.n_points, "NodeData", "vertices", name)
        request = LogRequest("node_data", (self.variable,), name, rows, None, "")
        return _at_state(sim, x, lambda s: node_values(s, request)[self.variable])


@dataclass(frozen=True)
class ElementData:
    """FEBio's element_data ``variable`` (``sx`` ... ``sxz``, ``s1``-``s3``, ``Ex`` ... ``Exz``,
    ``E1``-``E3``, ``J``: each element's mean over its integration points, as FEBio logs it) or
    an expression of them (FEBio's ``"=sx+sy+sz"``, read as the scene's safe expressions,
    ``scene/expressions.py``; ^ is a power) at ``cells`` of FEM body ``body`` (default:
    all), one value per cell, or their
    ``reduce`` = "sum" or "mean" (FEBio's filter_sum, filter_avg) as one value."""

    variable: str
    cells: tuple | list | np.ndarray | None = None
    body: str | None = None
    reduce: str | None = None

    def values(self, sim, x: np.ndarray) -> np.ndarray:
        from tissuesim.io.logfiles import ELEMENT_DATA, LogRequest, element_values
        from tissuesim.scene.expressions import compile_named

        what = "ElementData"
        # FEBio writes a power as ^ (Python's ** in the scene's safe expressions)
        evaluate, used = compile_named(self.variable.lstrip("=").replace("^", "**"),
                                       tuple(ELEMENT_DATA), what)  # fmt: skip
        if not used:
            raise InputError(f"{what}: {self.variable!r} names no element variable")
        name, body, _ = _fem_body(sim, self.body, what)
        rows = None
        if self.cells is not None:
            rows = _rows(self.cells, body.mesh.n_cells, what, "cells", name)
        request = LogRequest("element_data", tuple(used), name, rows, None, "")
        data = _at_state(sim, x, lambda s: element_values(s, request))
        y = np.broadcast_to(evaluate(data), (len(next(iter(data.values()))),)).astype(float)
        if self.reduce is None:
            return y
        if self.reduce not in ("sum", "mean"):
            raise InputError(f"{what}: reduce must be 'sum' or 'mean', not {self.reduce!r}")
        return np.array([y.sum() if self.reduce == "sum" else y.mean()])


@dataclass(frozen=True)
class EnclosedVolume:
    """FEBio's surface_data ``volume``: (1/3) of the integral of x . n over the facets (k, 3)
    or (k, 4) (vertex indices of FEM body ``body``; a name: the mesh's facet set), the volume a
    closed surface encloses (FEBio's ``FELogEnclosedVolume``; exact for triangles and
    bilinear quadrilaterals). One value."""

    facets: str | tuple | list | np.ndarray
    body: str | None = None
    explicit = False

    def values(self, sim, x: np.ndarray) -> np.ndarray:
        what = "EnclosedVolume"
        chosen = self.body
        if chosen is None and isinstance(self.facets, str):  # the body that has the set
            having = [n for n, b in sim.bodies.items()
                      if b.kind == "fem" and self.facets in b.mesh.facet_sets]  # fmt: skip
            chosen = having[0] if len(having) == 1 else None
        name, body, j = _fem_body(sim, chosen, what)
        facets = self.facets
        if isinstance(facets, str):
            if facets not in body.mesh.facet_sets:
                raise InputError(
                    f"{what}: body {name!r} has no facet set {facets!r}; it has "
                    f"{sorted(body.mesh.facet_sets)}"
                )
            facets = body.mesh.facet_sets[facets]
        f = np.asarray(facets, dtype=np.int64)
        if f.ndim != 2 or f.shape[1] not in (3, 4) or f.min() < 0 or f.max() >= body.mesh.n_points:
            raise InputError(
                f"{what}: facets must be (k, 3) or (k, 4) vertex indices of body {name!r}"
            )
        p = x[sim.system.config_slices[j]].reshape(-1, body.dim)[f]
        if f.shape[1] == 3:  # x1 . (x2 x x3) / 6, the rule's exact value
            return np.array([np.einsum("ij,ij->", p[:, 0], np.cross(p[:, 1], p[:, 2])) / 6.0])
        g = 1.0 / np.sqrt(3.0)
        total = 0.0
        for r in (-g, g):  # 2 x 2 Gauss points: exact for the bilinear facet's cubic integrand
            for q in (-g, g):
                n = np.array([(1 - r) * (1 - q), (1 + r) * (1 - q), (1 + r) * (1 + q),
                              (1 - r) * (1 + q)]) / 4.0  # fmt: skip
                dr = np.array([-(1 - q), 1 - q, 1 + q, -(1 + q)]) / 4.0
                dq = np.array([-(1 - r), -(1 + r), 1 + r, 1 - r]) / 4.0
                xg = np.einsum("a,kai->ki", n, p)
                cross = np.cross(np.einsum("a,kai->ki", dr, p), np.einsum("a,kai->ki", dq, p))
                total += np.einsum("ki,ki->", xg, cross) / 3.0
        return np.array([total])


@dataclass(frozen=True)
class RigidForce:
    """A rigid body's force (N) or moment (N m, about its centre) that its held DOFs' supports
    apply, FEBio's ``fem.rigidbody('name').Fz`` (``variable`` Fx, Fy, Fz, Mx, My, Mz), as in
    ``Simulation.forces()``: the step's gradient at the body's DOF (``rows``: its derivative is
    the gradient's, sensitivity.py)."""

    body: str
    variable: str

    def rows(self, sim) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """(X rows, R rows): the rigid body's tangent DOF of the variable."""
        self._check(sim)
        s = sim.system
        k = [r.name for r in s.rigid].index(self.body)
        if s.rigid[k].soft is not None:
            raise InputError(
                f"RigidForce({self.body!r}): a rigid body driven by springs (soft, with "
                "contact) is not differentiated: finite differences of whole runs"
            )
        dof = s.rigid_tangent_slices[k].start + ("FxFyFzMxMyMz".index(self.variable) // 2)
        return [np.zeros(0, int)], [np.array([dof])]

    def _check(self, sim) -> None:
        if self.variable not in ("Fx", "Fy", "Fz", "Mx", "My", "Mz"):
            raise InputError(f"RigidForce: variable {self.variable!r} is not Fx ... Mz")
        names = [r.name for r in sim.system.rigid]
        if self.body not in names:
            raise InputError(f"RigidForce: no rigid body {self.body!r}; rigid bodies: {names}")

    def values(self, sim, x: np.ndarray) -> np.ndarray:
        """The force or moment component after the last step (one value)."""
        self._check(sim)
        forces = sim._rigid_forces(sim._last_gradient)
        key = self.body if self.variable[0] == "F" else f"{self.body}.moment"
        if key not in forces:
            names = [r.name for r in sim.system.rigid]
            raise InputError(f"RigidForce: no rigid body {self.body!r}; rigid bodies: {names}")
        return np.array([forces[key]["xyz".index(self.variable[1])]])


@dataclass(frozen=True)
class ContactForce:
    """The force (N) obstacle ``name`` (an instrument, a probe, a table) exerts on the bodies
    through the barrier, as ``Simulation.forces()[name]``, its ``component`` (0, 1, 2; default
    all three): a function of the state and of the obstacle's place at the step's end, which
    a parameter of its motion moves (with friction, its lag held: held_friction.py)."""

    name: str
    component: int | tuple | None = None

    def _rows(self, sim):
        contact = sim.system.contact
        names = [] if contact is None else [ob.name for ob in contact.obstacles]
        if self.name not in names:
            raise InputError(
                f"ContactForce({self.name!r}): no obstacle of that name; obstacles: {names}"
            )
        comps = _components(self.component, contact.dim, f"ContactForce({self.name!r})")
        return contact, contact.slices[self.name][0], comps

    def values(self, sim, x: np.ndarray) -> np.ndarray:
        """The force's components at the state x, the obstacles where the step ended."""
        contact, _, comps = self._rows(sim)
        # the obstacles where the step ended (a parameter copy's: sensitivity.py's _sync)
        return np.asarray(contact.obstacle_forces(x)[self.name], dtype=float)[comps]

    def derivative(self, sim, x: np.ndarray, S: np.ndarray, Y: np.ndarray, friction=None,
                   copies=()):  # fmt: skip
        """(values, d values / d theta) at the converged x: the force is the barrier's (and
        the lagged friction's) gradient summed over the obstacle's vertices, so its derivative
        is their exact Hessian (over the collision vertices) applied to the vertices' motion,
        the bodies' J S and the obstacles' own Y (n_obstacle coordinates, p; their motion's
        derivative); with friction (``held_friction.py``'s step terms) less its Hessian
        applied to its slip's start's motion, plus its lag point's motion (the vertices',
        where the lag is taken as converged) and a varied coefficient's own part (the
        ``copies``' forces at the same vertices)."""
        contact, rows, comps = self._rows(sim)
        d = contact.dim
        V = contact.vertices(x)
        _, g_V, H_V = contact.vertex_terms(V, 2, False)
        if g_V is None:  # not touching: no force, and none for a small change either
            return np.zeros(len(comps)), np.zeros((len(comps), S.shape[1]))
        dV = contact.selection(x) @ S
        dV[contact.n_deformable * d :] += Y
        coords = (np.arange(V.shape[0])[rows][:, None] * d + np.asarray(comps)).T  # (k, m)
        y = np.array([g_V[c].sum() for c in coords])
        D = np.vstack([np.asarray(H_V[c].sum(axis=0)).ravel() @ dV for c in coords])
        if friction is not None:
            HW = friction.start_motion_term
            D -= np.vstack([HW[c].sum(axis=0) for c in coords])
            if friction.lag_term is not None:
                LdV = np.asarray(friction.lag_term @ dV)
                D += np.vstack([LdV[c].sum(axis=0) for c in coords])
            for j, (delta, pair) in enumerate(copies):  # at the same vertices, held lags
                g_pm = [c.system.contact.vertex_terms(V, 1, False)[1] for c in pair]
                D[:, j] += [(g_pm[0][c].sum() - g_pm[1][c].sum()) / (2 * delta) for c in coords]
        return y, D


def _rows(items, n: int, what: str, key: str, body: str) -> np.ndarray:
    rows = np.asarray(items, dtype=np.int64).ravel()
    if rows.size == 0 or rows.min() < 0 or rows.max() >= n:
        raise InputError(f"{what}: {key} must be indices 0..{n - 1} of body {body!r}")
    return rows


Observation = (Reaction | Displacement | SurfaceDistance | NodeData | ElementData
               | EnclosedVolume | RigidForce | ContactForce)  # fmt: skip


def _selection(groups: list[np.ndarray], n: int) -> sp.csr_matrix:
    rows = np.concatenate([np.full(len(r), i) for i, r in enumerate(groups)] or [[]])
    cols = np.concatenate(groups or [[]]).astype(np.int64)
    return sp.csr_matrix((np.ones(len(cols)), (rows.astype(np.int64), cols)),
                         shape=(len(groups), n))  # fmt: skip


def linearize(observation, sim, x: np.ndarray, g: np.ndarray):
    """(values (k,), X, R) of any observation at the state x with the step's gradient g."""
    if hasattr(observation, "linearize"):
        return observation.linearize(sim, x, g)
    n = sim.system.n_dofs
    xrows, grows = observation.rows(sim)
    X, R = _selection(xrows, n), _selection(grows, n)
    # the FEM bodies' configuration is their tangent DOFs, first (rigid blocks after them)
    y = X @ x[:n] + R @ g
    if isinstance(observation, Displacement):
        y = y - observation.rest(sim)
    return y, X, R
