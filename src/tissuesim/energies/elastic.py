"""Elastic energy E(x) = sum_q w_q psi(F_q(x)) for any kinematics and any material.

Gradient and Hessian by the chain rule through the kinematics' dF/dx (constant for P1):
    dE/dx = sum_q w_q (dF/dx)^T P,    d2E/dx2 = sum_q w_q (dF/dx)^T (dP/dF) (dF/dx).
With ``project`` the tangent dP/dF is clamped to positive semi-definite per point, which makes
every local Hessian PSD (w B^T A B with A PSD).

Two implementations (``backend.py``): the batched NumPy one below, and the fused Numba loop of
``assembly/fused_p1.py`` for the laws that have a point kernel (``assembly/fused_energy.py`` for
a law from its energy, whose kernel is generated); both compute the same sums.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InvertedElementError
from tissuesim.kinematics.nodal import NodalKinematics, local_hessians
from tissuesim.materials.base import Material
from tissuesim.materials.isotropic._common import det
from tissuesim.materials.psd import project_tangent_psd

__all__ = ["ElasticEnergy", "scatter_point_hessians"]


@dataclass(frozen=True, eq=False)
class ElasticEnergy:
    kinematics: NodalKinematics
    material: Material
    stencil_id: int = 0
    backend: str = "numpy"  # "numba" or "numpy", resolved (see backend.py)
    _law: int = field(init=False, default=-1)  # point-kernel id when the fused path applies
    _kernel: object = field(init=False, default=None)  # a generated kernel (EnergyLaw)

    def __post_init__(self) -> None:
        if self.backend == "numba":
            from tissuesim.materials.isotropic.point_kernels import LAW_IDS

            law = LAW_IDS.get(getattr(self.material, "name", ""), -1)
            registered = _registered_class(self.material)
            # a subclass that overrides evaluate() must not be replaced by the stock kernel
            if (
                law >= 0
                and registered is not None
                and (type(self.material).evaluate is registered.evaluate)
            ):
                object.__setattr__(self, "_law", law)
            elif law < 0 and _generated_kernel_law(self.material):
                kernel = self.material.point_kernel(self.kinematics.grads.shape[2])
                object.__setattr__(self, "_kernel", kernel)

    @property
    def fused(self) -> bool:
        """True when order-0/1/2 evaluations without projection run the Numba loop."""
        return self._law >= 0 or self._kernel is not None

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        if self.fused and not acc.project:
            self._accumulate_fused(x, acc)
            return
        F = self.kinematics.deformation_gradients(x)
        try:
            response = self.material.evaluate(F, min(acc.order, 2))
        except InvertedElementError:
            acc.add_value("elastic", np.inf)  # the line search backs off from here
            return
        w = self.kinematics.weights
        with np.errstate(invalid="ignore"):
            acc.add_value("elastic", float(np.dot(w, response.energy)))
        if acc.order >= 1:
            local = self.kinematics.stress_to_gradient(response.stress)
            acc.gradient += np.bincount(
                self.kinematics.stencil.ravel(), weights=local.ravel(), minlength=acc.pattern.n
            )
        if acc.order >= 2:
            A = response.tangent
            if acc.project:
                A = project_tangent_psd(A)
            scatter_point_hessians(self.kinematics, A, acc, self.stencil_id)

    def _accumulate_fused(self, x: np.ndarray, acc: Accumulator) -> None:
        K, empty = self.kinematics, np.empty(0)
        if self._kernel is not None:
            from tissuesim.assembly.fused_energy import assemble_energy

            energy, bad = assemble_energy(
                self._kernel,
                self.material.values,
                x,
                K.cells,
                K.grads,
                K.weights,
                K.points_per_cell,
                min(acc.order, 2),
                acc.pattern.scatters[self.stencil_id],
                acc.gradient if acc.order >= 1 else empty,
                acc.hessian if acc.order >= 2 else empty,
            )
            acc.add_value("elastic", float(np.inf) if bad >= 0 else float(energy))
            return
        args = [
            self._law,
            float(self.material.mu),
            float(self.material.lam),
            np.ascontiguousarray(x, dtype=float).ravel(),
            K.cells,
            K.grads,
            K.weights,
        ]
        if K.points_per_cell > 1:  # P2: an element's points summed before the scatter
            from tissuesim.assembly.fused_quadrature import assemble_points as assemble

            args.append(K.points_per_cell)
        else:
            from tissuesim.assembly.fused_p1 import assemble_p1 as assemble
        energy, bad = assemble(
            *args,
            min(acc.order, 2),
            acc.pattern.scatters[self.stencil_id],
            acc.gradient if acc.order >= 1 else empty,
            acc.hessian if acc.order >= 2 else empty,
        )
        acc.add_value("elastic", float(np.inf) if bad >= 0 else float(energy))

    def jacobians(self, x: np.ndarray) -> np.ndarray:
        """J = det F at every integration point at positions x, (q,) (P1: per element)."""
        if self.backend == "numba":
            from tissuesim.assembly.fused_p1 import element_jacobians

            K = self.kinematics
            x = np.ascontiguousarray(x, dtype=float).ravel()
            return element_jacobians(x, K.cells, K.grads)
        return det(self.kinematics.deformation_gradients(x))

    def cell_fields(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Per-element J and energy density psi (J/m^3) at positions x (P2: the element's
        volume averages over its quadrature points)."""
        K = self.kinematics
        F = K.deformation_gradients(x)
        psi = self.material.evaluate(F, 0).energy
        return {"J": K.cell_average(det(F)), "energy_density": K.cell_average(psi)}


def scatter_point_hessians(K: NodalKinematics, A: np.ndarray, acc: Accumulator, stencil_id: int):
    """Local Hessians from tangents A (q, d, d, d, d), summed per element, scattered; in
    chunks of elements so that P2's (q, 30, 30) blocks never fill memory at once."""
    nq = K.points_per_cell
    if nq == 1:
        acc.pattern.accumulate(acc.hessian, stencil_id, K.tangent_to_hessian(A))
        return
    scatter = acc.pattern.scatters[stencil_id]
    m = scatter.shape[0]
    chunk = max(1, 2_000_000 // scatter.shape[1])
    for start in range(0, m, chunk):  # a loop over chunks of elements, not elements
        stop = min(m, start + chunk)
        pts = slice(start * nq, stop * nq)
        part = local_hessians(K.grads[pts], K.weights[pts], A[pts])
        blocks = part.reshape(stop - start, nq, *part.shape[1:]).sum(axis=1)
        acc.hessian += np.bincount(
            scatter[start:stop].ravel(), weights=blocks.ravel(), minlength=acc.pattern.nnz
        )


def _generated_kernel_law(material: Material) -> bool:
    """A law from its energy (``EnergyLaw``, not a subclass that overrides evaluate)."""
    from tissuesim.materials.energy_law.energy import EnergyLaw

    return isinstance(material, EnergyLaw) and type(material).evaluate is EnergyLaw.evaluate


def _registered_class(material: Material):
    from tissuesim.materials.registry import MATERIALS

    return MATERIALS.get(getattr(material, "name", ""))
