"""Regions of one FEM model: cells of one material and formulation each, on the body's one
vertex array and DOF block (``Model(regions=...)``).

Each region is a model part on the mesh's points and its own cells: its kinematics, its
material (bound to its own integration points), its elastic energy over its own stencil of
the body's one sparsity pattern (stencil k for region k), its mass on that stencil. The
model's energy, gradient, Hessian and mass are the sums over the regions; a loop over
regions, each batched over its cells. The model's ``kinematics`` is the whole mesh's (the
displacement form: loads' and pictures' cell weights), ``material`` a ``RegionMaterials``
whose moduli are the stiffest region's (force and penalty scales).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.energies.elastic import ElasticEnergy
from tissuesim.energies.mass import MassMatrix
from tissuesim.energies.mean_dilatation import MeanDilatationEnergy
from tissuesim.errors import InputError
from tissuesim.materials.base import Material
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import positive_field, short

__all__ = ["Region", "RegionPart", "RegionElastic", "RegionMaterials", "build_regions"]

FORMULATIONS = ("displacement", "mean_dilatation", "shell")


@dataclass(frozen=True, eq=False)
class Region:
    """One region of a FEM body: ``cells`` (indices into the body mesh's cells, or the name
    of one of its cell sets), its ``material``, ``formulation`` and ``density`` (kg/m^3, a
    number or one per cell of the region); None: the body's."""

    cells: object
    material: Material
    formulation: str | None = None
    density: float | np.ndarray | None = None


@dataclass(eq=False)
class RegionPart:
    """A region as built: its name, cells (indices into the mesh's cells), kinematics on its
    cells, bound material, formulation and elastic energy (stencil ``k`` of the pattern)."""

    name: str
    cells: np.ndarray
    mesh: Mesh
    kinematics: object
    material: Material
    formulation: str
    density: np.ndarray
    elastic: object = None


class RegionElastic:
    """The elastic energy of all regions: their sums; Jacobians concatenated region by
    region (``RegionPart`` order)."""

    def __init__(self, parts: list[RegionPart]) -> None:
        self.parts = parts

    @property
    def fused(self) -> bool:
        return all(p.elastic.fused for p in self.parts)

    def accumulate(self, x: np.ndarray, acc) -> None:
        for p in self.parts:
            p.elastic.accumulate(x, acc)

    def jacobians(self, x: np.ndarray) -> np.ndarray:
        return np.concatenate([p.elastic.jacobians(x) for p in self.parts])


class RegionMaterials:
    """The materials of a body's regions, for what asks a body for one material: ``mu`` and
    ``lam`` the largest over the regions (stiffness and penalty scales), ``cell_mu`` and
    ``cell_lam`` each cell's region's (mesh order)."""

    def __init__(self, parts: list[RegionPart]) -> None:
        self.parts = parts
        self.mu = max(float(np.max(p.material.mu)) for p in parts)
        self.lam = max(float(np.max(p.material.lam)) for p in parts)
        n = sum(p.cells.size for p in parts)  # per cell (mesh order), for per-cell scales
        self.cell_mu, self.cell_lam = np.zeros(n), np.zeros(n)
        for p in parts:
            self.cell_mu[p.cells] = float(np.max(p.material.mu))
            self.cell_lam[p.cells] = float(np.max(p.material.lam))
        if any(hasattr(p.material, "accept_step") for p in parts):  # a region's history:
            self.accept_step = self._accept_step  # the steps then call Model.begin/end_step
        if any(hasattr(p.material, "state_arrays") for p in parts):  # checkpoints ask
            self.state_arrays, self.set_state_arrays = self._state_arrays, self._set_state_arrays

    def _accept_step(self, F: np.ndarray) -> None:
        raise InputError(
            "the regions' histories are updated region by region (Model.end_step), not from "
            "one F of the body"
        )

    def _state_arrays(self) -> dict[str, np.ndarray]:
        """Each region's history, its keys prefixed "r<k>_" (k: the region's index)."""
        out = {}
        for k, p in enumerate(self.parts):
            if hasattr(p.material, "state_arrays"):
                out.update({f"r{k}_{key}": v for key, v in p.material.state_arrays().items()})
        return out

    def _set_state_arrays(self, arrays: dict[str, np.ndarray]) -> None:
        for k, p in enumerate(self.parts):
            if hasattr(p.material, "set_state_arrays"):
                own = {key.removeprefix(f"r{k}_"): v for key, v in arrays.items()
                       if key.startswith(f"r{k}_")}  # fmt: skip
                p.material.set_state_arrays(own)

    def __repr__(self) -> str:
        inner = ", ".join(f"{p.name}={p.material!r}" for p in self.parts)
        return f"Regions({inner})"


def build_regions(model, kinematics_of, resolve_backend) -> None:
    """Set ``model``'s parts, kinematics, elastic energy, material, backend, pattern and mass
    from ``model.regions`` (a sequence of (name, cells, material, formulation, density) with
    cells indices into ``model.mesh``'s cells, every cell in exactly one region)."""
    mesh = model.mesh
    m = mesh.n_cells
    owner = np.full(m, -1)
    for k, (name, cells, *_rest) in enumerate(model.regions):
        cells = np.asarray(cells)
        if (owner[cells] >= 0).any():
            other = model.regions[owner[cells][owner[cells] >= 0][0]][0]
            raise InputError(f"region {name!r}: cells also in region {other!r}")
        owner[cells] = k
    if (owner < 0).any():
        raise InputError(
            f"cell {int(np.flatnonzero(owner < 0)[0])} of {mesh.source} is in no region; "
            "give every cell one region"
        )
    body_density = positive_field(model.density, "density", m, "kg/m^3")
    parts: list[RegionPart] = []
    density = body_density.copy()
    for name, cells, material, formulation, rho in model.regions:
        cells = np.asarray(cells, dtype=np.int64)
        if formulation not in FORMULATIONS:
            raise InputError(
                f"region {name!r}: formulation must be one of {FORMULATIONS}, not "
                f"{short(formulation)}"
            )
        if rho is not None:
            density[cells] = positive_field(rho, f"region {name!r} density", cells.size, "kg/m^3")
        sub = Mesh(mesh.points, mesh.cells[cells], source=f"{mesh.source} region {name!r}")
        K = kinematics_of(sub, None, formulation)
        if hasattr(material, "bind"):  # internal variables per integration point
            material = material.bind(K.weights.size, mesh.dim, cells.size)
        parts.append(RegionPart(name, cells, sub, K, material, formulation, density[cells]))
    model.density = density
    model.parts = parts
    model.kinematics = kinematics_of(mesh, None, "displacement")
    weight = sum(p.cells.size * (18 * 25 if p.formulation == "shell" else 1) for p in parts)
    model.backend, model.backend_reason = resolve_backend(model.backend, weight, mesh.dim)
    extras = []
    for k, p in enumerate(parts):
        if p.formulation == "mean_dilatation":
            p.elastic = MeanDilatationEnergy(p.kinematics, p.material, stencil_id=k)
            extra = p.elastic.extra_entries()
            if extra is not None:
                extras.append(extra)
        else:
            p.elastic = ElasticEnergy(p.kinematics, p.material, k, model.backend)
    stencils = [p.kinematics.cell_stencil for p in parts]
    if model.links is not None and len(model.links):
        from tissuesim.energies.node_springs import spring_stencil

        link = spring_stencil(model.links, mesh.dim)
        stencils.append(link.astype(stencils[0].dtype))
    extra = None
    if extras:
        extra = (np.concatenate([e[0] for e in extras]), np.concatenate([e[1] for e in extras]))
    model.pattern = SparsityPattern.from_stencils(model.kinematics.n_dofs, stencils, extra)
    for p in parts:
        if p.formulation == "mean_dilatation":
            p.elastic.set_pattern(model.pattern)
    model.elastic = RegionElastic(parts)
    model.material = RegionMaterials(parts)
    model.mass = None  # built at first use (Model.mass)


def region_mass(parts: list[RegionPart], pattern: SparsityPattern, kind: str, unit=False):
    """The sum of the regions' mass matrices over ``pattern`` (region k on stencil k)."""
    masses = [
        MassMatrix.build(
            p.kinematics, np.ones(p.cells.size) if unit else p.density, pattern, kind, k
        )
        for k, p in enumerate(parts)
    ]
    first = masses[0]
    return MassMatrix(
        first.kind,
        pattern,
        sum(mm.data for mm in masses),
        sum(mm.lumped for mm in masses),
        sum(mm.row_sums for mm in masses),
        first.dim,
    )


def shell_midsides(parts: list[RegionPart]) -> np.ndarray:
    """The thickness midside nodes of the shell regions (held: they carry no energy)."""
    nodes = [p.kinematics.thickness_midsides() for p in parts if p.formulation == "shell"]
    if not nodes:
        return np.zeros(0, dtype=np.int64)
    solid = [p.mesh.cells.ravel() for p in parts if p.formulation != "shell"]
    return np.setdiff1d(np.concatenate(nodes), np.concatenate(solid) if solid else [])
