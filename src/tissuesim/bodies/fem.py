"""A finite-element body of a Simulation: a mesh of one material or of several regions
(``bodies/regions.py``: cells of one material and formulation each, sharing the body's
vertices), its prescribed vertex sets (supports, prescribed motions, graspers), loads and
initial velocity.

The body owns its ``Model`` (kinematics, mass, pattern, elimination) from the moment it is
added, so set-up calls check their arguments at once. Every prescribed set and grasper has a
name under which its force is reported per step: the reaction sum over the set's vertices of
the step's final gradient dPhi/dx (the force the constraint applies to the body; it includes
the set's own inertia under Backward Euler), or for a spring grasper the springs' pull.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import numpy as np

from tissuesim.bodies.couplings import VertexCouplings
from tissuesim.bodies.fem_output import FemOutput
from tissuesim.bodies.graspers import Grasper, Motion, _vector, vertex_indices
from tissuesim.constraints.dirichlet import DirichletCondition, constant_displacement
from tissuesim.energies.loads import (
    BodyForce,
    ExternalForce,
    Gravity,
    NodalForces,
    Traction,
    as_field,
)
from tissuesim.energies.mass import Inertia, MassKind
from tissuesim.energies.vertex_springs import VertexSprings
from tissuesim.errors import InputError
from tissuesim.materials.base import Material
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.rows import rows_all
from tissuesim.model import Model
from tissuesim.time.phases import check_window, in_window
from tissuesim.validate import indices, short, vector

__all__ = ["FemBody", "Grasper", "vertex_indices"]


class FemBody(VertexCouplings, FemOutput):
    """See the module docstring. Created by ``Simulation.add_body``; ``claim_name`` checks a
    force name is new across the simulation."""

    kind = "fem"

    def __init__(
        self,
        name: str,
        mesh: Mesh,
        material: Material | None,
        *,
        density: float | np.ndarray,
        mass: MassKind,
        backend: str,
        claim_name: Callable[[str], str],
        changed: Callable[[], None],
        formulation: str = "displacement",
        regions=None,
    ) -> None:
        self.name = name
        specs = None
        if regions is not None:
            from tissuesim.bodies.regions import region_specs

            specs = region_specs(name, mesh, material, regions, formulation, density)
            if specs is None:  # one region of every cell: the plain model
                ((_, only),) = regions.items()
                material = only[1] if isinstance(only, tuple) else only.material
            else:
                material = specs[0][2]
        self.model = Model(
            mesh, material, density, mass, backend=backend, formulation=formulation, regions=specs
        )
        self._claim, self._changed = claim_name, changed
        self.conditions: list[tuple[str, DirichletCondition]] = []
        self.windows: dict[str, tuple[float, float]] = {}  # name -> (t0, t1]: when it holds
        self._condition_time: tuple[float, float] | None = None  # (step end, tolerance)
        self.graspers: list[Grasper] = []
        self.spring_graspers: list[tuple[Grasper, VertexSprings]] = []
        self.pressures: list = []  # energies/pressure.py FollowerPressure
        self.springs: list = []  # energies/node_springs.py NodeSprings
        self.linear_constraints: list = []  # constraints/linear.py LinearConstraint
        self.velocity = np.zeros(self.model.n_dofs)

    def __repr__(self) -> str:
        return f"FemBody({self.name!r}, {self.mesh!r})"

    _links_pending = False  # couplings added since the model was made (``_relink``)

    @property
    def model(self) -> Model:
        """The body's element model (made again first if couplings were added since)."""
        if self._links_pending:
            self._links_pending = False
            self._model = self._linked_model(self._model)
        return self._model

    @model.setter
    def model(self, model: Model) -> None:
        self._model, self._links_pending = model, False

    @property
    def mesh(self) -> Mesh:
        return self._model.mesh  # a relink keeps the mesh

    @property
    def dim(self) -> int:
        return self.mesh.dim

    # -- prescribed sets and graspers -----------------------------------------------------------
    def active_conditions(self) -> list[tuple[str, DirichletCondition]]:
        """The conditions that hold for the coming step (all, before the first one)."""
        if self._condition_time is None:
            return list(self.conditions)
        t_end, tol = self._condition_time
        return [(n, c) for n, c in self.conditions if in_window(self.windows.get(n), t_end, tol)]

    def _set_conditions(self) -> None:
        self.model.set_conditions([c for _, c in self.active_conditions()])
        self._changed()

    def set_condition_time(self, t_end: float, tol: float) -> None:
        """Hold the conditions whose ``active`` window takes the step that ends at t_end; the
        system is rebuilt only when that set changes (a vertex let go moves on from where it
        is, one taken keeps its prescribed value from then on)."""
        before = [n for n, _ in self.active_conditions()]
        self._condition_time = (t_end, tol)
        if [n for n, _ in self.active_conditions()] != before:
            self._set_conditions()

    def add_dirichlet(
        self,
        vertices,
        displacement: Sequence[float] | Callable[[np.ndarray, float], np.ndarray] | None = None,
        components: Sequence[int] | None = None,
        *,
        name: str | None = None,
        active: tuple[float, float] | None = None,
    ) -> str:
        """Prescribe u = g(X, t) (m) on ``vertices``: None clamps, a vector is constant, a
        callable maps rest positions (k, d) and time to displacements (k, d). ``components``
        restricts the condition to some axes (e.g. (0,) for x only). ``active`` (t0, t1) s:
        the condition holds only for the steps that end after t0 and by t1 (None: always).
        Returns the name its reaction force is reported under (default
        "<body>.dirichlet_<k>")."""
        default = f"{self.name}.dirichlet_{len(self.conditions)}"
        window = check_window(active, f"add_dirichlet {name or default!r}")
        return self._prescribe(vertices, displacement, components, name, default, window)

    def _prescribe(
        self,
        vertices,
        displacement,
        components,
        name,
        default: str,
        window=None,
        call: str = "add_dirichlet",
    ) -> str:
        v = vertex_indices(vertices, self.mesh.n_points, call)  # errors name the call made
        if displacement is None:
            displacement = np.zeros(self.dim)
        g = displacement if callable(displacement) else constant_displacement(displacement)
        comps = None
        if components is not None:
            arr = np.asarray(components)
            if arr.dtype == bool or not np.issubdtype(arr.dtype, np.integer) or arr.ndim != 1:
                raise InputError(
                    "add_dirichlet: components must be a sequence of integer axes, e.g. (0,), "
                    f"not {short(components)}"
                )
            comps = tuple(int(c) for c in arr)
            if not comps or min(comps) < 0 or max(comps) >= self.dim:
                raise InputError(
                    f"add_dirichlet: components must be axes in 0..{self.dim - 1}, "
                    f"not {short(components)}"
                )
        name = self._claim(name, default)
        self.conditions.append((name, DirichletCondition(v, g, comps, repr(name))))
        if window is not None:
            self.windows[name] = window
        self._set_conditions()
        return name

    def fix(self, vertices, name: str | None = None) -> str:
        """Clamp ``vertices`` (a support); its reaction is reported as ``name`` (default
        "<body>.support")."""
        return self._prescribe(vertices, None, None, name, f"{self.name}.support", call="fix")

    def grasp(
        self,
        vertices,
        displacement: Motion | Sequence[float],
        *,
        stiffness: float | None = None,
        name: str | None = None,
        release: float | None = None,
    ) -> Grasper:
        """Retract: move ``vertices`` by ``displacement(t)`` (d,) m (a callable or a constant
        vector). stiffness None prescribes the motion; a number (N/m per vertex) pulls through
        springs to the moving targets. The grasper's force is reported per step until it lets
        go at time ``release`` (s; None: never): from the first step that starts at or after it,
        its vertices are free."""
        # a grasper without a name yet (it gets one below) is "grasp", not "grasper None"
        who = "grasp" if name is None else f"grasper {name!r}"
        v = vertex_indices(vertices, self.mesh.n_points, who)
        if not callable(displacement):
            const = _vector(displacement, self.dim, f"{who} displacement")
            displacement = functools.partial(lambda c, t: c, const)
        _vector(displacement(0.0), self.dim, f"{who} displacement at t = 0")
        if stiffness is not None and not (np.isfinite(stiffness) and stiffness > 0):
            raise InputError(f"{who}: stiffness must be > 0 N/m, got {short(stiffness)}")
        if stiffness is not None and self.dim != 3:
            raise InputError(f"{who}: spring graspers need a 3D body")
        if release is not None:
            from tissuesim.validate import real

            release = real(release, f"{who} release", unit="s")
        name = self._claim(name, "grasper")
        g = Grasper(name, self.name, v, displacement, stiffness, release)
        self.graspers.append(g)
        if stiffness is None:
            motion = functools.partial(
                lambda d, dim, X, t: np.broadcast_to(_vector(d(t), dim, "grasper motion"), X.shape),
                displacement,
                self.dim,
            )
            self.conditions.append((name, DirichletCondition(v, motion, name=repr(name))))
            self._set_conditions()
        else:
            self.spring_graspers.append((g, g.springs(self.mesh.points)))
            self._changed()
        return g

    def release_graspers(self, t: float) -> list[str]:
        """Let go of every grasper whose release time is at or before t; their names."""
        done = [g for g in self.graspers if g.release is not None and g.release <= t]
        if not done:
            return []
        names = {g.name for g in done}
        self.graspers = [g for g in self.graspers if g.name not in names]
        self.spring_graspers = [(g, sp) for g, sp in self.spring_graspers if g.name not in names]
        self.conditions = [(n, c) for n, c in self.conditions if n not in names]
        self._set_conditions()
        return sorted(names)

    # -- loads -----------------------------------------------------------------------------------
    def add_traction(self, facets, traction) -> None:
        """Dead traction (N/m in 2D, Pa in 3D) on boundary facets (k, d) (hexahedra: quad
        faces (k, 4); wedges: rows of 4 or their triangles (k, 3)): a vector or a callable
        (X (k, d), t) -> (k, d) evaluated at the facets' vertices."""
        ids = indices(facets, "add_traction: facets", self.mesh.n_points)
        width = self.mesh.facet_nodes  # d; 4 for the quad faces of hexahedra
        facets = ids.reshape(np.shape(facets)) if ids.size else ids.reshape(0, width)
        if self.mesh.cell_type == "wedge" and facets.ndim == 2 and facets.shape[1] == 3:
            from tissuesim.mesh.cells.wedge import as_facets

            facets = as_facets(facets)  # a wedge's triangle faces, as its facet rows hold them
        if facets.ndim != 2 or facets.shape[1] != width:
            raise InputError(f"add_traction: facets must be (k, {width}) vertex indices")
        if self.mesh.order == 2 and facets.size:
            from tissuesim.mesh.cells.quadratic import quadratic_facets

            missing = (quadratic_facets(self.mesh, facets) < 0).any(axis=1)
            if missing.any():
                raise InputError(
                    f"add_traction: facet {facets[missing][0].tolist()} of body {self.name!r} is "
                    "not an edge/face of its quadratic elements; give boundary facets by their "
                    "corner vertices (mesh.facet_sets, facets_where)"
                )
        field = as_field(traction, "add_traction: traction (N/m or Pa)", self.dim)
        self.model.loads.append(Traction(facets, field))

    def add_follower_pressure(self, facets, pressure, name: str) -> None:
        """A follower pressure p (Pa; a number or a callable t -> p) on boundary facets of this
        3D body (P1 triangles (k, 3), Q1 or hexahedron20 quad faces (k, 4)): an energy on a
        closed surface of triangles, lagged on any other (``energies/pressure.py``,
        ``pressure_lag.py``)."""
        from tissuesim.energies.pressure import follower_pressure

        self.pressures.append(follower_pressure(self.mesh, facets, pressure, name, self.name))

    def add_gravity(self, acceleration: Sequence[float]) -> None:
        """Gravity, acceleration (d,) in m/s^2, acting on the element densities."""
        g = vector(acceleration, "add_gravity: acceleration", self.dim, unit="m/s^2")
        self.model.loads.append(Gravity(g))

    def add_body_force(self, force_density) -> None:
        """Body force per unit rest volume (N/m^3): a vector or a callable (X (n, d), t)."""
        field = as_field(force_density, "add_body_force: force_density (N/m^3)", self.dim)
        self.model.loads.append(BodyForce(field))

    def add_nodal_forces(self, vertices, force) -> None:
        """Dead point forces (N) on ``vertices``: a vector (d,) or (k, d) per vertex, or a
        callable t -> (k, d)."""
        v = vertex_indices(vertices, self.mesh.n_points, "add_nodal_forces", unique=False)
        if callable(force):
            fn = force
        else:
            f = np.asarray(force, dtype=float)
            if f.shape not in ((self.dim,), (v.size, self.dim)) or not np.all(np.isfinite(f)):
                raise InputError(
                    f"add_nodal_forces: force must be {self.dim} finite numbers or "
                    f"({v.size}, {self.dim}) of them (N), got shape {f.shape}"
                )
            fn = functools.partial(lambda c, t: c, f)
        fn_check = np.asarray(fn(0.0), dtype=float)
        if fn_check.shape not in ((self.dim,), (v.size, self.dim)):
            raise InputError(f"add_nodal_forces: force(t) must give ({v.size}, {self.dim})")
        self.model.loads.append(NodalForces(v, fn))

    def set_velocity(self, velocity) -> None:
        """Initial velocity (n, d) or a constant vector (d,), m/s."""
        try:
            v = np.asarray(velocity, dtype=float)
        except (TypeError, ValueError):
            given = short(velocity)
            raise InputError(f"set_velocity: velocities must be numbers, not {given}") from None
        try:
            v = np.broadcast_to(v, self.mesh.points.shape)
        except ValueError:
            raise InputError(
                f"set_velocity: body {self.name!r} needs ({self.mesh.n_points}, {self.dim}) or "
                f"({self.dim},) velocities, got shape {v.shape}"
            ) from None
        if not np.all(np.isfinite(v)):
            raise InputError("set_velocity: velocities must be finite")
        self.velocity = v.ravel().copy()
        self._changed("velocity")

    # -- cutting (mesh/cutting/virtual_nodes.py) ---------------------------------------------------
    def apply_cut(self, cut, carry: np.ndarray, state) -> None:
        """Take the mesh of a virtual-node cut (``VirtualNodeMesh`` of the original mesh of
        ``state``, a ``bodies.cut_state.CutState``): a new model on it (the copies' densities,
        shape gradients and rest volumes their parents', the same loads), every support and
        grasper on all copies of its vertices that lie in material (not on virtual nodes);
        ``carry`` (new n_points,) the current node each new one continues, kept as
        ``pending_origin`` for the simulation (positions and velocities)."""
        old = self.model
        if old.parts is not None:
            raise InputError(
                f"body {self.name!r} has several regions: it cannot be cut or torn (yet)"
            )
        if self.springs or self.linear_constraints:
            raise InputError(
                f"body {self.name!r} has discrete springs or linear constraints: it cannot be cut"
            )
        mesh = cut.to_mesh(state.original)
        rest = None if state.rest is None else tuple(a[cut.parent] for a in state.rest)
        same, src = None, state.source
        if src is not None and old.mesh.order == 1:  # cells the cut left as they were
            equal = rows_all(cut.cells == old.mesh.cells[np.maximum(src, 0)])
            same = np.where((src >= 0) & equal, src, -1)
        model = Model(
            mesh,
            old.material,
            state.density[cut.parent],
            old.mass_kind,
            backend=old.backend,
            formulation=old.formulation,
            rest=rest,
            renew=None if same is None else (old.pattern, old.mesh.cells, same),
        )
        model.loads = list(old.loads)  # nodal loads and tractions keep each node's first copy
        model.damping = old.damping  # Rayleigh's, per body (it was lost at the first cut)

        material = cut.material_nodes  # a virtual node is held by nothing

        def copies(vertices: np.ndarray) -> np.ndarray:
            return np.flatnonzero(np.isin(carry, vertices) & material)

        self.conditions = [
            (name, DirichletCondition(copies(c.vertices), c.displacement, c.components, c.name))
            for name, c in self.conditions
        ]
        graspers = []
        for g in self.graspers:
            graspers.append(
                Grasper(g.name, g.body, copies(g.vertices), g.displacement, g.stiffness, g.release)
            )
        self.graspers = graspers
        self.spring_graspers = [
            (g, g.springs(mesh.points)) for g in graspers if g.stiffness is not None
        ]
        self.velocity = self.velocity.reshape(-1, self.dim)[carry].ravel()
        self.model = model
        self.pending_origin = carry
        self._set_conditions()

    def restore_cut(self, state, held: dict[str, np.ndarray], velocity: np.ndarray) -> None:
        """Take a checkpoint's cut (``io/checkpoints/cuts.py``): ``state`` (a ``CutState``
        with its current cut) as this body's, the model made on its cut mesh afresh (the pattern
        a cut renews equals it entry for entry), every support and grasper on the vertices it
        held (``held``, by name), and ``velocity``."""
        source, state.source = state.source, None  # no pattern to renew it from
        self.apply_cut(state.vn, state.vn.origin, state)
        state.source = source
        self.cut_state, self.pending_origin, self.velocity = state, None, velocity
        self.conditions = [
            (n, DirichletCondition(held[n], c.displacement, c.components, c.name))
            for n, c in self.conditions
        ]
        self.graspers = [
            Grasper(g.name, g.body, held[g.name], g.displacement, g.stiffness, g.release)
            for g in self.graspers
        ]
        self.spring_graspers = [
            (g, g.springs(self.mesh.points)) for g in self.graspers if g.stiffness is not None
        ]
        self._set_conditions()

    pending_origin: np.ndarray | None = None  # set by apply_cut, taken by the next rebuild
    cut_state = None  # bodies/cut_state.CutState once the body is cut

    # -- what the system and the output ask of a body -------------------------------------------
    def step_energies(self, t: float, x_pred: np.ndarray | None, h: float) -> list:
        """Inertia (when x_pred is given), the dead loads at t and the spring graspers."""
        energies = [] if x_pred is None else [Inertia(self.model.mass, x_pred, h)]
        energies.append(ExternalForce(self.model.external_force(t)))
        energies += [s.energy(t) for _, s in self.spring_graspers]
        energies += [p.energy(t) for p in self.pressures]
        energies += [c.energy(t) for c in self.linear_constraints]
        return energies + [s.at(t) for s in self.springs]

    def reaction_owners(self) -> np.ndarray:
        """(vertices, d): the index in ``conditions`` of the active condition whose reaction
        holds each DOF (-1: none); a DOF prescribed by several sets counts for the last."""
        d = self.dim
        owner = np.full((self.mesh.n_points, d), -1)
        active = {n for n, _ in self.active_conditions()}
        for k, (name, c) in enumerate(self.conditions):
            if name in active:
                comps = range(d) if c.components is None else list(c.components)
                owner[np.ix_(np.asarray(c.vertices), comps)] = k
        return owner

    def forces(self, x: np.ndarray, gradient: np.ndarray | None, t: float) -> dict:
        """Force (N, 3-vector) every prescribed set and grasper applies to the body: a set's
        reaction sums the gradient over the DOFs it prescribes (only its ``components``); a DOF
        prescribed by several sets counts for the last of them, as its value does."""
        d = self.dim
        out = {}
        owner = self.reaction_owners()
        active = {n for n, _ in self.active_conditions()}
        for k, (name, c) in enumerate(self.conditions):
            f = np.zeros(3)  # a condition out of its window holds nothing
            if gradient is not None and name in active:
                g = gradient.reshape(-1, d)[c.vertices]
                f[:d] = np.where(owner[c.vertices] == k, g, 0.0).sum(axis=0)
            out[name] = f.tolist()
        for g, springs in self.spring_graspers:
            f = np.zeros(3)
            f[:d] = springs.stiffness * (
                springs.targets(t)[:, :d] - x.reshape(-1, d)[g.vertices]
            ).sum(axis=0)
            out[g.name] = f.tolist()
        return out
