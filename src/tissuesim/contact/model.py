"""Barrier contact (IPC, Li et al. 2020) between the surfaces of the bodies (each with itself,
too) and the kinematic obstacles, through the IPC Toolkit (``ipctk``).

The collision mesh stacks every body's contact surface (contact/geometry/surfaces.py: a FEM body's
boundary vertices are rows of the system configuration; a frame body's embedded surface moves
with its frames, mapped to frame DOFs with the chain rule) and the obstacles' vertices
(positions given by their motion at the step's time, no unknowns). Energies are evaluated over
the vertices and mapped to the system's DOFs by the surfaces' Jacobians. The energy is
ipctk's area-weighted "physical" barrier

    B(x) = kappa * sum_k w_k b(d_k^2; dhat^2) / dhat^3,  b(s) = -(s - dhat^2)^2 ln(s / dhat^2),

over the collision pairs closer than the activation distance ``dhat`` (m); w_k are surface
areas, so kappa is a pressure (Pa): by default the largest Young's modulus of the bodies in
contact, so the barrier is as stiff as a layer of the stiffest material dhat thick. Its gradient
and PSD-projected Hessian (per collision, as IPC does) enter the same Newton system as every
other energy; the Hessian's sparsity changes with the active pairs, so it is added as a sparse
matrix (``Accumulator.extra_hessian``). Newton's line search never tries a step longer than
ipctk's CCD (additive CCD, LBVH broad phase; its default narrow phase takes a minute, see the
field notes) says is free of intersection; when rigid frames are in contact (their points
move on arcs, not on CCD's straight lines) every trial is also checked (``path_free``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from tissuesim.contact.barrier.candidates import StepCandidates
from tissuesim.contact.barrier.ccd_queries import CollisionQueries
from tissuesim.contact.barrier.forces import ContactForces
from tissuesim.contact.barrier.friction_lag import FrictionLag
from tissuesim.contact.barrier.stiffness import AdaptiveStiffness
from tissuesim.contact.cut.sliver_points import weigh_points
from tissuesim.contact.geometry.edges import triangle_edges
from tissuesim.contact.geometry.surfaces import CutFemSurface, FemSurface
from tissuesim.errors import InputError

__all__ = ["ContactModel", "ContactSettings", "ContactStats"]


@dataclass(frozen=True)
class ContactSettings:
    """dhat: activation distance (m; None: 1e-3 of the scene's bounding-box diagonal).
    stiffness: kappa (Pa, fixed) or None / "adaptive": IPC's adaptive kappa, starting at the
    largest Young's modulus E of the bodies in contact, within [E, 100 E]
    (contact/barrier/stiffness.py)."""

    dhat: float | None = None
    stiffness: float | str | None = None
    friction: float = 0.0  # Coulomb coefficient mu (0: frictionless)
    eps_v: float = 1e-3  # m/s: below this sliding speed friction is smoothed (static regime)
    friction_iterations: int = 2  # Newton solves per step, the friction lagged between them
    # body name -> its contact surface: a facet set name or (k, 3) vertex indices (default:
    # the whole boundary)
    surfaces: dict = field(default_factory=dict)
    # contact/pairs.py ContactPair: a pair switched off or with its own mu
    pairs: tuple = ()
    # how a step treats contact (time/contact_step.py): "auto" (the barrier, interactive under
    # a budget), "accurate" (the barrier's Newton from the predicted contacts), "interactive"
    # (the certified prediction is the step), "barrier" (the barrier's Newton alone)
    mode: str = "auto"


@dataclass
class ContactStats:
    """Per step: seconds in candidates + barrier assembly (and in candidates alone) and in
    CCD, the number of active collision pairs and the smallest surface distance (m) at the end
    of the step."""

    candidates_and_barrier_s: float = 0.0
    candidates_s: float = 0.0  # of which building the collision set (broad + narrow phase)
    ccd_s: float = 0.0
    active: int = 0
    min_distance: float = float("inf")
    evaluations: int = 0
    ccd_calls: int = 0
    friction_solves: int = 0  # Newton solves with the friction lagged (0 without friction)
    candidate_builds: int = 0  # candidate sets built (once per step unless a vertex left it)


@dataclass(eq=False)
class ContactModel(FrictionLag, CollisionQueries, ContactForces):
    """See the module docstring. ``surfaces``: every body's contact surface
    (``contact/geometry/surfaces.py``: FEM boundaries, frame bodies' embedded surfaces);
    ``obstacles``: the Obstacle list; ``n_dofs``: the system's tangent DOFs."""

    surfaces: list
    obstacles: list
    settings: ContactSettings
    n_dofs: int
    time: float = 0.0
    stats: ContactStats = field(default_factory=ContactStats)
    # contact/barrier/kinematic.py's augmented pattern, elimination and linear solver
    augmented_cache: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        import ipctk

        self._ipctk = ipctk
        _set_contact_threads(ipctk)
        if not self.surfaces:
            raise InputError("contact needs at least one body with a surface")
        from tissuesim.contact.pairs import PairTable

        dims = {surface.dim for surface in self.surfaces}
        if len(dims) != 1:
            raise InputError("contact: the bodies in contact must all be 2D or all be 3D")
        self.dim = dims.pop()
        if self.dim == 2 and self.obstacles:
            raise InputError(
                "contact in 2D: obstacles are not built (they are 3D surfaces); model the "
                "obstacle as a 2D body with prescribed motion"
            )
        rest, faces, groups, self.slices = [], [], [], {}
        start = 0
        for surface in self.surfaces:
            k = len(surface.rest)
            rest.append(surface.rest)
            faces.append(surface.triangles + start)
            groups.append(np.full(k, len(groups)))
            self.slices[surface.name] = (slice(start, start + k), surface)
            start += k
        self.n_deformable = start
        for ob in self.obstacles:
            rest.append(ob.rest)
            faces.append(ob.triangles + start)
            groups.append(np.full(len(ob.rest), len(groups)))
            self.slices[ob.name] = (slice(start, start + len(ob.rest)), None)
            start += len(ob.rest)
        self.group = np.concatenate(groups)  # collision-mesh vertex -> body / obstacle index
        # the areas of contact points without faces (slivers of cut bodies), NaN elsewhere
        self.point_areas = None
        if any(getattr(s, "point_areas", None) is not None for s in self.surfaces):
            self.point_areas = np.full(start, np.nan)  # start: every vertex by now
            for surface in self.surfaces:
                if getattr(surface, "point_areas", None) is not None:
                    self.point_areas[self.slices[surface.name][0]] = surface.point_areas
        self.table = PairTable(
            [s.name for s in self.surfaces],
            self.obstacles,
            self.settings.friction,
            self.settings.pairs,
        )
        self.rest = np.vstack(rest)
        facets = np.ascontiguousarray(np.vstack(faces), dtype=np.int32)
        if self.dim == 3:
            F, E = facets, triangle_edges(ipctk, facets)
        else:  # 2D: the boundary edges, no faces (point-edge and edge-edge contact)
            F, E = np.zeros((0, 3), dtype=np.int32), facets
        self.mesh = ipctk.CollisionMesh(np.asfortranarray(self.rest), E, F)
        if self.table.filtered:
            # pairs of groups that do not collide are dropped in the broad phase (a compiled
            # filter: a Python callable deadlocks ipctk's threads and is slow)
            self.mesh.can_collide = self.table.collision_filter(ipctk, self.group, start)
        # the obstacles' vertex coordinates as unknowns after the system's DOFs (kinematic.py)
        self.n_obstacle = self.dim * (start - self.n_deformable)
        # rigid frames move points on arcs: line-search trials are checked by CCD (surfaces.py)
        self.linear = all(s.linear for s in self.surfaces)
        # dV/dq is constant (kept per augmented flag) when every surface is a FEM body's
        self._constant = all(isinstance(s, FemSurface | CutFemSurface) for s in self.surfaces)
        self._constant_selection: dict = {}
        self.obstacle_state: np.ndarray | None = None  # where the obstacles are (flat), if lagged
        # c -> a step's start with the kerf ahead of each blade in contact opened, or None
        # (set by the simulation when a blade cuts a body it touches: blade_clearance.py)
        self.clear_path = None
        diag = float(np.linalg.norm(np.ptp(self.rest, axis=0)))
        self.dhat = self.settings.dhat if self.settings.dhat is not None else 1e-3 * diag
        self._leave_out_rest_pairs(ipctk)
        default = max(_youngs(s.material) for s in self.surfaces)
        self.adaptive = None  # contact/barrier/stiffness.py, unless a fixed stiffness is given
        if self.settings.stiffness in (None, "adaptive"):
            self.adaptive = AdaptiveStiffness(default, diag)
        fixed = isinstance(self.settings.stiffness, float)
        self.set_stiffness(self.settings.stiffness if fixed else default)
        self._friction = None  # (TangentialCollisions, vertices at the step's start), lagged
        self._reported_friction = None  # the last step's, for obstacle_forces
        self._friction_lag_at = None  # the vertices the friction was last lagged at
        self.broad_phase = ipctk.LBVH()
        self._last_collisions = None  # (V, its collision set): see _collisions
        self.ccd = ipctk.AdditiveCCD()
        self.candidates = StepCandidates(ipctk, self.mesh, self.broad_phase, self.dhat, self.stats)
        self.predictor = None  # contact/predict/predictor.py ContactPredictor, made when used
        self.predicted_forces = None  # (x, Prediction) of an interactive step, for the report
        self.prediction_report: dict | None = None  # the step's predictor figures

    def carry_over(self, old: ContactModel) -> None:
        """Continue ``old``'s state after the system was rebuilt (a cut changes a body's
        surface): the obstacles where they are, the barrier's stiffness and its adaptation,
        the time. Friction is lagged afresh at the next step's start."""
        self.obstacle_state = old.obstacle_state
        self.time = old.time
        if old.adaptive is not None and self.adaptive is not None:
            self.adaptive = old.adaptive
        self.set_stiffness(old.kappa)

    # -- the barrier's stiffness (fixed, or IPC's adaptive one: contact/barrier/stiffness.py) --
    def set_stiffness(self, kappa: float) -> None:
        self.kappa = float(kappa)
        self.barrier = self._ipctk.BarrierPotential(self.dhat, self.kappa, True)

    def initialize_stiffness(
        self, c: np.ndarray, g_energy: np.ndarray, held: np.ndarray, obstacle=None
    ) -> None:
        """Adaptive stiffness: once contact appears at a step's start c, kappa balances the
        other energies' gradient ``g_energy`` (system DOFs; ``held`` DOFs left out)."""
        if self.adaptive is None or self.adaptive.initialized:
            return
        V = self.vertices(c, obstacle=obstacle)
        col = self._collisions(V)
        if len(col) == 0:
            return
        g_B = self.selection(c).T @ self.barrier.gradient(col, self.mesh, V) / self.kappa
        free = np.ones(self.n_dofs, dtype=bool)
        free[held] = False
        self.set_stiffness(self.adaptive.initial(g_energy[free], g_B[free]))

    def update_stiffness(self, c: np.ndarray) -> None:
        """Adaptive stiffness, after a step: double kappa if the gap keeps closing below
        round-off scale (IPC). ``step_kappa`` keeps the one the step was solved with (the
        derivatives of a run take it: identification/sensitivity.py)."""
        self.step_kappa = self.kappa
        if self.adaptive is None or not self.adaptive.initialized:
            return
        kappa = self.adaptive.update(self.kappa, self.proximity(c)[0])
        if kappa != self.kappa:
            self.set_stiffness(kappa)

    # -- the map from the system's DOFs to the collision vertices (surfaces.py) ------------------
    def selection(self, c: np.ndarray, augmented: bool = False) -> sp.csr_matrix:
        """dV/dq (d n_vertices, n_dofs [+ n_obstacle]): the bodies' Jacobians, and with
        ``augmented`` the identity on the obstacles' coordinates (unknowns after the system's);
        constant (kept) when every surface is a FEM body's."""
        if self._constant and augmented in self._constant_selection:
            return self._constant_selection[augmented]
        rows, cols, vals = [], [], []
        for surface in self.surfaces:
            r, cc, v = surface.jacobian(c)
            rows.append(r + self.dim * self.slices[surface.name][0].start)
            cols.append(cc)
            vals.append(v)
        n_cols = self.n_dofs
        if augmented:
            rows.append(self.dim * self.n_deformable + np.arange(self.n_obstacle))
            cols.append(self.n_dofs + np.arange(self.n_obstacle))
            vals.append(np.ones(self.n_obstacle))
            n_cols += self.n_obstacle
        S = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.dim * len(self.rest), n_cols),
        )
        if self._constant:
            self._constant_selection[augmented] = S
        return S

    def _to_dofs(self, c, order, g_V, H_V, augmented):
        """(gradient, Hessian) over the system's DOFs from those over the vertices: J^T g and
        J^T H J + the rigid frames' curvature (surfaces.py)."""
        if g_V is None:
            return None, None
        S = self.selection(c, augmented)
        grad = S.T @ g_V
        hess = None
        if order >= 2:
            hess = (S.T @ H_V @ S).tocsr()
            rows, cols, vals = [], [], []
            for surface in self.surfaces:
                g_surface = g_V.reshape(-1, self.dim)[self.slices[surface.name][0]]
                part = surface.curvature(c, g_surface)
                if part is not None:
                    rows.append(part[0])
                    cols.append(part[1])
                    vals.append(part[2])
            if rows:
                K = sp.csr_matrix(
                    (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                    shape=hess.shape,
                )
                hess = (hess + K).tocsr()
        return grad, hess

    # -- friction (IPC's smoothed, lagged Coulomb friction) ----------------------------------------
    @property
    def has_friction(self) -> bool:
        return self.table.has_friction

    def reset_stats(self) -> None:
        self.stats = ContactStats()
        self.candidates.stats = self.stats

    def describe(self) -> dict:
        return {
            "bodies": [surface.name for surface in self.surfaces],
            "dhat_m": self.dhat,
            "stiffness_Pa": self.kappa,
            "adaptive_stiffness": self.adaptive is not None,
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
        """Collision-mesh vertices (n, d) for the system configuration c, the obstacles at
        ``obstacle`` (flat), else at time t, else where they are (``obstacle_state``, or at
        ``self.time``)."""
        V = np.empty_like(self.rest)
        for surface in self.surfaces:
            V[self.slices[surface.name][0]] = surface.positions(c)
        if obstacle is None and t is None and self.obstacle_state is not None:
            obstacle = self.obstacle_state
        if obstacle is not None:
            V[self.n_deformable :] = np.reshape(obstacle, (-1, self.dim))
        else:
            t = self.time if t is None else t
            for ob in self.obstacles:
                V[self.slices[ob.name][0]] = ob.positions(t)
        return np.asfortranarray(V)

    # -- the candidate set, built once per step and reused ------------------------------------
    def begin_step(self) -> None:
        """A new step: the candidate set is built at the first evaluation with bounds inflated
        by a margin of dhat and reused by every evaluation (and CCD sweep, while it is not
        dense: ``contact/barrier/ccd_queries.py``) whose vertices stay within the margin of where it
        was built; a vertex that leaves it rebuilds the set (contact/barrier/candidates.py). A
        margin of the step's expected motion (up to a quarter of an edge, the earlier default) saved
        rebuilds but every evaluation paid for its extra pairs: dhat was within 10 % of it
        (run-to-run spread) on every scene of ``benchmarks/contact_candidates.py``, and needs
        no motion estimate."""
        self.candidates.begin(self.dhat)
        self.predicted_forces = None
        self.prediction_report = None

    def _leave_out_rest_pairs(self, ipctk) -> None:
        """Cut bodies' surface pairs of one piece that touch at rest do not collide
        (``contact/cut/rest_proximity.py``)."""
        from tissuesim.contact.cut.rest_proximity import rest_proximity_filter

        near = np.zeros(len(self.rest), dtype=bool)
        for surface in self.surfaces:
            if isinstance(surface, CutFemSurface) and surface.near_cut is not None:
                near[self.slices[surface.name][0]] = surface.near_cut
        rest_pairs = rest_proximity_filter(ipctk, self.mesh, self.rest, near, self.dhat)
        # a vertex filter beyond the pair table: the predictor's own broad phase cannot apply
        self.rest_filtered = rest_pairs is not None
        if rest_pairs is not None:
            kept = self.mesh.can_collide if self.table.filtered else None
            self.mesh.can_collide = rest_pairs if kept is None else kept & rest_pairs

    def _collisions(self, V: np.ndarray):
        """The collision set at vertex positions V; the last one again when V is the same:
        Newton evaluates a point's Hessian after its line search evaluated its gradient, and
        the contact projection tries it once more (half the builds of liver_instrument, 12 ms
        each on a cut organ, were of the positions just built)."""
        last = self._last_collisions
        if last is not None and last[0].shape == V.shape and np.array_equal(last[0], V):
            return last[1]
        col = self._build_collisions(V)
        self._last_collisions = (V.copy(), col)
        return col

    def _build_collisions(self, V: np.ndarray):
        col = self._ipctk.NormalCollisions()
        col.use_area_weighting = True
        candidates = self.candidates.get(V)
        if candidates is None:
            col.build(self.mesh, V, self.dhat, broad_phase=self.broad_phase)
        else:
            col.build(candidates, self.mesh, V, self.dhat)
        if self.point_areas is not None:
            weigh_points(col, self.point_areas)
        return col

    # -- the energy -------------------------------------------------------------------------------
    def evaluate(self, c: np.ndarray, order: int, project: bool = True):
        """(value J, gradient over the system DOFs or None, Hessian sparse or None); the
        Hessian is PSD-projected per collision (as IPC does) unless ``project`` is False."""
        start = time.perf_counter()
        out = self._terms(c, self.vertices(c), order, project, augmented=False)
        self.stats.candidates_and_barrier_s += time.perf_counter() - start
        return out

    def evaluate_augmented(self, c: np.ndarray, y: np.ndarray, order: int, project: bool = True):
        """As ``evaluate``, with the obstacles at y (flat) and their coordinates as unknowns
        after the system's: gradient (n_dofs + n_obstacle,), Hessian over the same."""
        start = time.perf_counter()
        out = self._terms(c, self.vertices(c, obstacle=y), order, project, augmented=True)
        self.stats.candidates_and_barrier_s += time.perf_counter() - start
        return out

    def _terms(self, c, V, order: int, project: bool, augmented: bool):
        """Barrier + lagged friction over the vertices, then through the surfaces' maps."""
        value, g_V, H_V = self.vertex_terms(V, order, project)
        grad, hess = self._to_dofs(c, order, g_V, H_V, augmented)
        return value, grad, hess

    def vertex_terms(self, V: np.ndarray, order: int, project: bool):
        """(value, gradient, sparse Hessian) of barrier + lagged friction over the collision
        vertices V (bodies' and obstacles'); None where absent or not asked for."""
        start = time.perf_counter()
        col = self._collisions(V)
        self.stats.candidates_s += time.perf_counter() - start
        self.stats.evaluations += 1
        value, g_V, H_V = 0.0, None, None
        if len(col):
            value = float(self.barrier(col, self.mesh, V))
            if order >= 1:
                g_V = self.barrier.gradient(col, self.mesh, V)
            if order >= 2:
                method = self._ipctk.PSDProjectionMethod
                H = self.barrier.hessian(
                    col, self.mesh, V, method.CLAMP if project else method.NONE
                )
                H_V = sp.csr_matrix(H)
        f_value, f_grad, f_hess = self._friction_terms(V, order, project)
        value += f_value
        if f_grad is not None:
            g_V = f_grad if g_V is None else g_V + f_grad
        if f_hess is not None:
            H_V = f_hess if H_V is None else H_V + f_hess
        return value, g_V, H_V


def _youngs(material) -> float:
    """Young's modulus E = mu (3 lambda + 2 mu) / (lambda + mu) of a material (Pa)."""
    mu, lam = float(material.mu), float(material.lam)
    return mu * (3 * lam + 2 * mu) / (lam + mu)


def _set_contact_threads(ipctk) -> None:
    """ipctk's threads from TISSUESIM_CONTACT_THREADS, if set. Its parallel sums make contact
    runs reproducible to round-off only (1e-16 apart from run to run); one thread makes them
    bit for bit reproducible, at 1.5x the contact cost on two cores (measured on a cut organ
    on a table)."""
    import os

    value = os.environ.get("TISSUESIM_CONTACT_THREADS", "").strip()
    if not value:
        return
    if not value.isdigit() or int(value) < 1:
        raise InputError(
            f"TISSUESIM_CONTACT_THREADS={value!r}: give a whole number of threads >= 1 "
            "(1 makes contact runs bit for bit reproducible), or unset it"
        )
    ipctk.set_num_threads(int(value))
