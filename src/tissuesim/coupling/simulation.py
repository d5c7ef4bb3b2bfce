"""CoupledSimulation: organs (FEM), the connective tissue between them (frames), graspers,
supports, cuts and tearing, advanced in time by one Newton solve per step.

    sim = CoupledSimulation(time_step=0.02, gravity=(0, 0, -9.81))
    sim.add_organ("liver", ellipsoid(...), make_material(...), density=1050)
    sim.add_organ("gallbladder", ...)
    sim.fix("liver", vertices)                       # a support: its reaction is reported
    sim.grasp("gallbladder", vertices, lambda t: (0, 0, 0.01 * t))   # retraction
    sim.add_tissue(make_material(...), thickness=0.006, spacing=0.002, frames=30)
    sim.add_cut(lambda t: blade_polyline(t), start=1.0, end=2.0)
    sim.run(150, "out")

See docs/coupling.md for every choice (penalty attachment, visibility cuts, reactions).
"""

from __future__ import annotations

import functools
import time as wallclock
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from tissuesim.constraints.dirichlet import DirichletCondition
from tissuesim.coupling.attachment import Attachment
from tissuesim.coupling.cutting import CutTool, Dissection, sweep_triangles
from tissuesim.coupling.integrators import coupled_step
from tissuesim.coupling.system import CoupledSystem
from tissuesim.energies.loads import ExternalForce, Gravity
from tissuesim.energies.mass import Inertia, MassKind
from tissuesim.energies.vertex_springs import VertexSprings
from tissuesim.frames.loads import FrameGravity
from tissuesim.frames.model import FrameModel
from tissuesim.frames.placement import farthest_point_frames
from tissuesim.frames.sampling import IntegrationPoints
from tissuesim.materials.base import Material
from tissuesim.mesh.boundary import facet_measures
from tissuesim.mesh.mesh import Mesh
from tissuesim.simulation import StepRecord
from tissuesim.solve.linear import make_linear_solver
from tissuesim.solve.newton import NewtonOptions
from tissuesim.time.retry import advance, validate_stepping
from tissuesim.time.state import State

__all__ = ["CoupledSimulation", "Grasper"]

CoupledIntegrator = Literal["backward_euler", "quasistatic"]
Motion = Callable[[float], np.ndarray]

# default penalty of the attachment per unit contact area, in units of the tissue's shear
# modulus / sample spacing (about 100 E / spacing): stiff enough that the gap stays ~1% of the
# tissue's own stretch, soft enough for a well-conditioned Hessian
ATTACHMENT_FACTOR = 250.0
# after a cut or tear, tissue points the new weights leave this compressed (or inverted) are
# removed with the cut: their energy is infinite or near it
MIN_J_AFTER_CUT = 0.05


@dataclass(frozen=True, eq=False)
class Grasper:
    """Retraction of ``vertices`` of an organ by ``displacement(t)`` (3,) m, rigidly: either
    prescribed (stiffness None) or through zero-length springs of ``stiffness`` N/m per vertex
    to the moving targets."""

    name: str
    organ: str
    vertices: np.ndarray
    displacement: Motion
    stiffness: float | None = None

    def springs(self, rest: np.ndarray) -> VertexSprings:
        X = rest[self.vertices]
        return VertexSprings(
            self.vertices, float(self.stiffness), lambda t: X + _vector(self.displacement(t))
        )


@dataclass(eq=False)
class _Organ:
    name: str
    mesh: Mesh
    material: Material
    density: float
    mass: MassKind
    supports: dict[str, np.ndarray] = field(default_factory=dict)
    graspers: list[Grasper] = field(default_factory=list)


@dataclass(eq=False)
class _Tissue:
    material: Material
    samples: IntegrationPoints
    frames: np.ndarray
    density: float
    frame_type: str
    shape: str
    radius_factor: float
    attach_distance: float
    attachment_stiffness: float  # Pa/m (N/m per m^2 of contact)
    # per organ with contact: rest points, cells, barycentric, stiffness
    contacts: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = field(
        default_factory=list
    )


def _facet_samples(
    points: np.ndarray, facets: np.ndarray, spacing: float
) -> tuple[np.ndarray, np.ndarray]:
    """Attachment points on triangles: each split into n^2 similar sub-triangles with edges
    <= spacing, one point (with its area) at each sub-triangle's centroid."""
    P = points[facets]  # (m, 3, 3)
    edge = np.linalg.norm(P - np.roll(P, 1, axis=1), axis=2).max(axis=1)
    area = facet_measures(points, facets)
    out_p, out_a = [], []
    for n in np.unique(np.maximum(1, np.ceil(edge / spacing)).astype(int)):
        sel = np.ceil(edge / spacing).clip(min=1).astype(int) == n
        # centroids of the n^2 sub-triangles in barycentric coordinates (up and down ones)
        i, k = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        up = i + k <= n - 1
        b_up = np.stack([i[up] + 1 / 3, k[up] + 1 / 3], axis=1) / n
        down = i + k <= n - 2
        b_down = np.stack([i[down] + 2 / 3, k[down] + 2 / 3], axis=1) / n
        b = np.concatenate([b_up, b_down])  # (n^2, 2)
        w = np.column_stack([1 - b.sum(axis=1), b])  # (n^2, 3)
        out_p.append(np.einsum("sv,mvi->msi", w, P[sel]).reshape(-1, 3))
        out_a.append(np.repeat(area[sel] / n**2, len(w)))
    return np.concatenate(out_p), np.concatenate(out_a)


def _vector(value) -> np.ndarray:
    v = np.asarray(value, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"a grasper displacement must be 3 finite numbers (m), got {value!r}")
    return v


class CoupledSimulation:
    """Organs, connective tissue, graspers, supports, cuts and tearing in one implicit system.

    integrator: "backward_euler" (default) or "quasistatic". time_step: s.
    gravity: (3,) m/s^2 on every body, or None.
    """

    def __init__(
        self,
        *,
        integrator: CoupledIntegrator = "backward_euler",
        time_step: float = 0.01,
        gravity: Sequence[float] | None = None,
        newton: NewtonOptions | None = None,
        max_step_halvings: int = 6,
        start_time: float = 0.0,
        backend: str = "auto",
    ) -> None:
        if integrator not in ("backward_euler", "quasistatic"):
            raise ValueError(
                f"integrator must be 'backward_euler' or 'quasistatic' for coupled scenes, "
                f"not {integrator!r}"
            )
        self.time_step, self.max_step_halvings = validate_stepping(time_step, max_step_halvings)
        self.integrator = integrator
        self.gravity = None if gravity is None else np.asarray(gravity, dtype=float)
        if self.gravity is not None and (
            self.gravity.shape != (3,) or not np.all(np.isfinite(self.gravity))
        ):
            raise ValueError(f"gravity must be 3 finite numbers (m/s^2), got {gravity!r}")
        self.newton = newton or NewtonOptions()
        self.backend = backend
        self.start_time = float(start_time)
        self._organs: dict[str, _Organ] = {}
        self._tissue: _Tissue | None = None
        self.cuts: list[CutTool] = []
        self.tear_threshold: float | None = None
        self.system: CoupledSystem | None = None
        self.state: State | None = None
        self.dissection: Dissection | None = None
        self.history: list[StepRecord] = []
        self._solver = None
        self.solver_reason = ""
        self._last_gradient: np.ndarray | None = None
        self._cut_world: list[np.ndarray] = []  # swept triangles as cut, world coordinates
        self._rest_blades: dict[str, np.ndarray] = {}  # each tool's last blade, rest coordinates

    # -- set-up -------------------------------------------------------------------------------
    def _editable(self, what: str) -> None:
        if self.system is not None:
            raise RuntimeError(f"{what} must come before the first step")

    def add_organ(
        self,
        name: str,
        mesh: Mesh,
        material: Material,
        *,
        density: float = 1000.0,
        mass: MassKind = "consistent",
    ) -> None:
        """An organ: a tetrahedral mesh (``mesh.box``, ``mesh.ellipsoid``, ``read_mesh``) of
        one material; density in kg/m^3."""
        self._editable("add_organ")
        if name in self._organs or name == "tissue":
            raise ValueError(f"organ name {name!r} is taken; choose another")
        if mesh.dim != 3:
            raise ValueError(f"organ {name!r}: coupled scenes are 3D; the mesh is {mesh.dim}D")
        if not (np.isfinite(density) and density > 0):
            raise ValueError(f"organ {name!r}: density must be > 0 kg/m^3, got {density!r}")
        self._organs[name] = _Organ(name, mesh, material, float(density), mass)

    def _organ(self, name: str) -> _Organ:
        if name not in self._organs:
            raise ValueError(f"unknown organ {name!r}; organs: {sorted(self._organs)}")
        return self._organs[name]

    def _vertices(self, organ: _Organ, vertices, what: str) -> np.ndarray:
        v = np.unique(np.asarray(vertices, dtype=np.int64).ravel())
        if v.size == 0:
            raise ValueError(f"{what} on organ {organ.name!r} selects no vertices")
        if v.min() < 0 or v.max() >= organ.mesh.n_points:
            raise ValueError(
                f"{what} on organ {organ.name!r}: vertex {int(v.max())} out of range "
                f"(the mesh has {organ.mesh.n_points} vertices)"
            )
        return v

    def fix(self, organ: str, vertices, name: str | None = None) -> str:
        """Clamp ``vertices`` of an organ (a support); its reaction force is reported per step
        under ``name`` (default "<organ>.support")."""
        self._editable("fix")
        o = self._organ(organ)
        name = name or f"{organ}.support"
        o.supports[name] = self._vertices(o, vertices, "fix")
        return name

    def grasp(
        self,
        organ: str,
        vertices,
        displacement: Motion | Sequence[float],
        *,
        stiffness: float | None = None,
        name: str = "grasper",
    ) -> Grasper:
        """Retract: move ``vertices`` by ``displacement(t)`` (3,) m (a callable, or a constant
        vector). stiffness None prescribes the motion; a number (N/m per vertex) pulls through
        springs to the moving targets. The grasper's force is reported per step."""
        self._editable("grasp")
        o = self._organ(organ)
        if any(g.name == name for x in self._organs.values() for g in x.graspers):
            raise ValueError(f"a grasper named {name!r} exists; give another name")
        if not callable(displacement):
            const = _vector(displacement)
            displacement = functools.partial(lambda c, t: c, const)
        if stiffness is not None and not (np.isfinite(stiffness) and stiffness > 0):
            raise ValueError(f"grasper {name!r}: stiffness must be > 0 N/m, got {stiffness!r}")
        g = Grasper(name, organ, self._vertices(o, vertices, "grasp"), displacement, stiffness)
        o.graspers.append(g)
        return g

    def add_tissue(
        self,
        material: Material,
        *,
        samples: IntegrationPoints | None = None,
        thickness: float | None = None,
        spacing: float | None = None,
        region: Callable[[np.ndarray], np.ndarray] | None = None,
        frames: int | np.ndarray = 24,
        density: float = 1000.0,
        frame_type: str = "affine",
        shape: str = "wendland",
        radius_factor: float = 1.5,
        attach_distance: float | None = None,
        attachment_stiffness: float | None = None,
    ) -> None:
        """The connective tissue: integration points ``samples``, or sampled between the organs
        (``sample_between``: outside every organ, within ``thickness`` of two of them, inside
        ``region`` if given) at ``spacing``; ``frames``: a count (farthest-point placement) or
        (n, 3) rest origins. frame_type "affine" (default) or "rigid": a layer between organs
        is stretched nearly uniformly, which affine frames represent exactly (patch test) and
        rigid frames blended by Shepard weights do not. It is attached to every organ on the
        boundary triangles within ``attach_distance`` (default: 1.5 spacing) of a tissue point,
        at points no farther apart than the spacing, with a penalty of
        ``attachment_stiffness`` N/m per m^2 of contact (default 250 mu / spacing)."""
        self._editable("add_tissue")
        if self._tissue is not None:
            raise ValueError("the scene has a tissue already; one tissue body per scene")
        if not self._organs:
            raise ValueError("add the organs before the tissue that connects them")
        from tissuesim.coupling.layer import contact_facets, sample_between

        meshes = [o.mesh for o in self._organs.values()]
        if samples is None:
            if thickness is None or spacing is None:
                raise ValueError(
                    "add_tissue needs samples=, or thickness= and spacing= to sample the layer "
                    "between the organs"
                )
            samples = sample_between(meshes, thickness, spacing, region=region)
        if spacing is None:
            spacing = float(np.cbrt(np.median(samples.volumes)))
        if isinstance(frames, int | np.integer):
            if frames < 1 or frames > samples.n:
                raise ValueError(
                    f"frames must be between 1 and the number of tissue points ({samples.n}), "
                    f"got {frames}"
                )
            frames = farthest_point_frames(samples.points, int(frames))
        frames = np.asarray(frames, dtype=float)
        attach_distance = float(1.5 * spacing if attach_distance is None else attach_distance)
        if attachment_stiffness is None:
            attachment_stiffness = ATTACHMENT_FACTOR * material.mu / spacing
        elif not (np.isfinite(attachment_stiffness) and attachment_stiffness > 0):
            raise ValueError(
                f"attachment_stiffness must be > 0 N/m per m^2 of contact, got "
                f"{attachment_stiffness!r}; leave it out for 250 shear moduli / spacing"
            )
        self._spacing = float(spacing)
        tissue = _Tissue(
            material,
            samples,
            frames,
            float(density),
            frame_type,
            shape,
            float(radius_factor),
            attach_distance,
            float(attachment_stiffness),
        )
        from tissuesim.mesh.locate import closest_boundary_points

        for j, o in enumerate(self._organs.values()):
            facets = contact_facets(o.mesh, samples.points, attach_distance)
            if len(facets) == 0:
                continue
            points, area = _facet_samples(o.mesh.points, facets, spacing)
            where = closest_boundary_points(o.mesh, points)
            tissue.contacts.append(
                (j, where.positions, where.cells, where.barycentric, attachment_stiffness * area)
            )
        if not tissue.contacts:
            raise ValueError(
                f"the tissue touches no organ: no organ boundary triangle lies within "
                f"attach_distance {attach_distance:g} m of a tissue point; increase "
                "attach_distance or move the tissue against the organs"
            )
        self._tissue = tissue

    def add_cut(
        self,
        blade: Callable[[float], np.ndarray],
        start: float,
        end: float,
        *,
        kerf: float | None = None,
        name: str = "cut",
    ) -> CutTool:
        """Dissect: ``blade(t)`` -> (k, 3) polyline (m) swept through the tissue for
        start <= t <= end; kerf (m, default: half the tissue's sample spacing) is the width
        of material it removes."""
        self._editable("add_cut")
        if self._tissue is None:
            raise ValueError("add_cut cuts the tissue: call add_tissue first")
        if not end > start:
            raise ValueError(f"cut {name!r}: end ({end}) must be after start ({start})")
        if kerf is None:
            kerf = 0.5 * float(np.cbrt(np.median(self._tissue.samples.volumes)))
        elif not (np.isfinite(kerf) and kerf >= 0):
            raise ValueError(
                f"cut {name!r}: kerf must be >= 0 m (the width the blade removes), got {kerf!r}"
            )
        tool = CutTool(blade, float(start), float(end), float(kerf), name)
        tool.positions(start)  # a malformed blade fails here
        self.cuts.append(tool)
        return tool

    def set_tearing(self, threshold: float) -> None:
        """Tissue integration points whose largest principal Green strain passes
        ``threshold`` are removed after the step (tearing)."""
        if not (np.isfinite(threshold) and threshold > 0):
            raise ValueError(f"tearing threshold must be a strain > 0, got {threshold!r}")
        self.tear_threshold = float(threshold)

    # -- building ----------------------------------------------------------------------------
    @property
    def organ_names(self) -> list[str]:
        return list(self._organs)

    def build(self) -> None:
        """Assemble the bodies, attachments and the global system (done by the first step;
        call it to inspect ``system`` earlier). Set-up methods are refused afterwards."""
        if self.system is not None:
            return
        if not self._organs:
            raise ValueError("the scene has no organs: add_organ first")
        self._models = []
        for o in self._organs.values():
            from tissuesim.model import Model

            conditions = [
                DirichletCondition(v, lambda X, t: np.zeros_like(X)) for v in o.supports.values()
            ]
            for g in o.graspers:
                if g.stiffness is None:
                    conditions.append(
                        DirichletCondition(
                            g.vertices,
                            functools.partial(
                                lambda d, X, t: np.broadcast_to(_vector(d(t)), X.shape),
                                g.displacement,
                            ),
                        )
                    )
            loads = [Gravity(self.gravity)] if self.gravity is not None else []
            self._models.append(
                Model(o.mesh, o.material, o.density, o.mass, loads, conditions, self.backend)
            )
        self._springs = [
            [g.springs(o.mesh.points) for g in o.graspers if g.stiffness is not None]
            for o in self._organs.values()
        ]
        tissue_z = None
        if self._tissue is not None:
            t = self._tissue
            self.dissection = Dissection(
                len(t.frames), t.samples.n, [len(c[1]) for c in t.contacts]
            )
            self._radii = None
            model = self._tissue_model()
            self._radii = model.shapes.radii
            tissue_z = model.rest_config()
        self.system = self._make_system(model if self._tissue is not None else None)
        organs = np.concatenate([m.rest_positions() for m in self._models])
        c = organs if tissue_z is None else np.concatenate([organs, tissue_z])
        self.state = State(self.start_time, c, np.zeros(self.system.n_dofs))
        self._solver = None

    def _tissue_model(self) -> FrameModel | None:
        t, d = self._tissue, self.dissection
        ids = np.flatnonzero(d.alive)
        if ids.size == 0:
            return None
        loads = [FrameGravity(self.gravity)] if self.gravity is not None else []
        return FrameModel(
            t.frames,
            IntegrationPoints(t.samples.points[ids], t.samples.volumes[ids], t.samples.source),
            t.material,
            density=t.density,
            frame_kind=t.frame_type,
            shape=t.shape,
            radius=self._radii,
            radius_factor=t.radius_factor,
            backend=self.backend,
            loads=loads,
            keep_pair=d.point_filter(),
            allow_orphans=True,
        )

    def _make_system(self, tissue: FrameModel | None) -> CoupledSystem:
        attachments = []
        if tissue is not None:
            d = self.dissection
            for slot, (organ, points, cells, bary, k) in enumerate(self._tissue.contacts):
                ids = np.flatnonzero(d.attachment_alive[slot])
                if ids.size == 0:
                    continue
                emb = tissue.embed(
                    points[ids], "attachment point", keep_pair=d.attachment_filter(slot)
                )
                attachments.append(
                    Attachment(organ, points[ids], cells[ids], bary[ids], k[ids], emb, ids)
                )
        return CoupledSystem(self._models, self.organ_names, tissue, attachments)

    # -- state -------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.start_time if self.state is None else self.state.time

    def organ_positions(self, name: str) -> np.ndarray:
        """Current vertex positions (n, 3) of an organ."""
        self.build()
        j = self.organ_names.index(self._organ(name).name)
        return self.system.organ_x(self.state.x, j).reshape(-1, 3)

    @property
    def tissue_samples(self) -> IntegrationPoints | None:
        """The tissue's original integration points (rest), before any cut or tear."""
        return None if self._tissue is None else self._tissue.samples

    @property
    def cut_surface(self) -> np.ndarray:
        """Triangles (m, 3, 3) the blades swept through so far, in world coordinates as cut."""
        return np.concatenate(self._cut_world) if self._cut_world else np.zeros((0, 3, 3))

    @property
    def graspers(self) -> list[Grasper]:
        return [g for o in self._organs.values() for g in o.graspers]

    @property
    def tissue(self) -> FrameModel | None:
        self.build()
        return self.system.tissue

    def tissue_fields(self) -> dict[str, np.ndarray]:
        """At the alive tissue integration points: positions, F, J, Green strain, energy
        density, the largest principal strain and the points' stable ids."""
        tissue = self.tissue
        if tissue is None:
            return {}
        fields = tissue.point_fields(self.system.tissue_z(self.state.x))
        fields["max_principal_strain"] = np.linalg.eigvalsh(fields["green_strain"])[:, -1]
        fields["ids"] = np.flatnonzero(self.dissection.alive)
        return fields

    def attachment_gap(self) -> float:
        """Largest distance (m) between where the organ and the tissue put an attachment
        point: the penalty's violation."""
        gap = 0.0
        for a in self.system.attachments:
            organ = self.system.organs[a.organ]
            y = a.organ_positions(organ.mesh.cells, self.system.organ_x(self.state.x, a.organ))
            p = a.tissue.positions(self.system.tissue_z(self.state.x))
            gap = max(gap, float(np.linalg.norm(p - y, axis=1).max()))
        return gap

    def forces(self) -> dict[str, list[float]]:
        """Force (N) each grasper and support applies to its organ at the current state (the
        reaction of prescribed vertices; the springs' pull for spring graspers)."""
        self.build()
        out: dict[str, list[float]] = {}
        g = self._last_gradient
        for j, o in enumerate(self._organs.values()):
            off = self.system.organ_slices[j].start
            x = self.system.organ_x(self.state.x, j)
            for name, v in o.supports.items():
                out[name] = self._reaction(g, off, v)
            springs = iter(self._springs[j])  # the spring graspers' energies, in order
            for gr in o.graspers:
                if gr.stiffness is None:
                    out[gr.name] = self._reaction(g, off, gr.vertices)
                else:
                    out[gr.name] = next(springs).force(x, self.time).tolist()
        return out

    @staticmethod
    def _reaction(gradient, off: int, vertices: np.ndarray) -> list[float]:
        if gradient is None:
            return [0.0, 0.0, 0.0]
        dofs = off + vertices[:, None] * 3 + np.arange(3)
        return gradient[dofs].sum(axis=0).tolist()

    def energies(self) -> dict[str, float]:
        acc = self.system.evaluate(self.state.x, 0)
        out = dict(acc.terms)
        kinetic = 0.0
        for j, m in enumerate(self.system.organs):
            v = self.state.v[self.system.organ_slices[j]]
            kinetic += 0.5 * float(v @ m.mass.dot(v))
        if self.system.tissue is not None:
            kinetic += self.system.tissue.kinetic_energy(
                self.system.tissue_z(self.state.x), self.state.v[self.system.tissue_tangent]
            )
        out["kinetic"] = kinetic
        return out

    # -- stepping ----------------------------------------------------------------------------
    def _linear_solver(self):
        if self._solver is None:
            self._solver, self.solver_reason = make_linear_solver(
                self.newton.linear_solver, self.system.n_dofs, 3, None
            )
        return self._solver

    def _energies(self, t1: float, c_pred: np.ndarray | None, h: float):
        organ = []
        for j, m in enumerate(self.system.organs):
            e = [ExternalForce(m.external_force(t1))]
            e += [s.energy(t1) for s in self._springs[j]]
            if c_pred is not None:
                e.append(Inertia(m.mass, c_pred[self.system.organ_slices[j]], h))
            organ.append(e)
        tissue = []
        if self.system.tissue is not None:
            tm = self.system.tissue
            tissue.append(ExternalForce(tm.external_force(t1)))
            if c_pred is not None:
                tissue.append(Inertia(tm.mass, c_pred[self.system.tissue_config], h))
        return organ, tissue

    def _keep_gradient(self, gradient: np.ndarray) -> None:
        self._last_gradient = gradient

    def step(self) -> StepRecord:
        """Advance one time step (halving on failure), then apply cuts and tearing."""
        self.build()
        solver = self._linear_solver()
        start = wallclock.perf_counter()
        t0 = self.time
        step_fn = functools.partial(
            coupled_step,
            dynamic=self.integrator == "backward_euler",
            energies=self._energies,
            on_converged=self._keep_gradient,
        )
        self.state, records, substeps = advance(
            step_fn,
            self.system,
            self.state,
            self.time_step,
            solver,
            self.newton,
            self.max_step_halvings,
            self.start_time + (len(self.history) + 1) * self.time_step,
        )
        forces = self.forces()
        events = self._topology(t0, self.time)
        fields = self.tissue_fields()
        min_J = min(
            float(m.elastic.jacobians(self.system.organ_x(self.state.x, j)).min())
            for j, m in enumerate(self.system.organs)
        )
        if fields:
            min_J = min(min_J, float(fields["J"].min()))
        record = StepRecord.build(
            len(self.history) + 1,
            self.time,
            records,
            substeps,
            start,
            solver,
            energies=self.energies(),
            min_J=min_J,
            extra={
                "forces": forces,
                "attachment_gap": self.attachment_gap(),
                "tissue_points": int(self.dissection.alive.sum()) if self.dissection else 0,
                "attachments": int(sum(a.n for a in self.system.attachments)),
                "events": events,
            },
        )
        self.history.append(record)
        return record

    def _topology(self, t0: float, t1: float) -> list[dict]:
        """Cuts swept during (t0, t1] and tearing at t1; rebuild the tissue if anything
        changed. The state is kept: frames stay where they are, only who acts where changes."""
        if self.system.tissue is None:
            return []
        d = self.dissection
        events = []
        t = self._tissue
        for tool in self.cuts:
            last = self._rest_blades.get(tool.name)
            count = None if last is None else len(last)
            world = tool.blades(t0, t1, self._spacing, count)
            if world is None:
                continue
            rest = self._to_rest(world.reshape(-1, 3)).reshape(world.shape)
            if last is not None:
                # continue the cut surface from where the last step left it: the rest-space
                # map changes between steps, and a seam would leave a strip uncut
                rest[0] = last
            self._rest_blades[tool.name] = rest[-1]
            triangles = sweep_triangles(rest)
            # the part of the sweep that passes beyond the tissue cuts nothing
            pts = t.samples.points
            lo, hi = pts.min(axis=0) - self._spacing, pts.max(axis=0) + self._spacing
            inside = np.all((triangles.max(axis=1) >= lo) & (triangles.min(axis=1) <= hi), axis=1)
            triangles = triangles[inside]
            if not len(triangles):
                self._cut_world.append(sweep_triangles(world))
                events.append({"kind": "cut", "tool": tool.name, "time": t1})
                continue
            report = d.cut(
                triangles,
                tool.kerf,
                t.frames,
                t.samples.points,
                [c[1] for c in t.contacts],
                self._radii,
            )
            self._cut_world.append(sweep_triangles(world))
            events.append({"kind": "cut", "tool": tool.name, "time": t1, **report})
        if self.tear_threshold is not None:
            f = self.tissue_fields()
            torn = f["ids"][f["max_principal_strain"] > self.tear_threshold]
            if torn.size:
                events.append({"kind": "tear", "time": t1, **d.tear(torn)})
        changed = any(
            e.get(k, 0)
            for e in events
            for k in ("removed_points", "severed_pairs", "retired_frames", "removed_attachments")
        ) or any(e["kind"] == "tear" for e in events)
        if not changed:  # the blade is still outside the tissue: nothing to rebuild
            return events
        inverted, report = 0, {}
        for _ in range(10):
            more = d.consolidate(
                t.frames, t.samples.points, [c[1] for c in t.contacts], self._radii, t.shape
            )
            report = {k: report.get(k, 0) + v for k, v in more.items()}
            self._rebuild()
            # renormalised weights change F at once; a point they leave inverted (at the lips
            # of a cut) has no finite neo-Hookean energy: it is removed like the kerf
            f = self.tissue_fields()
            if not f:
                break
            bad = f["ids"][~((f["J"] > MIN_J_AFTER_CUT) & np.isfinite(f["energy_density"]))]
            if not bad.size:
                break
            d.alive[bad] = False
            inverted += int(bad.size)
        events[-1].update(report)
        events[-1]["inverted_points_removed"] = inverted
        return events

    def _to_rest(self, w: np.ndarray) -> np.ndarray:
        """Rest positions of world points w (k, 3) in the tissue: X_s + F_s^-1 (w - p_s) with
        s the nearest integration point now (first-order inverse of the deformation)."""
        from scipy.spatial import cKDTree

        tissue = self.system.tissue
        f = tissue.point_fields(self.system.tissue_z(self.state.x))
        _, s = cKDTree(f["positions"]).query(w)
        dX = np.linalg.solve(f["F"][s], (w - f["positions"][s])[:, :, None])[:, :, 0]
        return tissue.samples.points[s] + dX

    def _rebuild(self) -> None:
        old = self.system
        tissue = self._tissue_model()
        n_org = old.tissue_config.start
        z, vz = self.state.x[old.tissue_config], self.state.v[old.tissue_tangent]
        self.system = self._make_system(tissue)
        if tissue is None:  # all tissue gone: the organs go on alone (output keeps its last look)
            x, v = self.state.x[:n_org], self.state.v[:n_org]
        else:
            x = np.concatenate([self.state.x[:n_org], z])
            v = np.concatenate([self.state.v[:n_org], vz])
        self.state = State(self.state.time, x, v)
        self._solver = None  # the pattern changed: a new symbolic analysis

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
        """Run ``steps`` steps; with ``output``, write VTU series of the organs, the tissue
        points and the cut surface, summary.json with the forces per step, and (``render``)
        final.png and run.gif (PyVista, off-screen)."""
        from tissuesim.coupling.output import CoupledRunOutput

        writer = CoupledRunOutput(self, output, every=every, render=render, metadata=metadata)
        return writer.run(steps, progress=progress)

    def describe(self) -> dict[str, Any]:
        s = self.system
        out: dict[str, Any] = {
            "discretisation": "coupled",
            "integrator": self.integrator,
            "time_step": self.time_step,
            "gravity": None if self.gravity is None else self.gravity.tolist(),
            "organs": {
                o.name: {
                    "vertices": o.mesh.n_points,
                    "tetrahedra": o.mesh.n_cells,
                    "material": repr(o.material),
                    "density": o.density,
                    "supports": {k: int(v.size) for k, v in o.supports.items()},
                    "graspers": {
                        g.name: {
                            "vertices": int(g.vertices.size),
                            "kind": "prescribed" if g.stiffness is None else "spring",
                        }
                        for g in o.graspers
                    },
                }
                for o in self._organs.values()
            },
            "n_dofs": None if s is None else s.n_dofs,
            "prescribed_dofs": None if s is None else int(s.prescribed_dofs.size),
            "newton": asdict(self.newton),
            "linear_solver": {
                "name": getattr(self._solver, "name", None),
                "reason": self.solver_reason,
            },
            "cuts": [
                {"name": c.name, "start": c.start, "end": c.end, "kerf": c.kerf} for c in self.cuts
            ],
            "tear_threshold": self.tear_threshold,
        }
        if self._tissue is not None:
            t = self._tissue
            out["tissue"] = {
                "material": repr(t.material),
                "density": t.density,
                "integration_points": t.samples.n,
                "volume": t.samples.volume,
                "frames": len(t.frames),
                "frame_type": t.frame_type,
                "shape_functions": t.shape,
                "attachment": "penalty (zero-length springs, barycentric in organ tetrahedra)",
                "attachment_stiffness_per_area": t.attachment_stiffness,
                "attachment_points": {self.organ_names[c[0]]: int(len(c[1])) for c in t.contacts},
            }
        return out
