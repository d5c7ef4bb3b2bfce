"""Barrier contact (IPC, Li et al. 2020) between the boundary surfaces of every FEM body (each
with itself, too) and the kinematic obstacles, through the IPC Toolkit (``ipctk``).

The collision mesh stacks the boundary vertices of every FEM body (their positions are rows of
the system configuration) and the obstacles' vertices (positions given by their motion at the
step's time, no unknowns). The energy is ipctk's area-weighted "physical" barrier

    B(x) = kappa * sum_k w_k b(d_k^2; dhat^2) / dhat^3,  b(s) = -(s - dhat^2)^2 ln(s / dhat^2),

over the collision pairs closer than the activation distance ``dhat`` (m); w_k are surface
areas, so kappa is a pressure (Pa): by default the largest Young's modulus of the bodies in
contact, so the barrier is as stiff as a layer of the stiffest material dhat thick. Its gradient
and PSD-projected Hessian (per collision, as IPC does) enter the same Newton system as every
other energy; the Hessian's sparsity changes with the active pairs, so it is added as a sparse
matrix (``Accumulator.extra_hessian``). Newton's line search never tries a step longer than
ipctk's CCD (additive CCD, LBVH broad phase; its default narrow phase takes a minute, see the
field notes) says is free of intersection.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from tissuesim.errors import InputError

__all__ = ["ContactModel", "ContactSettings", "ContactStats"]


@dataclass(frozen=True)
class ContactSettings:
    """dhat: activation distance (m; None: 1e-3 of the scene's bounding-box diagonal).
    stiffness: kappa (Pa; None: the largest Young's modulus of the FEM bodies)."""

    dhat: float | None = None
    stiffness: float | None = None
    friction: float = 0.0  # Coulomb coefficient mu (0: frictionless)
    eps_v: float = 1e-3  # m/s: below this sliding speed friction is smoothed (static regime)
    friction_iterations: int = 2  # Newton solves per step, the friction lagged between them
    # body name -> its contact surface: a facet set name or (k, 3) vertex indices (default:
    # the whole boundary)
    surfaces: dict = field(default_factory=dict)
    pairs: tuple = ()  # contact/pairs.py ContactPair: a pair switched off or with its own mu


@dataclass
class ContactStats:
    """Per step: seconds in candidates + barrier assembly and in CCD, the number of active
    collision pairs and the smallest surface distance (m) at the end of the step."""

    candidates_and_barrier_s: float = 0.0
    ccd_s: float = 0.0
    active: int = 0
    min_distance: float = float("inf")
    evaluations: int = 0
    ccd_calls: int = 0
    friction_solves: int = 0  # Newton solves with the friction lagged (0 without friction)


@dataclass(eq=False)
class ContactModel:
    """See the module docstring. ``bodies``: (name, Model, configuration offset, tangent
    offset) of every FEM body in the system; ``obstacles``: the Obstacle list; ``n_dofs``: the
    system's tangent DOFs."""

    bodies: list
    obstacles: list
    settings: ContactSettings
    n_dofs: int
    time: float = 0.0
    stats: ContactStats = field(default_factory=ContactStats)
    # contact/kinematic.py's augmented pattern, elimination and linear solver
    augmented_cache: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        import ipctk

        self._ipctk = ipctk
        dims = {m.mesh.dim for _, m, _, _ in self.bodies}
        if dims != {3}:
            raise InputError("contact needs 3D FEM bodies (tetrahedra); 2D contact is not built")
        from tissuesim.contact.pairs import PairTable, contact_facets

        unknown = set(self.settings.surfaces) - {name for name, *_ in self.bodies}
        if unknown:
            raise InputError(
                f"contact surfaces: no FEM body {sorted(unknown)[0]!r} (bodies: "
                f"{', '.join(name for name, *_ in self.bodies)})"
            )
        rest, faces, dofs, config, groups, self.slices = [], [], [], [], [], {}
        start = 0
        for name, model, config_offset, offset in self.bodies:
            tri = contact_facets(name, model.mesh, self.settings.surfaces.get(name))
            surface = np.unique(tri)
            local = np.full(model.mesh.n_points, -1)
            local[surface] = np.arange(surface.size)
            rest.append(model.mesh.points[surface])
            faces.append(local[tri] + start)
            dofs.append(offset + 3 * surface[:, None] + np.arange(3))
            config.append(config_offset + 3 * surface[:, None] + np.arange(3))
            groups.append(np.full(surface.size, len(groups)))
            self.slices[name] = (slice(start, start + surface.size), surface)
            start += surface.size
        self.n_deformable = start
        for ob in self.obstacles:
            rest.append(ob.rest)
            faces.append(ob.triangles + start)
            dofs.append(np.full((len(ob.rest), 3), -1))
            config.append(np.full((len(ob.rest), 3), -1))
            groups.append(np.full(len(ob.rest), len(groups)))
            self.slices[ob.name] = (slice(start, start + len(ob.rest)), None)
            start += len(ob.rest)
        self.group = np.concatenate(groups)  # collision-mesh vertex -> body / obstacle index
        self.table = PairTable(
            [name for name, *_ in self.bodies],
            self.obstacles,
            self.settings.friction,
            self.settings.pairs,
        )
        self.rest = np.vstack(rest)
        F = np.ascontiguousarray(np.vstack(faces), dtype=np.int32)
        E = ipctk.edges(F)
        self.mesh = ipctk.CollisionMesh(np.asfortranarray(self.rest), E, F)
        if self.table.filtered:
            # pairs of groups that do not collide are dropped in the broad phase (a compiled
            # filter: a Python callable deadlocks ipctk's threads and is slow)
            self.mesh.can_collide = self.table.collision_filter(ipctk, self.group, start)
        self.dofs = np.vstack(dofs).ravel()  # system tangent DOF of each mesh coordinate
        self.config_dofs = np.vstack(config).ravel()  # and its place in the configuration
        mapped = self.dofs >= 0
        self._select = sp.csr_matrix(
            (np.ones(mapped.sum()), (np.flatnonzero(mapped), self.dofs[mapped])),
            shape=(self.dofs.size, self.n_dofs),
        )
        # the obstacles' vertex coordinates as unknowns after the system's DOFs (kinematic.py)
        self.n_obstacle = int((~mapped).sum())
        aug = self.dofs.copy()
        aug[~mapped] = self.n_dofs + np.arange(self.n_obstacle)
        self._select_aug = sp.csr_matrix(
            (np.ones(aug.size), (np.arange(aug.size), aug)),
            shape=(aug.size, self.n_dofs + self.n_obstacle),
        )
        self.obstacle_state: np.ndarray | None = None  # where the obstacles are (flat), if lagged
        diag = float(np.linalg.norm(np.ptp(self.rest, axis=0)))
        self.dhat = self.settings.dhat if self.settings.dhat is not None else 1e-3 * diag
        default = max(_youngs(m.material) for _, m, _, _ in self.bodies)
        self.kappa = self.settings.stiffness if self.settings.stiffness is not None else default
        self.barrier = ipctk.BarrierPotential(self.dhat, self.kappa, True)
        self._friction = None  # (TangentialCollisions, vertices at the step's start), lagged
        self._reported_friction = None  # the last step's, for obstacle_forces
        self.broad_phase = ipctk.LBVH()
        self.ccd = ipctk.AdditiveCCD()

    # -- friction (IPC's smoothed, lagged Coulomb friction) ----------------------------------------
    @property
    def has_friction(self) -> bool:
        return self.table.has_friction

    def lag_friction(self, V_start: np.ndarray, V_lag: np.ndarray, h: float) -> int:
        """Fix the friction's normal forces and tangent bases at V_lag (the step's start, then
        each Newton solution) for displacements from V_start; returns the active pairs."""
        if not self.has_friction:
            self._friction = None
            return 0
        ipctk = self._ipctk
        col = self._collisions(V_lag)
        tangential = ipctk.TangentialCollisions()
        mu = self.table.uniform_mu
        tangential.build(self.mesh, V_lag, col, self.barrier, 0.0 if mu is None else mu)
        if mu is None:
            self._pair_friction(tangential)
        potential = ipctk.FrictionPotential(self.settings.eps_v * h)
        self._friction = (tangential, np.asfortranarray(V_start), potential)
        return len(tangential)

    def _pair_friction(self, tangential) -> None:
        """Each collision's mu from its pair of groups (the first and last vertex of a stencil
        lie on its two sides)."""
        E, F = self.mesh.edges, self.mesh.faces
        group, mu = self.group, self.table.mu
        for k in range(len(tangential)):
            c = tangential[k]
            ids = [i for i in c.vertex_ids(E, F) if i >= 0]
            value = float(mu[group[ids[0]], group[ids[-1]]])
            # the potential reads the lagged effective coefficients, set at build time
            c.mu_s = c.mu_k = c.mu_s_effective_lagged = c.mu_k_effective_lagged = value

    def clear_friction(self) -> None:
        """End of a step: the lagged friction is dropped, kept only to report its forces."""
        self._reported_friction, self._friction = self._friction, None

    def _add_friction(self, V: np.ndarray, order: int, select, value, grad, hess, project=True):
        if self._friction is None:
            return value, grad, hess
        tangential, V_start, potential = self._friction
        if len(tangential) == 0:
            return value, grad, hess
        U = np.asfortranarray(V - V_start)
        value += float(potential(tangential, self.mesh, U))
        if order >= 1:
            g = select.T @ potential.gradient(tangential, self.mesh, U)
            grad = g if grad is None else grad + g
        if order >= 2:
            method = self._ipctk.PSDProjectionMethod
            H = potential.hessian(
                tangential, self.mesh, U, method.CLAMP if project else method.NONE
            )
            Hs = (select.T @ sp.csr_matrix(H) @ select).tocsr()
            hess = Hs if hess is None else hess + Hs
        return value, grad, hess

    def reset_stats(self) -> None:
        self.stats = ContactStats()

    def describe(self) -> dict:
        return {
            "dhat_m": self.dhat,
            "stiffness_Pa": self.kappa,
            "surface_vertices": self.n_deformable,
            "obstacle_vertices": int(len(self.rest) - self.n_deformable),
            "obstacles": [ob.name for ob in self.obstacles],
            "friction": self.settings.friction,
            "surfaces": {
                k: (v if isinstance(v, str) else f"{len(v)} triangles")
                for k, v in self.settings.surfaces.items()
            },
            "pairs": self.table.describe(),
            "eps_v_m_per_s": self.settings.eps_v,
            "friction_iterations": self.settings.friction_iterations,
        }

    # -- positions ------------------------------------------------------------------------------
    def obstacle_positions(self, t: float) -> np.ndarray:
        """Every obstacle's vertices at time t, flat (n_obstacle,)."""
        if not self.obstacles:
            return np.zeros(0)
        return np.concatenate([ob.positions(t).ravel() for ob in self.obstacles])

    @property
    def moving(self) -> bool:
        """Whether any obstacle has a motion (then Newton moves them: kinematic.py)."""
        return any(ob.translation or ob.rotation for ob in self.obstacles)

    def vertices(
        self, c: np.ndarray, t: float | None = None, obstacle: np.ndarray | None = None
    ) -> np.ndarray:
        """Collision-mesh vertices (n, 3) for the system configuration c, the obstacles at
        ``obstacle`` (flat), else at time t, else where they are (``obstacle_state``, or at
        ``self.time``)."""
        V = np.empty_like(self.rest)
        mapped = self.config_dofs >= 0
        flat = V.reshape(-1)
        flat[mapped] = c[self.config_dofs[mapped]]
        if obstacle is None and t is None and self.obstacle_state is not None:
            obstacle = self.obstacle_state
        if obstacle is not None:
            flat[~mapped] = obstacle
        else:
            t = self.time if t is None else t
            for ob in self.obstacles:
                V[self.slices[ob.name][0]] = ob.positions(t)
        return np.asfortranarray(V)

    def _collisions(self, V: np.ndarray):
        col = self._ipctk.NormalCollisions()
        col.use_area_weighting = True
        col.build(self.mesh, V, self.dhat, broad_phase=self.broad_phase)
        return col

    # -- the energy -------------------------------------------------------------------------------
    def evaluate(self, c: np.ndarray, order: int, project: bool = True):
        """(value J, gradient over the system DOFs or None, Hessian sparse or None); the
        Hessian is PSD-projected per collision (as IPC does) unless ``project`` is False."""
        start = time.perf_counter()
        V = self.vertices(c)
        value, grad, hess = self._barrier_terms(V, order, project, self._select)
        value, grad, hess = self._add_friction(V, order, self._select, value, grad, hess, project)
        self.stats.candidates_and_barrier_s += time.perf_counter() - start
        return value, grad, hess

    def _barrier_terms(self, V: np.ndarray, order: int, project: bool, select):
        col = self._collisions(V)
        self.stats.evaluations += 1
        if len(col) == 0:
            return 0.0, None, None
        value = float(self.barrier(col, self.mesh, V))
        grad = hess = None
        if order >= 1:
            grad = select.T @ self.barrier.gradient(col, self.mesh, V)
        if order >= 2:
            method = self._ipctk.PSDProjectionMethod
            H = self.barrier.hessian(col, self.mesh, V, method.CLAMP if project else method.NONE)
            hess = (select.T @ sp.csr_matrix(H) @ select).tocsr()
        return value, grad, hess

    def evaluate_augmented(self, c: np.ndarray, y: np.ndarray, order: int, project: bool = True):
        """As ``evaluate``, with the obstacles at y (flat) and their coordinates as unknowns
        after the system's: gradient (n_dofs + n_obstacle,), Hessian over the same."""
        start = time.perf_counter()
        V = self.vertices(c, obstacle=y)
        value, grad, hess = self._barrier_terms(V, order, project, self._select_aug)
        sel = self._select_aug
        value, grad, hess = self._add_friction(V, order, sel, value, grad, hess, project)
        self.stats.candidates_and_barrier_s += time.perf_counter() - start
        return value, grad, hess

    def max_step(
        self,
        c0: np.ndarray,
        c1: np.ndarray,
        y0: np.ndarray | None = None,
        y1: np.ndarray | None = None,
    ) -> float:
        """The largest fraction of the straight move c0 -> c1 (obstacles y0 -> y1, or where
        they are) free of intersection (CCD)."""
        start = time.perf_counter()
        step = self._ipctk.compute_collision_free_stepsize(
            self.mesh,
            self.vertices(c0, obstacle=y0),
            self.vertices(c1, obstacle=y1),
            broad_phase=self.broad_phase,
            narrow_phase_ccd=self.ccd,
        )
        self.stats.ccd_s += time.perf_counter() - start
        self.stats.ccd_calls += 1
        return float(step)

    def reachable(self, c0: np.ndarray, t0: float, c1: np.ndarray, t1: float) -> bool:
        """Whether the straight move from (c0, obstacles at t0) to (c1, obstacles at t1) is
        free of intersection: the start of a step's Newton solve must be reached so."""
        start = time.perf_counter()
        free = self._ipctk.is_step_collision_free(
            self.mesh,
            self.vertices(c0, t0),
            self.vertices(c1, t1),
            broad_phase=self.broad_phase,
            narrow_phase_ccd=self.ccd,
        )
        self.stats.ccd_s += time.perf_counter() - start
        return bool(free)

    def intersecting(self, c: np.ndarray, t: float | None = None) -> bool:
        return bool(self._ipctk.has_intersections(self.mesh, self.vertices(c, t)))

    def proximity(self, c: np.ndarray) -> tuple[float, int]:
        """(the smallest distance (m) between surface elements within dhat, inf if none; the
        number of collision pairs within dhat), from one collision build."""
        V = self.vertices(c)
        col = self._collisions(V)
        if len(col) == 0:
            return float("inf"), 0
        return float(np.sqrt(col.compute_minimum_distance(self.mesh, V))), len(col)

    def min_distance(self, c: np.ndarray) -> float:
        return self.proximity(c)[0]

    def indentation_depths(self) -> dict[str, float]:
        """Per sphere or plane obstacle, how deep (m) it reaches below the bodies' rest
        surfaces at the current time (``Obstacle.indentation_depth``)."""
        rest = self.rest[: self.n_deformable]
        out = {}
        for ob in self.obstacles:
            depth = ob.indentation_depth(rest, self.time)
            if depth is not None:
                out[ob.name] = depth
        return out

    def obstacle_forces(self, c: np.ndarray) -> dict[str, np.ndarray]:
        """Force (N, 3-vector) each obstacle exerts on the bodies, as ``name``, and with
        friction its parts ``name.normal`` (the barrier's gradient with respect to the
        obstacle's vertices, summed: the bodies' side is its negative) and ``name.friction``
        (the last step's lagged friction potential's, likewise)."""
        V = self.vertices(c)
        col = self._collisions(V)
        normal = (
            self.barrier.gradient(col, self.mesh, V).reshape(-1, 3)
            if len(col)
            else np.zeros_like(V)
        )
        friction = None
        state = self._friction or self._reported_friction
        if self.has_friction and state is not None and len(state[0]):
            tangential, V_start, potential = state
            U = np.asfortranarray(V - V_start)
            friction = potential.gradient(tangential, self.mesh, U).reshape(-1, 3)
        out = {}
        for ob in self.obstacles:
            rows = self.slices[ob.name][0]
            n = normal[rows].sum(axis=0)
            f = np.zeros(3) if friction is None else friction[rows].sum(axis=0)
            out[ob.name] = n + f
            if self.has_friction:
                out[f"{ob.name}.normal"] = n
                out[f"{ob.name}.friction"] = f
        return out


def _youngs(material) -> float:
    """Young's modulus E = mu (3 lambda + 2 mu) / (lambda + mu) of a material (Pa)."""
    mu, lam = float(material.mu), float(material.lam)
    return mu * (3 * lam + 2 * mu) / (lam + mu)
