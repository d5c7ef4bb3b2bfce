"""A Model: mesh, kinematics, material, mass, loads and conditions, set up once.

Everything constant across Newton iterations and time steps is built here: shape gradients,
the CSR sparsity pattern with its scatter maps, the mass matrix, the elimination index sets.
``evaluate`` sums the energies at a point; the time integrators add inertia and call Newton.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.assembly.pattern_renewal import renew_pattern
from tissuesim.backend import resolve_backend
from tissuesim.constraints.dirichlet import (
    DirichletCondition,
    Elimination,
    PrescribedDofs,
    constant_displacement,
)
from tissuesim.energies.accumulator import Accumulator
from tissuesim.energies.elastic import ElasticEnergy
from tissuesim.energies.mass import MassKind, MassMatrix
from tissuesim.energies.mean_dilatation import MeanDilatationEnergy
from tissuesim.errors import InputError
from tissuesim.kinematics.p1 import P1Kinematics
from tissuesim.kinematics.p2 import P2Kinematics
from tissuesim.materials.base import Material
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import check_memory, positive_field, short

__all__ = ["Model"]


#: bytes a model needs per cell before any factorisation (measured: 2.7 KB per triangle,
#: 9.8 KB per tetrahedron with its sparsity pattern and scatter maps); keys (dim, order), and
#: the cell type for Q1 cells (estimated from their arrays, not measured: a hexahedron has 8
#: points of 8 x 3 gradients and a 24 x 24 scatter)
MODEL_BYTES_PER_CELL = {
    (2, 1): 2500,
    (3, 1): 9000,
    (2, 2): 8000,
    (3, 2): 40000,
    "quad": 6000,
    "hexahedron": 30000,
    # quadratic ones, estimated the same way (3^d points of nv x d gradients, their scatter)
    "quad8": 12000,
    "quad9": 14000,
    "hexahedron20": 90000,
    "hexahedron27": 160000,
    # wedges, estimated the same way (6 points of 6 x 3 gradients, an 18 x 18 scatter)
    "wedge": 18000,
}


def _kinematics(mesh: Mesh, rest: tuple | None = None, formulation: str = "displacement"):
    if formulation == "shell":  # FEBio's quad8 shells on hexahedron20 cells
        from tissuesim.kinematics.shell import ShellKinematics

        return ShellKinematics.from_mesh(mesh)
    if mesh.cell_type == "wedge":
        from tissuesim.kinematics.wedge import WedgeKinematics

        return WedgeKinematics.from_mesh(mesh)
    if not mesh.simplicial and mesh.order == 2:
        from tissuesim.kinematics.q2 import Q2Kinematics

        return Q2Kinematics.from_mesh(mesh)
    if not mesh.simplicial:
        from tissuesim.kinematics.q1 import Q1Kinematics

        return Q1Kinematics.from_mesh(mesh)
    if mesh.order == 1:
        return P1Kinematics.from_mesh(mesh, rest)
    return P2Kinematics.from_mesh(mesh)


@dataclass(eq=False)
class Model:
    mesh: Mesh
    material: Material
    density: np.ndarray  # (m,) kg/m^3 (kg/m^2 per unit thickness in 2D)
    mass_kind: MassKind = "consistent"
    loads: list = field(default_factory=list)
    conditions: Sequence[DirichletCondition] = ()
    backend: str = "auto"  # "auto", "numba" or "numpy" (see backend.py)
    #: or "mean_dilatation" (energies/mean_dilatation.py), or "shell": hexahedron20 cells read
    #: as FEBio's quad8 shells (kinematics/shell.py; their thickness midside nodes held)
    formulation: str = "displacement"
    #: P1 cells' (shape gradients, rest measures) when known: a cut's copies keep their parent's
    rest: tuple | None = field(default=None, repr=False)
    #: (pattern, cells) of the P1 model this one replaces and, per cell, the cell of it with
    #: the same nodes (-1 none): a cut renews only the pattern's rows it touched
    renew: tuple | None = field(default=None, repr=False)
    #: (k, 2) vertex pairs coupled outside the cells (discrete springs,
    #: ``energies/node_springs.py``): their blocks join the pattern
    links: np.ndarray | None = field(default=None, repr=False)
    #: several regions, (name, cells, material, formulation, density) each (``model_regions``):
    #: ``material``, ``formulation`` and ``density`` are then the regions' defaults
    regions: tuple | None = field(default=None, repr=False)
    parts: list | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        cells = self.mesh.n_cells
        key = (self.mesh.dim, self.mesh.order) if self.mesh.simplicial else self.mesh.cell_type
        check_memory(
            cells * MODEL_BYTES_PER_CELL[key],
            f"a model of {self.mesh.source} ({cells} cells)",
            "Use a coarser mesh.",
        )
        if self.regions is not None:
            from tissuesim.model_regions import build_regions

            build_regions(self, _kinematics, resolve_backend)
            self.set_conditions(self.conditions)
            return
        self.density = positive_field(self.density, "density", self.mesh.n_cells, "kg/m^3")
        self.kinematics = _kinematics(self.mesh, self.rest, self.formulation)
        if hasattr(self.material, "bind"):  # internal variables per integration point
            self.material = self.material.bind(
                self.kinematics.weights.size, self.mesh.dim, self.mesh.n_cells
            )
        cells = self.mesh.n_cells
        if self.formulation == "shell":  # 18 points of 60 x 60 Hessians per cell: as many
            cells *= 18 * 25  # tetrahedra's work (1 point, 12 x 12) as "auto" weighs its size
        self.backend, self.backend_reason = resolve_backend(self.backend, cells, self.mesh.dim)
        if self.formulation in ("displacement", "shell"):
            self.elastic = ElasticEnergy(
                self.kinematics, self.material, stencil_id=0, backend=self.backend
            )
            extra = None
        elif self.formulation == "mean_dilatation":
            self.elastic = MeanDilatationEnergy(self.kinematics, self.material)
            extra = self.elastic.extra_entries()
        else:
            raise InputError(
                f"formulation must be 'displacement', 'mean_dilatation' or 'shell', not "
                f"{short(self.formulation)}"
            )
        pattern = None
        stencils = [self.kinematics.cell_stencil]
        if self.links is not None and len(self.links):
            from tissuesim.energies.node_springs import spring_stencil

            link = spring_stencil(self.links, self.mesh.dim)
            stencils.append(link.astype(self.kinematics.cell_stencil.dtype))
        elif self.renew is not None and extra is None and self.mesh.simplicial:
            pattern = renew_pattern(*self.renew, self.mesh.cells, self.mesh.n_points)
        self.pattern = pattern or SparsityPattern.from_stencils(
            self.kinematics.n_dofs, stencils, extra
        )
        if extra is not None:
            self.elastic.set_pattern(self.pattern)
        self._mass = None  # built at first use (``mass``)
        self.set_conditions(self.conditions)

    @property
    def mass(self) -> MassMatrix:
        """The mass matrix over ``pattern`` (of ``density``, ``mass_kind``), built at first
        use: a quasistatic run's parameter copies (identification/sensitivity.py) never need
        it (half of a copy's build on a bar of 8 regions)."""
        if self._mass is None:
            if self.parts is not None:
                from tissuesim.model_regions import region_mass

                self._mass = region_mass(self.parts, self.pattern, self.mass_kind)
            else:
                self._mass = MassMatrix.build(
                    self.kinematics, self.density, self.pattern, self.mass_kind
                )
        return self._mass

    @mass.setter
    def mass(self, value: MassMatrix) -> None:
        self._mass = value

    def set_conditions(self, conditions: Sequence[DirichletCondition]) -> None:
        self.conditions = tuple(conditions)
        held = self.conditions
        if self.formulation == "shell":  # the midside nodes through the thickness: no energy
            nodes = self.kinematics.thickness_midsides()
            zero = constant_displacement([0.0] * 3)
            midsides = DirichletCondition(nodes, zero, name="the shells' thickness midsides")
            held = (*held, midsides)
        elif self.parts is not None:
            from tissuesim.model_regions import shell_midsides

            nodes = shell_midsides(self.parts)
            if nodes.size:
                zero = constant_displacement([0.0] * 3)
                midsides = DirichletCondition(nodes, zero, name="the shells' thickness midsides")
                held = (*held, midsides)
        self.prescribed = PrescribedDofs.build(held, self.mesh.points)
        self.elimination = Elimination.build(self.pattern, self.prescribed.dofs)

    @property
    def n_dofs(self) -> int:
        return self.kinematics.n_dofs

    # -- the body interface shared with FrameModel (system.py) --------------------------------
    @property
    def n_config(self) -> int:
        return self.kinematics.n_dofs

    @property
    def tangent_pattern(self) -> SparsityPattern:
        return self.pattern

    @property
    def prescribed_dofs(self) -> np.ndarray:
        return self.prescribed.dofs

    @property
    def scale_points(self) -> np.ndarray:
        return self.mesh.points

    def rest_config(self) -> np.ndarray:
        return self.rest_positions()

    @staticmethod
    def retract(x: np.ndarray, dx: np.ndarray) -> np.ndarray:
        return x + dx

    @staticmethod
    def difference(x1: np.ndarray, x0: np.ndarray) -> np.ndarray:
        return x1 - x0

    def apply_prescribed(self, x: np.ndarray, t: float) -> np.ndarray:
        """x with the prescribed DOFs at their values at time t."""
        if not self.prescribed.dofs.size:
            return x
        out = x.copy()
        out[self.prescribed.dofs] = self.prescribed.positions(t)
        return out

    def kinetic_energy(self, x: np.ndarray, v: np.ndarray) -> float:
        return 0.5 * float(v @ self.mass.dot(v))

    @cached_property
    def length_scale(self) -> float:
        """Bounding-box diagonal of the rest mesh (m)."""
        p = self.mesh.points
        return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))

    @cached_property
    def force_scale(self) -> float:
        """A model force, mu * volume / length (N), for absolute tolerances."""
        return float(self.material.mu * self.kinematics.weights.sum() / self.length_scale)

    def unit_mass(self) -> MassMatrix:
        """Consistent mass matrix of unit density (integrates vertex fields against N^a)."""
        if not hasattr(self, "_unit_mass") and self.parts is not None:
            from tissuesim.model_regions import region_mass

            self._unit_mass = region_mass(self.parts, self.pattern, "consistent", unit=True)
        if not hasattr(self, "_unit_mass"):
            self._unit_mass = MassMatrix.build(
                self.kinematics, np.ones(self.mesh.n_cells), self.pattern, "consistent"
            )
        return self._unit_mass

    def external_force(self, t: float) -> np.ndarray:
        """Sum of dead loads at time t, flat (n_dofs,) in N."""
        f = np.zeros((self.mesh.n_points, self.mesh.dim))
        for load in self.loads:
            part = load.nodal_forces(self, t)
            if not np.all(np.isfinite(part)):
                what = type(load).__name__.lower().replace("nodalforces", "nodal force")
                raise InputError(
                    f"the {what} on {self.mesh.source} is not finite at t = {t:g} s; check its "
                    "value or expression"
                )
            f += part
        return f.ravel()

    def new_accumulator(self, order: int, project: bool = False) -> Accumulator:
        return Accumulator(self.pattern, order, project)

    #: Rayleigh damping (alpha 1/s, beta s) or None (``time/attempts/history.py``)
    damping: tuple[float, float] | None = None
    _step_damping = None  # the damping energy of the step in progress

    def begin_step(self, x: np.ndarray, h: float) -> None:
        """A step of ``h`` s from positions x starts: the material's history is frozen for it
        and the Rayleigh damping about x is set up (``time/attempts/history.py``)."""
        for material in self._materials():
            if hasattr(material, "begin_step"):
                material.begin_step(h)
        if self.damping is not None:
            from tissuesim.energies.damping import RayleighDamping

            self._step_damping = RayleighDamping.at(self, x, h, *self.damping)

    def end_step(self, x: np.ndarray | None) -> None:
        """The step ended at positions x (None: it was rejected): the material's history is
        updated once, and the damping term dropped."""
        self._step_damping = None
        if x is None:
            return
        if self.parts is not None:
            for p in self.parts:
                if hasattr(p.material, "accept_step"):
                    p.material.accept_step(p.kinematics.deformation_gradients(x))
        elif hasattr(self.material, "accept_step"):
            self.material.accept_step(self.kinematics.deformation_gradients(x))

    def lagged_materials(self) -> bool:
        """Whether a region's material lags something in a step (a reactive viscoelastic
        law's recruitment: ``relag_materials``)."""
        return any(getattr(m, "lagged", False) for m in self._materials())

    def relag_materials(self, x: np.ndarray, tolerance: float) -> bool:
        """Re-lag the materials' lagged terms at positions x (a converged solve: Newton's
        relag, ``time/lags.py``); whether any moved by more than ``tolerance``."""
        changed = False
        for material, kinematics in self._lagged_regions():
            changed = material.relag(kinematics.deformation_gradients(x), tolerance) or changed
        return changed

    def materials_lag_moved(self, x: np.ndarray) -> float:
        """How far the materials' lagged terms are from their values at positions x."""
        return max((m.lag_moved(k.deformation_gradients(x)) for m, k in self._lagged_regions()),
                   default=0.0)  # fmt: skip

    def _lagged_regions(self) -> list:
        """(material, kinematics) of each region whose material lags a term in a step."""
        regions = [(self.material, self.kinematics)] if self.parts is None else [
            (p.material, p.kinematics) for p in self.parts
        ]  # fmt: skip
        return [(m, k) for m, k in regions if getattr(m, "lagged", False)]

    def lag_coupling(self, x: np.ndarray):
        """d(gradient)/dx through the materials' lagged terms at their fixed point x (sparse,
        the body's DOFs; None where no material lags): per integration point the rank-one
        w (dP/dX_lag : grad N_a) (dX/dF : grad N_b) (``lag_derivatives``), unsymmetric."""
        from tissuesim.kinematics.nodal import NodalKinematics

        rows, cols, vals = [], [], []
        for material, kinematics in self._lagged_regions():
            if not isinstance(kinematics, NodalKinematics) or not hasattr(
                material, "lag_derivatives"
            ):
                raise InputError(
                    f"{material.name} with a lagged recruitment on {self.mesh.source}: its "
                    "sensitivities are taken on solid elements with the law itself (not in a "
                    "mixture or on shells); use finite differences of whole runs"
                )
            F = kinematics.deformation_gradients(x)
            dP, dX = material.lag_derivatives(F)
            u = kinematics.stress_to_gradient(dP)  # (q, nloc): w G^a_j dP_ij
            v = np.matmul(kinematics.grads, np.swapaxes(dX, 1, 2)).reshape(len(F), -1)
            st = kinematics.stencil
            rows.append(np.repeat(st, st.shape[1], axis=1).ravel())
            cols.append(np.tile(st, (1, st.shape[1])).ravel())
            vals.append((u[:, :, None] * v[:, None, :]).ravel())
        if not vals:
            return None
        import scipy.sparse as sp

        n = self.kinematics.n_dofs
        return sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
        )

    def _materials(self) -> list:
        """The material of each region (one without regions)."""
        return [self.material] if self.parts is None else [p.material for p in self.parts]

    def evaluate(self, x: np.ndarray, order: int, project: bool, energies=()) -> Accumulator:
        """Elastic energy plus ``energies`` (inertia, loads, ...) at x, and in a step the
        Rayleigh damping."""
        acc = self.new_accumulator(order, project)
        self.elastic.accumulate(x, acc)
        if self._step_damping is not None:
            self._step_damping.accumulate(x, acc)
        for energy in energies:
            energy.accumulate(x, acc)
        return acc

    def rest_positions(self) -> np.ndarray:
        return self.mesh.points.ravel().copy()
