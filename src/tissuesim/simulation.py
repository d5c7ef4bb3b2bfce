"""Simulation: the thin object users script. It builds a Model, steps it, and writes output.

sim = Simulation(mesh, CourseNeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
                 density=1.0, integrator="backward_euler", time_step=0.02)
sim.add_dirichlet(select.vertices_on_plane(mesh, axis=0, value=-1.0))
sim.add_gravity([0.0, -9.81])
sim.run(steps=100, output="out")
"""

from __future__ import annotations

import time as wallclock
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from tissuesim.constraints.dirichlet import DirichletCondition, constant_displacement
from tissuesim.energies.loads import BodyForce, Gravity, Traction, as_field
from tissuesim.energies.mass import MassKind
from tissuesim.materials.base import Material
from tissuesim.mesh.mesh import Mesh
from tissuesim.model import Model
from tissuesim.solve.linear import make_linear_solver
from tissuesim.solve.newton import NewtonOptions
from tissuesim.time.backward_euler import backward_euler_step
from tissuesim.time.quasistatic import check_supported, quasistatic_step
from tissuesim.time.retry import advance, validate_stepping
from tissuesim.time.state import State
from tissuesim.time.symplectic_euler import symplectic_euler_step

__all__ = ["Simulation", "StepRecord", "INTEGRATORS"]

Integrator = Literal["backward_euler", "quasistatic", "symplectic_euler"]
INTEGRATORS = {
    "backward_euler": backward_euler_step,
    "quasistatic": quasistatic_step,
    "symplectic_euler": symplectic_euler_step,
}


@dataclass
class StepRecord:
    """What one time step did; one entry of summary.json's "steps"."""

    step: int
    time: float
    converged: bool
    substeps: int
    newton_iterations: int
    projected_iterations: int
    residual_norms: list[list[float]]
    energies: dict[str, float]
    min_J: float
    wall_time_s: float
    linear_solver: str = ""
    extra: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def build(
        cls, step: int, time: float, records, substeps: int, start: float, solver, **fields
    ) -> StepRecord:
        """The record of a converged step from its Newton records; ``start`` is the
        perf_counter value when the step began; ``fields``: energies, min_J, extra."""
        return cls(
            step=step,
            time=time,
            converged=True,
            substeps=substeps,
            newton_iterations=sum(r.iterations for r in records),
            projected_iterations=sum(sum(r.projected) for r in records),
            residual_norms=[r.gradient_norms for r in records],
            wall_time_s=wallclock.perf_counter() - start,
            linear_solver=getattr(solver, "name", "none"),
            **fields,
        )


class Simulation:
    """A body of one material on one mesh, with loads, conditions and a time integrator.

    mesh: a validated Mesh (``tissuesim.mesh``); material: a Material.
    density: kg/m^3, a scalar or one value per element (m,).
    integrator: "backward_euler", "quasistatic" or "symplectic_euler".
    time_step: s (for quasistatics, the load-step length in "time").
    mass: "consistent" or "lumped" (symplectic Euler always uses the lumped mass).
    newton: NewtonOptions (tolerances, hessian_projection, linear_solver).
    max_step_halvings: how often a failing step is split in two before giving up.
    backend: "auto", "numba" or "numpy": who assembles the elastic energy (``backend.py``).
    """

    def __init__(
        self,
        mesh: Mesh,
        material: Material,
        *,
        density: float | np.ndarray = 1.0,
        integrator: Integrator = "backward_euler",
        time_step: float = 0.01,
        mass: MassKind = "consistent",
        newton: NewtonOptions | None = None,
        max_step_halvings: int = 6,
        start_time: float = 0.0,
        backend: str = "auto",
    ) -> None:
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {sorted(INTEGRATORS)}, not {integrator!r}")
        time_step, max_step_halvings = validate_stepping(time_step, max_step_halvings)
        if integrator == "symplectic_euler":
            mass = "lumped"  # the explicit update inverts the mass: it must be diagonal
        self.model = Model(mesh, material, density, mass, backend=backend)
        self.integrator = integrator
        self.time_step = float(time_step)
        self.newton = newton or NewtonOptions()
        self.max_step_halvings = int(max_step_halvings)
        x = mesh.points.ravel().copy()
        self.start_time = float(start_time)
        self.state = State(float(start_time), x, np.zeros_like(x))
        self._conditions: list[DirichletCondition] = []
        self._solver = None
        self.solver_reason = ""
        self.history: list[StepRecord] = []
        self._fields_state: State | None = None  # the state ``_fields`` belongs to
        self._fields: dict[str, np.ndarray] = {}
        if integrator != "symplectic_euler":
            self._linear_solver()  # an unknown or unavailable linear_solver fails here, not later

    def __repr__(self) -> str:
        return (
            f"Simulation({self.mesh.n_points} vertices, {self.mesh.n_cells} "
            f"{'triangles' if self.mesh.dim == 2 else 'tetrahedra'}, {self.model.material!r}, "
            f"{self.integrator}, "
            f"time_step {self.time_step:g} s, t = {self.time:g} s, {len(self.history)} steps, "
            f"{self.model.prescribed.dofs.size} prescribed DOFs)"
        )

    # -- set-up -------------------------------------------------------------------------------
    @property
    def mesh(self) -> Mesh:
        return self.model.mesh

    def add_dirichlet(
        self,
        vertices: np.ndarray,
        displacement: Sequence[float] | Callable[[np.ndarray, float], np.ndarray] | None = None,
        components: Sequence[int] | None = None,
    ) -> None:
        """Prescribe u = g(X, t) (m) on ``vertices``: None clamps, a vector is constant, a
        callable maps rest positions (k, d) and time to displacements (k, d). ``components``
        restricts the condition to some axes (e.g. (0,) for x only)."""
        vertices = np.asarray(vertices, dtype=np.int64).ravel()
        if vertices.size == 0:
            raise ValueError("add_dirichlet: the vertex selection is empty")
        if vertices.min() < 0 or vertices.max() >= self.mesh.n_points:
            raise ValueError(
                f"add_dirichlet: vertex indices must be in [0, {self.mesh.n_points}); "
                f"got {vertices.min()}..{vertices.max()}"
            )
        if displacement is None:
            displacement = np.zeros(self.mesh.dim)
        g = displacement if callable(displacement) else constant_displacement(displacement)
        try:
            comps = None if components is None else tuple(int(c) for c in components)
        except (TypeError, ValueError):
            raise ValueError(
                "add_dirichlet: components must be a sequence of axes, e.g. (0,), "
                f"not {components!r}"
            ) from None
        if comps is not None and (not comps or min(comps) < 0 or max(comps) >= self.mesh.dim):
            raise ValueError(
                f"add_dirichlet: components must be axes in 0..{self.mesh.dim - 1}, "
                f"not {components!r}"
            )
        self._conditions.append(DirichletCondition(vertices, g, comps))
        self.model.set_conditions(self._conditions)
        self._solver = None

    def add_traction(self, facets: np.ndarray, traction) -> None:
        """Dead traction (N/m in 2D, Pa in 3D) on boundary facets (k, d): a vector or a
        callable (X (k, d), t) -> (k, d) evaluated at the facets' vertices."""
        facets = np.asarray(facets, dtype=np.int64)
        if facets.ndim != 2 or facets.shape[1] != self.mesh.dim:
            raise ValueError(f"add_traction: facets must be (k, {self.mesh.dim}) vertex indices")
        self.model.loads.append(Traction(facets, as_field(traction)))

    def add_gravity(self, acceleration: Sequence[float]) -> None:
        """Gravity, acceleration (d,) in m/s^2, acting on the element densities."""
        g = np.asarray(acceleration, dtype=float)
        if g.shape != (self.mesh.dim,):
            raise ValueError(f"add_gravity: acceleration must have {self.mesh.dim} components")
        self.model.loads.append(Gravity(g))

    def add_body_force(self, force_density) -> None:
        """Body force per unit rest volume (N/m^3): a vector or a callable (X (n, d), t)."""
        self.model.loads.append(BodyForce(as_field(force_density)))

    def set_velocity(self, velocity) -> None:
        """Initial velocity (n, d) or a constant vector (d,), m/s."""
        v = np.broadcast_to(np.asarray(velocity, float), self.mesh.points.shape).ravel().copy()
        self.state = State(self.state.time, self.state.x, v)

    # -- results ------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.state.time

    @property
    def positions(self) -> np.ndarray:
        """Current positions (n, d) in m."""
        return self.state.x.reshape(self.mesh.points.shape)

    @property
    def displacement(self) -> np.ndarray:
        return self.positions - self.mesh.points

    @property
    def velocity(self) -> np.ndarray:
        return self.state.v.reshape(self.mesh.points.shape)

    def cell_fields(self) -> dict[str, np.ndarray]:
        """Per-element J and energy density at the current state (computed once per state)."""
        if self._fields_state is not self.state:
            self._fields = self.model.elastic.cell_fields(self.state.x)
            self._fields_state = self.state
        return self._fields

    def kinetic_energy(self) -> float:
        return 0.5 * float(self.state.v @ self.model.mass.dot(self.state.v))

    def energies(self) -> dict[str, float]:
        """Elastic, kinetic and external-load potential energy (J) at the current state."""
        acc = self.model.evaluate(self.state.x, 0, False)
        potential = -float(self.model.external_force(self.time) @ self.state.x)
        return {"elastic": acc.value, "kinetic": self.kinetic_energy(), "load_potential": potential}

    # -- stepping -----------------------------------------------------------------------------
    def _linear_solver(self):
        if self._solver is None:
            self._solver, self.solver_reason = make_linear_solver(
                self.newton.linear_solver, self.model.n_dofs, self.mesh.dim, self.mesh.points
            )
        return self._solver

    def step(self) -> StepRecord:
        """Advance one time step (with automatic halving on failure); ConvergenceError if it
        cannot. Returns the step's record (also appended to ``history``)."""
        if self.integrator == "quasistatic":
            check_supported(self.model)
        solver = self._linear_solver() if self.integrator != "symplectic_euler" else None
        start = wallclock.perf_counter()
        new_state, records, substeps = advance(
            INTEGRATORS[self.integrator],
            self.model,
            self.state,
            self.time_step,
            solver,
            self.newton,
            self.max_step_halvings,
            self.start_time + (len(self.history) + 1) * self.time_step,
        )
        self.state = new_state
        record = StepRecord.build(
            len(self.history) + 1,
            self.time,
            records,
            substeps,
            start,
            solver,
            energies=self.energies(),
            min_J=float(self.model.elastic.jacobians(self.state.x).min()),
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
        metadata: dict | None = None,
    ) -> list[StepRecord]:
        """Run ``steps`` time steps; with ``output``, write a VTU series, summary.json and
        (if ``render``) a PNG of the final frame and a GIF of the run (``io.run_output``)."""
        from tissuesim.io.run_output import RunOutput

        writer = RunOutput(self, output, every=every, render=render, metadata=metadata)
        return writer.run(steps, progress=progress)

    def describe(self) -> dict[str, Any]:
        return {
            "integrator": self.integrator,
            "time_step": self.time_step,
            "mass": self.model.mass_kind,
            "material": repr(self.model.material),
            "n_dofs": self.model.n_dofs,
            "prescribed_dofs": int(self.model.prescribed.dofs.size),
            "newton": asdict(self.newton),
            "linear_solver": {
                "name": getattr(self._solver, "name", None),
                "reason": self.solver_reason,
            },
            "backend": {
                "name": self.model.backend,
                "reason": self.model.backend_reason,
                "fused_elastic": self.model.elastic.fused,
            },
        }
