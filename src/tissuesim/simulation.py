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
    sim.fix("liver", vertices)                                        # a support
    sim.grasp("gallbladder", vertices, lambda t: (0, 0, 0.01 * t))     # retraction
    sim.add_tissue(make_material(...), thickness=0.006, spacing=0.002, frames=30)
    sim.add_cut(blade, start=1.0, end=2.0)
    sim.run(150, "out")

Set-up methods that act on one body take ``body=`` (its name); it may be left out when the
simulation has one body of the kind the method needs. Every support, prescribed set, grasper
and spring set has a name; its force (N) is reported per step in ``history[k].extra["forces"]``.
"""

from __future__ import annotations

import functools
import re
import time as wallclock
import warnings
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from tissuesim import validate
from tissuesim.bodies.fem import FemBody
from tissuesim.contact.indentation import IndentationTracker, is_probe
from tissuesim.energies.mass import MassKind
from tissuesim.errors import InputError
from tissuesim.materials.base import Material
from tissuesim.mesh.mesh import Mesh
from tissuesim.records import StepRecord
from tissuesim.simulation_results import BodyResults
from tissuesim.simulation_setup import SetupCalls
from tissuesim.solve.linear import make_linear_solver
from tissuesim.solve.newton import NewtonOptions
from tissuesim.time.retry import advance, validate_stepping
from tissuesim.time.state import State

if TYPE_CHECKING:  # frames and the system pull in scipy.spatial: imported when first used
    from tissuesim.bodies.frames import FrameBody
    from tissuesim.coupling.tissue import TissueBody
    from tissuesim.system import System

__all__ = ["Simulation", "StepRecord", "INTEGRATORS"]

Integrator = Literal["backward_euler", "quasistatic", "explicit", "symplectic_euler"]
#: "symplectic_euler" is the FEM name of the explicit scheme; both step every body explicitly
INTEGRATORS = ("backward_euler", "quasistatic", "explicit", "symplectic_euler")
EXPLICIT = ("explicit", "symplectic_euler")
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
#: series the output writes besides the bodies'; no body may take these names
RESERVED_NAMES = ("cut", "summary", "forces", "manifest")
#: explicit time steps above this multiple of the stability estimate are refused
STABILITY_MARGIN = 1.5


def check_time_resolution(t: float, h: float, what: str) -> None:
    """Refuse a time so large that steps of h are lost to round-off (t + h == t, or h
    resolved to worse than 1e-3 of itself): every frame would carry the same time."""
    if abs(t) * 2.0**-52 > 1e-3 * h:
        raise InputError(
            f"{what} {t:g} s is too large for time_step {h:g} s: a double cannot resolve steps of "
            f"{h:g} s at t = {t:g} s; count time from 0 (start_time = 0)"
        )


class Simulation(SetupCalls, BodyResults):
    """Bodies, their interactions and a time integrator; see the module docstring.

    mesh, material (optional): the short form, one FEM body named ``name`` with ``density``
    (kg/m^3, scalar or per element) and ``mass`` ("consistent" or "lumped").
    integrator: "backward_euler", "quasistatic" or "explicit" ("symplectic_euler": the same;
    FEM bodies then use the lumped mass). time_step: s (quasistatics: the load-step length).
    gravity: (d,) m/s^2 on every body, or None. newton: NewtonOptions. max_step_halvings: how
    often a failing step is split in two before giving up. backend: "auto", "numba" or "numpy".
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
    ) -> None:
        self.integrator = validate.choice(integrator, "integrator", INTEGRATORS)
        self.time_step, self.max_step_halvings = validate_stepping(time_step, max_step_halvings)
        self.start_time = validate.real(start_time, "start_time", unit="s")
        check_time_resolution(self.start_time, self.time_step, "start_time")
        if newton is not None and not isinstance(newton, NewtonOptions):
            raise InputError(f"newton must be a NewtonOptions, not {validate.short(newton)}")
        self.newton = newton or NewtonOptions()
        self.backend = validate.choice(backend, "backend", ("auto", "numba", "numpy"))
        self.bodies: dict[str, FemBody | FrameBody | TissueBody] = {}
        self.tissue: TissueBody | None = None
        self.history: list[StepRecord] = []
        self.gravity: list[np.ndarray] = []  # on every body, those added later too
        self._force_names: set[str] = set()
        self.ties: list = []  # coupling/tie.py
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
        return self.integrator in EXPLICIT

    # -- bodies -------------------------------------------------------------------------------
    def _new_name(self, name: str, what: str, kind: str = "fem") -> str:
        """A body name that is valid as a file stem and clashes with no other body's output
        series (``<name>``, ``<name>_frames``, ``<name>_surface``, ``<name>_points``)."""
        from tissuesim.io.body_series import series_names

        if not isinstance(name, str) or not _NAME.fullmatch(name):
            raise InputError(
                f"{what} name {validate.short(name)} must be letters, digits, '_', '-' or '.', "
                "starting with a letter or digit (it names output files)"
            )
        taken = name in self.bodies or name in {o.name for o in self.obstacles}
        if taken or name in RESERVED_NAMES or (name == "tissue" != what):
            raise InputError(f"{what} name {name!r} is taken; choose another")
        mine = set(series_names(name, kind))
        for other in self.bodies.values():
            clash = mine & set(series_names(other.name, other.kind))
            if clash:
                raise InputError(
                    f"{what} name {name!r} would write the series {sorted(clash)[0]!r} that "
                    f"body {other.name!r} writes; choose another name"
                )
        if self._system is not None and self.history:
            raise RuntimeError(f"add {what}s before the first step")
        return name

    def _claim_force_name(self, name: str | None, default: str = "") -> str:
        """``name`` if it is new (else an error); None: ``default``, numbered if taken."""
        if name is None:
            name, k = default, 1
            while name in self._force_names:
                name, k = f"{default}_{k}", k + 1
        elif name in self._force_names:
            raise InputError(
                f"a support, grasper or spring set named {name!r} exists; give another name"
            )
        self._force_names.add(name)
        return name

    def _changed(self, body: str = "", what: str = "structure") -> None:
        """A body's set-up changed: ``structure`` rebuilds the system before the next step;
        ``prescribed`` / ``velocity`` also update the body's part of the state."""
        known = self._system is not None and body in self._system.names
        if self._state is not None and known and what in ("prescribed", "velocity"):
            j = self._system.index(body)
            b = self.bodies[body]
            x, v = self._state.x.copy(), self._state.v.copy()
            sc, st = self._system.config_slices[j], self._system.tangent_slices[j]
            if what == "prescribed":
                x[sc] = b.model.apply_prescribed(x[sc], self.time)
            else:
                v[st] = b.velocity
            self._state = State(self.time, x, v)
        if what != "velocity":  # a new velocity changes the state, not the system
            self._system_dirty = True

    def add_body(
        self,
        name: str,
        mesh: Mesh,
        material: Material,
        *,
        density: float | np.ndarray = 1000.0,
        mass: MassKind = "consistent",
        order: int | None = None,
        formulation: str = "displacement",
    ) -> FemBody:
        """A FEM body: a triangle or tetrahedral mesh (``mesh.box``, ``mesh.ellipsoid``,
        ``read_mesh``) of one material; density kg/m^3 (scalar or one per element).

        order: None (the mesh's), 1, or 2 (a linear mesh gets a node at every edge's midpoint;
        vertex indices are kept, point sets gain the midside nodes between their vertices).
        formulation: "displacement", or "mean_dilatation" for nearly incompressible laws
        (nu >= 0.45): the lambda term on element (P2) or vertex-patch (P1) volume averages,
        free of volumetric locking (``energies/mean_dilatation.py``)."""
        name = self._new_name(name, "body")
        if self.tissue is not None:
            raise InputError("add the organs before the tissue that connects them")
        if not isinstance(mesh, Mesh):
            raise InputError(f"add_body: mesh must be a tissuesim Mesh, not {validate.short(mesh)}")
        if not isinstance(material, Material):
            raise InputError(
                f"add_body: material must be a tissuesim material (make_material), not "
                f"{validate.short(material)}"
            )
        validate.choice(mass, "mass", ("consistent", "lumped"))
        validate.choice(formulation, "formulation", ("displacement", "mean_dilatation"))
        if order is not None:
            if isinstance(order, bool) or order not in (1, 2):
                raise InputError(f"order must be 1 or 2, not {validate.short(order)}")
            if order == 2 and mesh.order == 1:
                from tissuesim.mesh.quadratic import elevate_mesh

                mesh = elevate_mesh(mesh)
            elif order == 1 and mesh.order == 2:
                raise InputError(
                    f"add_body {name!r}: order 1 was asked for but {mesh.source} has quadratic "
                    "elements; give a linear mesh or order = 2"
                )
        if self.explicit:
            mass = "lumped"  # the explicit update inverts the mass: it must be diagonal
        body = FemBody(
            name,
            mesh,
            material,
            density=density,
            mass=mass,
            formulation=formulation,
            backend=self.backend,
            claim_name=self._claim_force_name,
            changed=functools.partial(self._changed, name),
        )
        for g in self.gravity:
            body.add_gravity(g)
        self.bodies[name] = body
        self._changed()
        return body

    def add_frame_body(self, name: str, frames: np.ndarray, samples, material: Material, **kw):
        """A meshless body: frame origins (n, 3) (``grid_frames``, ``farthest_point_frames``),
        integration points with volumes (``sample_box``, ``sample_surface``, ...), any
        material; keywords of ``bodies.frames.FrameBody`` (density, frame_type "rigid" or
        "affine", shape "wendland" or "shepard", radius, radius_factor, min_frames,
        rotations, mass "full" or "lumped")."""
        from tissuesim.bodies.frames import FrameBody

        name = self._new_name(name, "body", "frames")
        body = FrameBody(
            name,
            frames,
            samples,
            material,
            backend=self.backend,
            claim_name=self._claim_force_name,
            changed=functools.partial(self._changed, name),
            time=lambda: self.time,
            **kw,
        )
        for g in self.gravity:
            body.add_gravity(g)
        self.bodies[name] = body
        self._changed()
        return body

    def add_tissue(self, material: Material, *, name: str = "tissue", **kw) -> TissueBody:
        """The connective tissue between the FEM bodies (``coupling/tissue.py``): integration
        points ``samples=``, or sampled between the organs (``thickness``, ``spacing``,
        ``region``); ``frames`` a count or (n, 3) origins; ``frame_type`` "affine" (default)
        or "rigid"; attached to every organ it touches (``attach_distance``,
        ``attachment_stiffness`` N/m per m^2)."""
        from tissuesim.coupling.tissue import TissueBody

        if self.tissue is not None:
            raise InputError("the scene has a tissue already; one tissue body per scene")
        name = self._new_name(name, "tissue", "tissue")
        organs = [(n, b.mesh) for n, b in self.bodies.items() if b.kind == "fem"]
        if any(m.dim != 3 for _, m in organs):
            raise InputError("the tissue joins 3D organs; a 2D body cannot take part")
        tissue = TissueBody(name, organs, material, backend=self.backend, **kw)
        for g in self.gravity:
            tissue.add_gravity(g)
        self.bodies[name] = self.tissue = tissue
        self._changed()
        return tissue

    def remove_body(self, name: str) -> None:
        """Take a body (and, for the tissue, its attachments and cuts) out, before the first
        step (e.g. to measure a scene without its tissue)."""
        if self.history:
            raise RuntimeError("remove_body must come before the first step")
        body = self.body(name)
        del self.bodies[name]
        if body is self.tissue:
            self.tissue = None
        self._state = None
        self._system = None
        self._changed()

    def body(self, name: str | None = None, kinds: tuple[str, ...] = ()):
        """The body called ``name``; None: the only body (of ``kinds``, if given)."""
        if name is not None:
            if name not in self.bodies:
                raise InputError(
                    f"unknown body {validate.short(name)}; bodies: {list(self.bodies)}"
                )
            b = self.bodies[name]
            if kinds and b.kind not in kinds:
                raise InputError(f"body {name!r} is a {b.kind} body; this needs {kinds}")
            return b
        candidates = [b for b in self.bodies.values() if not kinds or b.kind in kinds]
        if len(candidates) != 1:
            what = f"{'/'.join(kinds)} " if kinds else ""
            raise InputError(
                f"the simulation has {len(candidates)} {what}bodies "
                f"({[b.name for b in candidates]}); name one with body="
            )
        return candidates[0]

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
                parts[name] = (state.x[old.config_slices[j]], state.v[old.tangent_slices[j]])
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
        self._system = System([b.model for b in bodies], names, attachments, ties)
        if self.contact is not None:
            self._system.contact = self._contact_model()
        self._system_dirty = False
        x, v = [], []
        for b in bodies:
            c0, v0 = parts.get(b.name) or (self._initial_config(b), b.velocity)
            x.append(c0)
            v.append(v0)
        t = self.start_time if state is None else state.time
        self._state = State(t, np.concatenate(x), np.concatenate(v))
        if old is None or old.pattern is not self._system.pattern:
            self._solver = None  # the pattern changed: a new symbolic analysis

    def _contact_model(self):
        """The contact model over every FEM body's surface and every frame body's embedded
        surface (a frame body without one, and the tissue, take no part)."""
        from tissuesim.contact.model import ContactModel
        from tissuesim.contact.surfaces import fem_surface, frame_surface

        s, settings = self._system, self.contact
        surfaces = []
        for j, name in enumerate(s.names):
            body, choice = self.bodies[name], settings.surfaces.get(name)
            config, tangent = s.config_slices[j], s.tangent_slices[j]
            if body.kind == "fem":
                surfaces.append(fem_surface(name, s.bodies[j], config.start, tangent.start, choice))
            elif body.kind == "frames" and body.surface is not None:
                embedding = body.embedded["surface"]
                surfaces.append(
                    frame_surface(
                        name,
                        s.bodies[j],
                        embedding,
                        body.surface.triangles,
                        config,
                        tangent,
                        choice,
                    )
                )
            elif choice is not None:
                raise InputError(
                    f"contact surfaces: body {name!r} has no contact surface (a frame body "
                    "needs an embedded surface, embed_surface; the tissue takes no part)"
                )
        named = {sf.name for sf in surfaces}
        unknown = set(settings.surfaces) - set(s.names)
        if unknown:
            raise InputError(
                f"contact surfaces: no body {sorted(unknown)[0]!r} (bodies in contact: "
                f"{', '.join(sorted(named))})"
            )
        if not surfaces:
            raise InputError(
                "contact acts on FEM bodies and frame bodies with an embedded surface; this "
                "simulation has none"
            )
        return ContactModel(surfaces, list(self.obstacles), settings, s.n_dofs)

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
        return [
            self.bodies[name].step_energies(
                t, None if c_pred is None else c_pred[s.config_slices[j]], h
            )
            for j, name in enumerate(s.names)
        ]

    def _check_supported(self) -> None:
        """A quasistatic solve that nothing holds has no solution (SciPy would return finite
        garbage): refuse it."""
        s = self.system
        if len(s.bodies) == 1 and self._active()[0].kind == "fem":
            from tissuesim.time.quasistatic import check_supported

            check_supported(s.bodies[0])
            return
        springs = any(b.kind == "frames" and b.model.springs for b in self._active())
        spring_graspers = any(b.kind == "fem" and b.spring_graspers for b in self._active())
        if not (s.prescribed_dofs.size or springs or spring_graspers):
            raise InputError(
                "a quasistatic solve needs supports, fixed or prescribed frames, or springs, to "
                "hold the bodies against rigid motions; add fix(...) / fix_frames(...) or use "
                "backward_euler"
            )

    _stability_checked = None  # the system whose explicit stability limit was checked

    def _check_stability(self) -> None:
        """Explicit steps far above the stability limit blow up: refuse them before the first
        step. The estimate is within 21 % of the true limit 2 / omega_max on the test meshes
        (benchmarks/results/explicit_limit.md), so above STABILITY_MARGIN times it no run is
        stable; between 1 and that a warning, and the blow-up check of each step stands."""
        limit = self.critical_time_step()
        h = self.time_step
        if h > STABILITY_MARGIN * limit:
            raise InputError(
                f"time_step {h:g} s is {h / limit:.3g} x the explicit stability limit (estimate "
                f"{limit:.3g} s); explicit steps would blow up: use time_step <= "
                f"{0.9 * limit:.3g} s, or integrator = backward_euler"
            )
        if h > limit:
            warnings.warn(
                f"time_step {h:g} s is above the explicit stability estimate {limit:.3g} s; the "
                "run stops if the energy grows without bound",
                UserWarning,
                stacklevel=3,
            )

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
        from tissuesim.time.steps import explicit_step, implicit_step

        tol = 1e-9 * self.time_step  # a release at t_n counts for the step from t_n
        for body in self.bodies.values():
            if body.kind == "fem":
                body.release_graspers(self.time + tol)
        s = self.system
        if self.integrator == "quasistatic":
            self._check_supported()
        if self.explicit and self._stability_checked is not s:
            self._check_stability()
            self._stability_checked = s
        start = wallclock.perf_counter()
        t0 = self.time
        explicit_gradient: dict = {}
        if self.explicit:
            solver = None

            def step_fn(system, state, h, solver, options):
                return explicit_step(
                    system,
                    state,
                    h,
                    energies=self.step_energies,
                    limit=self.critical_time_step,
                    keep=explicit_gradient,
                )
        else:
            solver = self._linear_solver()
            step_fn = functools.partial(
                implicit_step,
                dynamic=self.integrator == "backward_euler",
                energies=self.step_energies,
                budget=budget,
            )
        self._state, records, substeps = advance(
            step_fn,
            s,
            self._state,
            self.time_step,
            solver,
            self.newton,
            self.max_step_halvings,
            self._end_time(),
        )
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
        if s.contact is not None:
            extra["contact"] = self._contact_report(s.contact, self._state.x, extra["forces"])
        if self.tissue is not None:
            extra.update(self._tissue_step(t0))
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

    def _contact_report(self, contact, x: np.ndarray, forces: dict) -> dict[str, Any]:
        """The step's contact figures, and the time split since the last report."""
        stats = contact.stats
        depths = {}
        if any(is_probe(ob) for ob in contact.obstacles):  # the bodies' vertices only then
            n = contact.n_deformable
            bodies, rest = contact.vertices(x)[:n], contact.rest[:n]
            depths = self._indentation.depths(contact.obstacles, bodies, rest, self.time, forces)
        distance, pairs = contact.proximity(x)
        report = {
            "min_distance": distance,
            "active_pairs": pairs,
            "candidates_and_barrier_s": stats.candidates_and_barrier_s,
            "candidates_s": stats.candidates_s,
            "ccd_s": stats.ccd_s,
            "barrier_evaluations": stats.evaluations,
            "ccd_calls": stats.ccd_calls,
            "friction_solves": stats.friction_solves,
            "stiffness_Pa": contact.kappa,
            "indentation_depth": depths,
        }
        contact.reset_stats()
        return report

    def _end_time(self) -> float:
        """start + (k + 1) h for a state at start + k h (no running sum: ten steps of 0.1 end
        at 1.0); a state off that grid (set by hand, or a changed time_step) steps to t + h."""
        h, t = self.time_step, self._state.time
        k = round((t - self.start_time) / h)
        if abs(self.start_time + k * h - t) <= 1e-9 * h:
            return self.start_time + (k + 1) * h
        return t + h

    def _static_gradient(self) -> np.ndarray | None:
        """Explicit steps have no Newton gradient: the reactions come from the static balance
        at the new state (one gradient evaluation, only when there are forces to report)."""
        if not self._force_names:
            return None
        s = self.system
        energies = self.step_energies(self.time, None, self.time_step)
        return s.evaluate(self._state.x, 1, False, energies).gradient

    def _tissue_step(self, t0: float) -> dict[str, Any]:
        tissue = self.tissue
        events = []
        if tissue.model is not None:
            j = self.system.index(tissue.name)
            z = self.system.body_config(self._state.x, j)

            def rebuild() -> np.ndarray | None:
                self._build()
                if tissue.model is None:  # all of it torn or cut: no longer in the system
                    return None
                return self.system.body_config(self._state.x, self.system.index(tissue.name))

            events = tissue.topology(z, t0, self.time, rebuild)
            if tissue.model is None:  # all tissue gone: the organs go on alone
                self._build()
        return {
            "attachment_gap": self.attachment_gap() if tissue.model is not None else 0.0,
            "tissue_points": int(tissue.dissection.alive.sum()),
            "attachments": int(sum(a.n for a in self.system.attachments)),
            "events": events,
        }

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
    ) -> list[StepRecord]:
        """Run ``steps`` time steps; with ``output``, write per body a VTU series on rest
        positions, summary.json, forces.csv / forces.png and (``render``) final.png and run.gif
        coloured by ``field`` ("J", "von_mises", "displacement", "green_strain";
        ``io/run_output.py``)."""
        from tissuesim.io.run_output import RunOutput

        writer = RunOutput(self, output, every=every, render=render, field=field, metadata=metadata)
        self.run_time_split = writer.time_split  # filled in as the run goes (s)
        return writer.run(steps, progress=progress)

    def linear_solver_info(self) -> dict[str, Any]:
        """The linear solver in use (None before the first implicit step) and why."""
        return {"name": getattr(self._solver, "name", None), "reason": self.solver_reason}

    def describe(self) -> dict[str, Any]:
        s = self.system
        return {
            "integrator": self.integrator,
            "time_step": self.time_step,
            "start_time": self.start_time,
            "gravity": [g.tolist() for g in self.gravity],
            "bodies": {name: b.describe() for name, b in self.bodies.items()},
            "n_dofs": s.n_dofs,
            "prescribed_dofs": int(s.prescribed_dofs.size),
            "newton": asdict(self.newton),
            "linear_solver": self.linear_solver_info(),
            "contact": None if s.contact is None else s.contact.describe(),
        }
