"""Regions of a FEM body (``Simulation.add_body(..., regions=...)``): what the API takes
(a cell set's name or cell indices, with a material and optionally a formulation and a
density) checked into the model's regions (``model_regions.py``), and the per-element output
of a body of several regions: each region's fields on its own integration points, put back
in the mesh's cell order."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from tissuesim.errors import InputError
from tissuesim.materials.base import Material
from tissuesim.materials.measures import continuum_fields, von_mises
from tissuesim.mesh.mesh import Mesh
from tissuesim.model_regions import Region
from tissuesim.validate import indices, short

__all__ = ["Region", "region_specs", "region_quadrature_fields", "region_cell_fields"]

#: the name of the region of the cells no region names, when the body has a material
DEFAULT_REGION = "default"


def _cells(mesh: Mesh, cells, what: str) -> np.ndarray:
    if isinstance(cells, str):
        if cells not in mesh.cell_sets:
            raise InputError(
                f"{what}: {cells!r} is not a cell set of {mesh.source} (its cell sets: "
                f"{sorted(mesh.cell_sets)})"
            )
        cells = mesh.cell_sets[cells]
    ids = np.unique(indices(cells, f"{what} cells", mesh.n_cells))
    if ids.size == 0:
        raise InputError(f"{what}: the cell selection is empty")
    return ids


def region_specs(
    body: str,
    mesh: Mesh,
    material: Material | None,
    regions: Mapping,
    formulation: str,
    density,
) -> tuple | None:
    """The model's regions, (name, cells, material, formulation, density) each, from
    ``regions`` {name: Region or (cells, material)}; the cells no region names make the
    region "default" of ``material`` (an error without one). None when one region holds
    every cell with the body's formulation and density (the plain one-material model)."""
    if not isinstance(regions, Mapping) or not regions:
        raise InputError(
            f"add_body {body!r}: regions must be a non-empty mapping {{name: (cells, "
            f"material)}} or {{name: Region(...)}}, not {short(regions)}"
        )
    specs, taken = [], np.zeros(mesh.n_cells, dtype=bool)
    for name, value in regions.items():
        what = f"add_body {body!r} region {name!r}"
        if not isinstance(name, str) or not name:
            raise InputError(f"add_body {body!r}: region names must be strings, not {name!r}")
        if isinstance(value, tuple) and len(value) == 2:
            value = Region(*value)
        if not isinstance(value, Region):
            raise InputError(f"{what}: give (cells, material) or a Region, not {short(value)}")
        if not isinstance(value.material, Material):
            raise InputError(f"{what}: material must be a tissuesim material (make_material)")
        cells = _cells(mesh, value.cells, what)
        if taken[cells].any():
            raise InputError(f"{what}: cell {int(cells[taken[cells]][0])} is in two regions")
        taken[cells] = True
        rho = value.density
        own_density = rho is not None
        if rho is None:
            rho = np.broadcast_to(np.asarray(density, dtype=float), (mesh.n_cells,))[cells]
        specs.append([name, cells, value.material, value.formulation or formulation, rho])
    rest = np.flatnonzero(~taken)
    if rest.size and material is None:
        raise InputError(
            f"add_body {body!r}: cell {int(rest[0])} ({rest.size} in all) is in no region; give "
            "every cell a region or the body a material for the others"
        )
    if rest.size:
        if DEFAULT_REGION in regions:
            raise InputError(f"add_body {body!r}: region name {DEFAULT_REGION!r} is the rest's")
        rho = np.broadcast_to(np.asarray(density, dtype=float), (mesh.n_cells,))[rest]
        specs.append([DEFAULT_REGION, rest, material, formulation, rho])
    if len(specs) == 1 and specs[0][3] == formulation and not own_density:
        return None  # the plain model: bit for bit the one-material body
    return tuple(tuple(s) for s in specs)


def region_quadrature_fields(model, x: np.ndarray) -> dict[str, np.ndarray]:
    """``continuum_fields`` at every integration point, region by region (each region's
    points in its cells' order; the regions in the order they were given)."""
    out: dict[str, list] = {}
    for p in model.parts:
        fields = continuum_fields(p.material, p.kinematics.deformation_gradients(x))
        if p.formulation == "mean_dilatation":  # the patch pressure, not the point's
            fields["cauchy_stress"] = fields["cauchy_stress"] + p.elastic.cauchy_correction(x)
            fields["von_mises"] = von_mises(fields["cauchy_stress"])
            fields["energy_density"] = p.elastic.point_energy_density(x)
        for k, v in fields.items():
            out.setdefault(k, []).append(np.asarray(v))
    return {k: np.concatenate(v) for k, v in out.items()}


def region_cell_means(model, values: np.ndarray) -> np.ndarray:
    """Point values in ``region_quadrature_fields``' order -> each cell's mean over its
    points (FEBio's element value), in the mesh's cell order."""
    out = np.zeros((model.mesh.n_cells, *values.shape[1:]))
    start = 0
    for p in model.parts:
        K = p.kinematics
        q = K.weights.size
        out[p.cells] = K.per_cell_sum(values[start : start + q]) / K.points_per_cell
        start += q
    return out


def region_cell_fields(model, x: np.ndarray) -> dict[str, np.ndarray]:
    """Per element in the mesh's cell order: each region's volume averages, and ``region``
    (the region's index in the order given)."""
    fields = region_quadrature_fields(model, x)
    out: dict[str, np.ndarray] = {}
    for key, values in fields.items():
        cell = np.zeros((model.mesh.n_cells, *values.shape[1:]))
        start = 0
        for p in model.parts:
            q = p.kinematics.weights.size
            cell[p.cells] = p.kinematics.cell_average(values[start : start + q])
            start += q
        out[key] = cell
    region = np.zeros(model.mesh.n_cells, dtype=np.int64)
    for k, p in enumerate(model.parts):
        region[p.cells] = k
    out["region"] = region
    return out
