"""What the output asks of a FEM body (a mixin of ``FemBody``): per-element and per-point
fields, the smallest J, the description in summary.json; a body of several regions answers
region by region (``bodies/regions.py``)."""

from __future__ import annotations

import numpy as np

from tissuesim.materials.measures import continuum_fields

__all__ = ["FemOutput"]


class FemOutput:
    """Mixed into ``FemBody`` (``model``, ``mesh``, ``conditions``, ``graspers``)."""

    def cell_fields(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Per element: J, green_strain, cauchy_stress, von_mises, energy_density
        (``materials/measures.py``); for P2 the volume averages over each element's points;
        with regions also ``region`` (each cell's region, in the order they were given)."""
        if self.model.parts is not None:
            from tissuesim.bodies.regions import region_cell_fields

            return region_cell_fields(self.model, x)
        K = self.model.kinematics
        return {k: K.cell_average(v) for k, v in self.quadrature_fields(x).items()}

    def quadrature_fields(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """``cell_fields`` at each integration point (``kinematics.points_per_cell``
        consecutive points per element), before their average; with regions, region by
        region (``cell_means`` takes them to the cells)."""
        if self.model.parts is not None:
            from tissuesim.bodies.regions import region_quadrature_fields

            return region_quadrature_fields(self.model, x)
        K = self.model.kinematics
        fields = continuum_fields(self.model.material, K.deformation_gradients(x))
        if self.model.formulation == "mean_dilatation":  # the patch pressure, not the point's
            from tissuesim.materials.measures import von_mises

            fields["cauchy_stress"] = fields[
                "cauchy_stress"
            ] + self.model.elastic.cauchy_correction(x)
            fields["von_mises"] = von_mises(fields["cauchy_stress"])
            fields["energy_density"] = self.model.elastic.point_energy_density(x)
        return fields

    def cell_means(self, values: np.ndarray) -> np.ndarray:
        """Values at the points of ``quadrature_fields`` -> each cell's mean over its points,
        in the mesh's cell order."""
        if self.model.parts is not None:
            from tissuesim.bodies.regions import region_cell_means

            return region_cell_means(self.model, values)
        K = self.model.kinematics
        return K.per_cell_sum(values) / K.points_per_cell

    def min_J(self, x: np.ndarray) -> float:
        return float(self.model.elastic.jacobians(x).min())

    def _regions(self) -> dict:
        parts = self.model.parts
        if parts is None:
            return {}
        return {"regions": {p.name: {"cells": int(p.cells.size), "material": repr(p.material),
                                     "formulation": p.formulation} for p in parts}}  # fmt: skip

    def describe(self) -> dict:
        from tissuesim.mesh.io import describe_mesh

        return {
            "kind": "fem",
            "mesh": describe_mesh(self.mesh),
            "material": repr(self.model.material),
            **self._regions(),
            "mass": self.model.mass_kind,
            "prescribed_dofs": int(self.model.prescribed.dofs.size),
            "prescribed_sets": {n: int(c.vertices.size) for n, c in self.conditions},
            "graspers": {
                g.name: "prescribed" if g.stiffness is None else "spring" for g in self.graspers
            },
            "backend": {
                "name": self.model.backend,
                "reason": self.model.backend_reason,
                "fused_elastic": self.model.elastic.fused,
            },
        }
