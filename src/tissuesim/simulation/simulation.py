"""Simulation: the object users script. Any number of bodies (FEM meshes, meshless frame bodies,
the connective tissue between organs), their supports, graspers, springs and loads, advanced in
time by one Newton solve over all of them per step (``time/steps.py`` on ``system.py``).

One body, the short form:

    sim = Simulation(mesh, CourseNeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
                     density=1.0, integrator="backward_euler", time_step=0.02)
    sim.add_dirichlet(select.vertices_on_plane(mesh, axis=0, value=-1.0))
    sim.add_gravity([0.0, -9.81])
    sim.run(steps=100, output="out")

Many bodies:

    sim = Simulation(integrator="quasistatic", time_step=0.1, gravity=(0, 0, -9.81))
    sim.add_body("liver", ellipsoid(...), make_material(...), density=1050)
    sim.add_body("gallbladder", ...)
    sim.fix(vertices, body="liver")                                   # a support
    sim.grasp(vertices, lambda t: (0, 0, 0.01 * t), body="gallbladder")  # retraction
    sim.add_tissue(make_material(...), thickness=0.006, spacing=0.002, frames=30)
    sim.add_cut(blade, start=1.0, end=2.0)
    sim.run(150, "out")

Set-up methods that act on one body take ``body=`` (its name); it may be left out when the
simulation has one body of the kind the method needs. Every support, prescribed set, grasper
and spring set has a name; its force (N) is reported per step in ``history[k].extra["forces"]``.
"""

from __future__ import annotations

import time as wallclock
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from tissuesim import validate
from tissuesim.bodies.fem import FemBody
from tissuesim.contact.readout.indentation import IndentationTracker
from tissuesim.energies.mass import MassKind
from tissuesim.errors import InputError
from tissuesim.materials.base import Material
from tissuesim.mesh.mesh import Mesh
from tissuesim.records import StepRecord
from tissuesim.simulation.bodies import BodyCalls
from tissuesim.simulation.checks import StepChecks
from tissuesim.simulation.cuts import CutCalls
from tissuesim.simulation.interactions import InteractionCalls
from tissuesim.simulation.loads import LoadCalls
from tissuesim.simulation.penalty_contact import PenaltyContactCalls, carry_penalty_state
from tissuesim.simulation.results import BodyResults
from tissuesim.simulation.rigid import RigidCalls
from tissuesim.simulation.rigid_wall import RigidWallCalls, carry_wall_state
from tissuesim.simulation.saving import SavedAndDescribed
from tissuesim.simulation.stepping import Stepping
from tissuesim.solve.linear import make_linear_solver
from tissuesim.solve.newton import NewtonOptions
from tissuesim.time.adaptive import AdaptiveStepping
from tissuesim.time.attempts.retry import validate_stepping
from tissuesim.time.grid import check_time_resolution
from tissuesim.time.integrators.generalized_alpha import check_generalized_alpha
from tissuesim.time.integrators.newmark import check_newmark
from tissuesim.time.phases import Phase, Schedule
from tissuesim.time.state import State

if TYPE_CHECKING:  # frames and the system pull in scipy.spatial: imported when first used
    from tissuesim.bodies.frames import FrameBody
    from tissuesim.coupling.tissue import TissueBody
    from tissuesim.system import System

__all__ = ["Simulation", "INTEGRATORS"]

Integrator = Literal[
    "backward_euler", "quasistatic", "explicit", "symplectic_euler", "newmark", "generalized_alpha"
]
#: "symplectic_euler" is the FEM name of the explicit scheme; both step every body explicitly
INTEGRATORS = (
    "backward_euler",
    "quasistatic",
    "explicit",
    "symplectic_euler",
    "newmark",
    "generalized_alpha",
)
EXPLICIT = ("explicit", "symplectic_euler")


class Simulation(
    BodyCalls,
    LoadCalls,
    InteractionCalls,
    PenaltyContactCalls,
    RigidWallCalls,
    CutCalls,
    RigidCalls,
    StepChecks,
    BodyResults,
    Stepping,
    SavedAndDescribed,
):
    """Bodies, their interactions and a time integrator; see the module docstring.

    mesh, material (optional): the short form, one FEM body named ``name`` with ``density``
    (kg/m^3, scalar or per element) and ``mass`` ("consistent" or "lumped").
    integrator: "backward_euler", "quasistatic", "newmark" (``newmark`` = (beta, gamma), the
    trapezoidal rule (0.25, 0.5) by default: FEBio's dynamics, no numerical damping),
    "generalized_alpha" (``generalized_alpha`` = rho_inf in [0, 1], the spectral radius at
    infinite step, 1 by default, or (alpha_f, alpha_m, beta, gamma) in FEBio's weights: FEBio's
    rhoi; ``time/integrators/generalized_alpha.py``) or
    "explicit" ("symplectic_euler": the same; FEM bodies then use the lumped mass).
    time_step: s (quasistatics: the load-step length).
    gravity: (d,) m/s^2 on every body, or None. newton: NewtonOptions. max_step_halvings: how
    often a failing step is split in two before giving up. backend: "auto", "numba" or "numpy".
    phases: a run in phases (``set_phases``), each with its steps, time step and integrator.
    adaptive: FEBio's adaptive steps (``set_adaptive``; ``time_step`` is then the first).
    """

    def __init__(
        self,
        mesh: Mesh | None = None,
        material: Material | None = None,
        *,
        density: float | np.ndarray = 1.0,
        mass: MassKind = "consistent",
        name: str = "body",
        integrator: Integrator = "backward_euler",
        time_step: float = 0.01,
        gravity: Sequence[float] | None = None,
        newton: NewtonOptions | None = None,
        max_step_halvings: int = 6,
        start_time: float = 0.0,
        backend: str = "auto",
        phases: Sequence[Phase | dict] | None = None,
        newmark: Sequence[float] = (0.25, 0.5),
        generalized_alpha: float | Sequence[float] = 1.0,
        adaptive: AdaptiveStepping | dict | None = None,
    ) -> None:
        self.integrator = validate.choice(integrator, "integrator", INTEGRATORS)
        self.newmark = check_newmark(newmark)
        self.generalized_alpha = check_generalized_alpha(generalized_alpha)
        self.time_step, self.max_step_halvings = validate_stepping(time_step, max_step_halvings)
        self.start_time = validate.real(start_time, "start_time", unit="s")
        check_time_resolution(self.start_time, self.time_step, "start_time")
        if newton is not None and not isinstance(newton, NewtonOptions):
            raise InputError(f"newton must be a NewtonOptions, not {validate.short(newton)}")
        self.newton = newton or NewtonOptions()
        self.backend = validate.choice(backend, "backend", ("auto", "numba", "numpy"))
        self.bodies: dict[str, FemBody | FrameBody | TissueBody] = {}
        self.tissue: TissueBody | None = None
        self.rigid_bodies: dict = {}  # name -> simulation/rigid.py RigidBodySpec
        self.rigid_joints: list = []  # rigid/joints.py RigidJoint, RigidSpring
        self.history: list[StepRecord] = []
        self.gravity: list[np.ndarray] = []  # on every body, those added later too
        self._force_names: set[str] = set()
        self.ties: list = []  # coupling/tie.py
        self.penalty_contacts: list = []  # simulation/penalty_contact.py PenaltySpec
        self.rigid_walls: list = []  # simulation/rigid_wall.py RigidWallSpec
        self._named_attachments: list = []  # (name, sign, index in system.attachments)
        self.frame_attachments: list = []  # (coupling/frame_attachment.py spec, sign)
        self.contact = None  # contact/model.py ContactSettings when contact is on
        self.obstacles: list = []  # contact/obstacles.py Obstacle
        self._system: System | None = None
        self._state: State | None = None
        self._solver = None
        self.solver_reason = ""
        self.run_time_split: dict[str, float] = {}  # the last run()'s wall time split (s)
        self._last_gradient: np.ndarray | None = None
        self._indentation = IndentationTracker()  # probes' touch points, across rebuilds
        self.organ_cuts: list = []  # blades cutting FEM bodies (bodies/organ_cut.py)
        self.organ_tears: list = []  # FEM bodies that tear (bodies/organ_tear.py)
        self.visual_surfaces: dict = {}  # name -> bodies/visual_surface.py VisualSurface
        self.logfiles: list = []  # io/logfiles.py LogRequest: FEBio's log tables
        self.schedule: Schedule | None = None  # time/phases.py: a run in phases
        self.adaptive: AdaptiveStepping | None = None  # time/adaptive.py: FEBio's steps
        self._controller = None  # the adaptive steps' TimeStepController now
        self.set_adaptive(adaptive)
        if phases is not None:
            self.set_phases(phases)
        if self.newton.linear_solver != "auto" and not self.explicit:
            make_linear_solver(self.newton.linear_solver, 1, 3)  # unavailable: fail now
        if mesh is not None:
            if material is None:
                raise InputError("Simulation(mesh, material): a mesh needs its material")
            self.add_body(name, mesh, material, density=density, mass=mass)
        elif material is not None:
            raise InputError("Simulation(mesh, material): a material needs its mesh")
        if gravity is not None:
            self.add_gravity(gravity)

    @classmethod
    def from_frames(
        cls, frames: np.ndarray, samples, material: Material, *, name: str = "body", **kw
    ) -> Simulation:
        """The short form for one frame body: ``Simulation.from_frames(frames, samples,
        material, density=..., frame_type=..., integrator=..., time_step=...)``; the keywords
        of ``Simulation`` go to the simulation, the others to ``add_frame_body``."""
        own = ("integrator", "time_step", "gravity", "newton", "max_step_halvings")
        own += ("start_time", "backend")
        sim = cls(**{k: kw.pop(k) for k in own if k in kw})
        sim.add_frame_body(name, frames, samples, material, **kw)
        return sim

    def __repr__(self) -> str:
        if len(self.bodies) == 1:
            (b,) = self.bodies.values()
            if b.kind == "fem":
                kind = "triangles" if b.dim == 2 else "tetrahedra"
                what = f"{b.mesh.n_points} vertices, {b.mesh.n_cells} {kind}, {b.model.material!r}"
            else:
                what = repr(b)
        else:
            what = ", ".join(repr(b) for b in self.bodies.values()) or "no bodies"
        return (
            f"Simulation({what}, {self.integrator}, time_step {self.time_step:g} s, "
            f"t = {self.time:g} s, {len(self.history)} steps)"
        )

    @property
    def explicit(self) -> bool:
        """True when the integrator is explicit (``"explicit"`` or ``"symplectic_euler"``)."""
        return self.integrator in EXPLICIT

    # -- the assembled system and the state ---------------------------------------------------
    _system_dirty = True

    @property
    def system(self) -> System:
        """The assembled system (built on first use and again after set-up changes)."""
        if self._system is None or self._system_dirty:
            self._build()
        return self._system

    def build(self) -> None:
        """Assemble the system now (the first step does it otherwise)."""
        self.system  # noqa: B018

    def _active(self) -> list:
        return [b for b in self.bodies.values() if b.model is not None]

    def _build(self) -> None:
        from tissuesim.system import System

        if not self.bodies:
            raise InputError("the simulation has no bodies: add_body or add_frame_body first")
        old, state = self._system, self._state
        parts: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        if old is not None and state is not None:
            for j, name in enumerate(old.names):
                a = None if state.a is None else state.a[old.tangent_slices[j]]
                parts[name] = (state.x[old.config_slices[j]], state.v[old.tangent_slices[j]], a)
        bodies = self._active()
        names = [b.name for b in bodies]
        attachments = []
        if self.tissue is not None and self.tissue.model is not None:
            attachments = self.tissue.attachments(names.index, names.index(self.tissue.name))
        self._named_attachments = []  # (name, sign, index among the system's attachments)
        for spec, sign in self.frame_attachments:
            if spec.fem in names and spec.frames in names:
                j = names.index(spec.frames)
                self._named_attachments.append((spec.name, sign, len(attachments)))
                attachments.append(spec.build(names.index(spec.fem), j, bodies[j].model))
        ties = [t for t in self.ties if t.a in names and t.b in names]
        rigid, members = self._rigid_models(names)
        self._system = System([b.model for b in bodies], names, attachments, ties, rigid=rigid,
                              rigid_members=members, joints=self.rigid_joints)  # fmt: skip
        parts.update(self._rigid_parts(old, state))
        # FEBio-style penalty energies: the pairs, then the rigid walls (same interface)
        walls = self._rigid_wall_energies(self._system)
        self._system.penalty_contacts = self._penalty_pairs(self._system) + walls
        if old is not None:  # a rebuild keeps the pairs' multipliers (same facets, same points)
            carry_penalty_state(old.penalty_contacts, self._system.penalty_contacts)
            carry_wall_state(old.penalty_contacts, walls)
        if self.contact is not None:
            self._system.contact = self._contact_model()
            if old is not None and old.contact is not None:
                self._system.contact.carry_over(old.contact)
            self._soften_rigid(self._system)
        self._system_dirty = False
        x, v, a, carry_a = [], [], [], False
        for b in bodies:
            c0, v0, a0 = parts.get(b.name) or (self._initial_config(b), b.velocity, None)
            origin = getattr(b, "pending_origin", None)
            if origin is not None and b.name in parts:  # a cut: each new node continues its old
                d = b.dim
                c0 = c0.reshape(-1, d)[origin].ravel()
                v0 = v0.reshape(-1, d)[origin].ravel()
                a0 = None if a0 is None else a0.reshape(-1, d)[origin].ravel()
            if origin is not None:
                b.pending_origin = None
            x.append(c0)
            v.append(v0)
            a.append(np.zeros_like(v0) if a0 is None else a0)
            carry_a = carry_a or a0 is not None
        for r in rigid:  # the rigid blocks after the bodies (system.py)
            c0, v0, _ = parts.get(f"rigid:{r.name}") or (r.rest_config(), np.zeros(6), None)
            x.append(c0)
            v.append(v0)
            a.append(np.zeros(6))
        t = self.start_time if state is None else state.time
        acceleration = np.concatenate(a) if carry_a else None  # Newmark's, across rebuilds
        self._state = State(t, np.concatenate(x), np.concatenate(v), acceleration)
        if old is None or old.pattern is not self._system.pattern:
            self._solver = None  # the pattern changed: a new symbolic analysis

    @staticmethod
    def _initial_config(b) -> np.ndarray:
        return b.mesh.points.ravel().copy() if b.kind == "fem" else b.config.copy()

    @property
    def state(self) -> State:
        """Time, configuration (every body's block in turn) and tangent velocity."""
        self.system  # noqa: B018
        return self._state

    @state.setter
    def state(self, value: State) -> None:
        self.system  # noqa: B018
        if value.x.shape != self._state.x.shape or value.v.shape != self._state.v.shape:
            raise InputError("a state must have the shapes of the simulation's state")
        self._state = value

    @property
    def time(self) -> float:
        """The current simulated time (s): ``start_time`` plus the steps taken."""
        return self.start_time if self._state is None else self._state.time

    def body_state(self, name: str | None = None, kinds=()) -> tuple[Any, np.ndarray, np.ndarray]:
        """(body, its block of the configuration, its block of the tangent velocity) now."""
        b = self.body(name, kinds)
        s = self.system
        j = s.index(b.name) if b.name in s.names else None
        if j is None:
            raise InputError(f"body {b.name!r} has no material left (all of it was cut away)")
        return b, self._state.x[s.config_slices[j]], self._state.v[s.tangent_slices[j]]

    # -- stepping -----------------------------------------------------------------------------
    def _linear_solver(self):
        if self._solver is None:
            s = self.system
            dims = {b.dim for b in self._active()}
            single = len(s.bodies) == 1 and self._active()[0].kind == "fem"
            ratio = max(
                (
                    b.model.material.lam / b.model.material.mu
                    for b in self._active()
                    if b.kind == "fem"
                ),
                default=0.0,
            )
            self._solver, self.solver_reason = make_linear_solver(
                self.newton.linear_solver,
                s.n_dofs,
                max(dims),
                self._active()[0].mesh.points if single else None,
                volumetric_ratio=ratio,
                quadratic=any(b.kind == "fem" and b.mesh.order == 2 for b in self._active()),
            )
            from tissuesim.solve.reuse import ReusedFactorSolver, is_direct

            if self.newton.reuse_factorization and is_direct(self._solver):
                self._solver = ReusedFactorSolver(self._solver)
                self.solver_reason += "; factorisation reused (CG on the last factor)"
        return self._solver

    def step_energies(self, t: float, c_pred: np.ndarray | None, h: float) -> list[list]:
        """Every body's extra energies of a step at time t (inertia about c_pred when given,
        loads, springs): what ``time/steps.py`` adds to the elastic energies."""
        s = self.system
        s.load_time = t  # the rigid bodies' loads (system.py)
        return [
            self.bodies[name].step_energies(
                t, None if c_pred is None else c_pred[s.config_slices[j]], h
            )
            for j, name in enumerate(s.names)
        ]

    def step(
        self, *, budget_s: float | None = None, budget_iterations: int | None = None
    ) -> StepRecord:
        """Advance one time step (halving on failure; ConvergenceError if it cannot), then
        apply cuts and tearing. Returns the step's record (also appended to ``history``).

        budget_s / budget_iterations: for interactive loops, Newton stops when the step has
        run this long (wall-clock seconds) or this many iterations, after at least one; the
        state reached (intersection-free, as every iterate) is accepted and the record says
        ``extra["early_stop"]`` True. Without a budget a step runs to convergence."""
        budget = None
        if budget_s is not None or budget_iterations is not None:
            budget = {}
            if budget_s is not None:
                seconds = validate.real(budget_s, "budget_s", low=0.0, low_open=True, unit="s")
                budget["deadline"] = wallclock.perf_counter() + seconds
            if budget_iterations is not None:
                budget["iterations"] = validate.integer(
                    budget_iterations, "budget_iterations", low=1, high=10_000
                )

        self._enter_phase()
        tol = 1e-9 * self.time_step  # a release at t_n counts for the step from t_n
        t_end = self._end_time()
        for body in self.bodies.values():
            if body.kind == "fem":
                body.release_graspers(self.time + tol)
                body.set_condition_time(t_end, tol)
        if self.organ_cuts:
            self._cut_ahead()  # blades in contact with what they cut: the cut goes first
        s = self.system
        by_contact = self.integrator == "quasistatic" and self._check_supported()
        self._check_contact_start()  # dhat, and surfaces apart, before the first step
        if self.explicit and self._stability_checked is not s:
            self._check_stability()
            self._stability_checked = s
        start = wallclock.perf_counter()
        t0 = self.time
        explicit_gradient: dict = {}
        step_fn, solver = self._step_function(budget, explicit_gradient, by_contact)
        self._state, records, substeps, adaptive = self._advance(step_fn, s, solver)
        if records:
            self._last_gradient = records[-1].gradient
        elif "gradient" in explicit_gradient:
            # the explicit step's own gradient (at its start): the reactions one step behind,
            # without a second evaluation per step (it cost a third of an explicit step)
            self._last_gradient = explicit_gradient["gradient"]
        else:
            self._last_gradient = self._static_gradient()
        extra: dict[str, Any] = {"forces": self.forces()}
        if hasattr(solver, "take_stats"):
            extra["linear"] = solver.take_stats()
        extra["early_stop"] = any(getattr(r, "budget_stop", False) for r in records)
        fallbacks = sum(getattr(r, "fallback", False) for r in records)
        if fallbacks:  # newton method "febio": steps its Newton solved (time/steps.py)
            extra["newton_fallback"] = fallbacks
        if adaptive is not None:  # the step's length, retries and whether it hit a must point
            extra["adaptive"] = adaptive
        if s.contact is not None:
            extra["contact"] = self._contact_report(s.contact, self._state.x, extra["forces"])
        if self.tissue is not None:
            extra.update(self._tissue_step(t0))
        if self.organ_cuts or self.organ_tears:
            extra.update(self._organ_cut_step(t0, extra["forces"]))
        record = StepRecord.build(
            len(self.history) + 1,
            self.time,
            records,
            substeps,
            start,
            solver,
            energies=self.energies(),
            min_J=self.min_J(),
            extra=extra,
        )
        self.history.append(record)
        return record

    def run(
        self,
        steps: int,
        output: str | Path | None = None,
        *,
        every: int = 1,
        progress: bool = True,
        render: bool = True,
        field: str = "J",
        metadata: dict | None = None,
        resume: bool = False,
    ) -> list[StepRecord]:
        """Run ``steps`` time steps; with ``output``, write per body a VTU series on rest
        positions, summary.json, forces.csv and (``render``) forces.png, final.png and run.gif
        coloured by ``field`` ("J", "von_mises", "displacement", "green_strain";
        ``io/run_output.py``), and checkpoint.npz at every frame. Returns this run's step
        records. Steps taken before by ``step()`` are not part of the run's output: its series,
        summary.json and forces.csv all start at the state the run starts from.

        resume: continue the run in ``output`` from its checkpoint (this simulation set up the
        same way, not stepped yet); ``steps`` then counts the whole run, the steps done
        included. A complete run is left as it is."""
        from tissuesim.io.run_output import RunOutput

        writer = RunOutput(
            self, output, every=every, render=render, field=field, metadata=metadata, resume=resume
        )
        self.run_time_split = writer.time_split  # filled in as the run goes (s)
        with writer.lock:  # the directory's run lock (io/lock.py), released however it ends
            return writer.run(steps, progress=progress)
