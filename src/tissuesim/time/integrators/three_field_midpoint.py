"""FEBio's three-field (mean-dilatation) shell at rhoi = 1, the midpoint rule (alpha_f = 1/2),
for a body whose elastic energy is the mean-dilatation one with a patch per element
(``energies/mean_dilatation.py``): ``FE3FieldElasticShellDomain::UpdateElementStress``.

FEBio's Cauchy stress at a point of element e is

    s = dev(F_{n+1/2}) + U'(theta_e(x_{n+1})) I + c D,
    c = ((W(F_{n+1}) - W(F_n)) / (h J) - s : D) / (D : D),

the element's dilatation theta_e = v_e / V_e taken at x_{n+1} (its shell base vectors are the
current ones), not at x_{n+1/2}; W the point's energy W_dev + U(J) (``StrainEnergyDensity`` of
an uncoupled law); J, D as in ``generalized_alpha.midpoint_correction``. It is integrated over
x_{n+1/2}: the pressure's force is U'(theta_e(x_{n+1})) dv_e/dx at y = x_{n+1/2}.

tissuesim's step in y has U'(theta_e(y)) dv_e/dx(y) instead. The pressure at x_{n+1} is stiff
(the bulk modulus), too stiff for the dead-load fixed point of ``generalized_alpha``: the step
carries it as an energy of y, ``EndPressure``: sum_e V_e [alpha_f U(theta_e(x_{n+1}(y))) -
U(theta_e(y))] with x_{n+1}(y) = x_n + (y - x_n) / alpha_f, whose gradient U'(theta_e(x_{n+1}))
dv_e/dx(x_{n+1}) - U'(theta_e(y)) dv_e/dx(y) swaps the pressure. What is left, U'(theta_e(
x_{n+1})) (dv_e/dx(y) - dv_e/dx(x_{n+1})) and the c D term, is the dead load
(``end_pressure_correction``); it changes with x_{n+1} by the pressure times the step's change
of shape, not by the bulk modulus, and settles in a few updates.

(FEBio's three-field solid, ``FE3FieldElasticSolidDomain``, corrects differently: not followed.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.energies.accumulator import Accumulator
from tissuesim.energies.elastic import scatter_point_hessians
from tissuesim.energies.mean_dilatation import MeanDilatationEnergy
from tissuesim.errors import InvertedElementError
from tissuesim.materials.isotropic._common import det

__all__ = ["EndPressure", "end_pressure_correction", "takes_end_pressure"]


def takes_end_pressure(elastic: object) -> bool:
    """A mean-dilatation energy with one patch per element and theta = J (FEBio's three-field
    element, an uncoupled law's U(J))."""
    return (
        isinstance(elastic, MeanDilatationEnergy)
        and elastic.kinematics.points_per_cell > 1
        and elastic.volumetric.theta_kind == "J"
    )


def _patch_pressure(elastic: MeanDilatationEnergy, F: np.ndarray, order: int):
    """(theta_bar (m,) = v_e / V_e; U, U', U'' there; b (m, nloc) = dv_e/dx, the element's
    sum of w_q B_q^T dJ/dF_q; dJ/dF and d2J/dF2 per point)."""
    K, vol = elastic.kinematics, elastic.volumetric
    theta, dtheta, ddtheta = vol.theta(F, max(order, 1))
    theta_bar = (elastic.C @ theta) / elastic.volumes
    U, dU, ddU = vol.energy(theta_bar, 2)
    b = K.per_cell_sum(K.stress_to_gradient(dtheta))
    return theta_bar, U, dU, ddU, b, dtheta, ddtheta


@dataclass(eq=False)
class EndPressure:
    """The energy of y that swaps the mean-dilatation pressure at y for the one at x_{n+1}
    (module docstring); x0 the body's x_n."""

    elastic: MeanDilatationEnergy
    x0: np.ndarray
    alpha_f: float

    def accumulate(self, y: np.ndarray, acc: Accumulator) -> None:
        K, af = self.elastic.kinematics, self.alpha_f
        x1 = self.x0 + (y - self.x0) / af
        try:
            end = _patch_pressure(self.elastic, K.deformation_gradients(x1), acc.order)
            mid = _patch_pressure(self.elastic, K.deformation_gradients(y), acc.order)
        except InvertedElementError:
            acc.add_value("end_pressure", np.inf)
            return
        V = self.elastic.volumes
        with np.errstate(invalid="ignore"):
            value = float(V @ (af * end[1] - mid[1]))
        acc.add_value("end_pressure", value if np.isfinite(value) else np.inf)
        if acc.order == 0 or not np.isfinite(value):
            return
        dofs = K.cell_stencil
        for (_, _, dU, ddU, b, _, ddth), sign, scale in ((end, 1.0, 1.0 / af), (mid, -1.0, 1.0)):
            acc.gradient += np.bincount(
                dofs.ravel(), weights=(sign * dU[:, None] * b).ravel(), minlength=acc.gradient.size
            )
            if acc.order < 2:
                continue
            # d2/dy2: U'' / V b b^T + U' d2v/dx2 (the latter per point: p theta''), times
            # 1 / alpha_f for the end's (x_{n+1} moves by dy / alpha_f)
            rank = sign * scale * ddU / V
            if acc.project:
                rank = np.maximum(rank, 0.0) if sign > 0 else -np.maximum(-rank, 0.0)
            blocks = rank[:, None, None] * b[:, :, None] * b[:, None, :]
            acc.pattern.accumulate(acc.hessian, self.elastic.stencil_id, blocks)
            if not acc.project:  # indefinite (the determinant's Hessian): left out then
                p = np.repeat(sign * scale * dU, K.points_per_cell)
                scatter_point_hessians(K, p[:, None, None, None, None] * ddth, acc,
                                       self.elastic.stencil_id)  # fmt: skip


def end_pressure_correction(
    elastic: MeanDilatationEnergy, x0: np.ndarray, x1: np.ndarray, h: float
) -> np.ndarray:
    """The dead load (n_dofs,) left once ``EndPressure`` swapped the pressure: FEBio's force
    less the step's (module docstring)."""
    K, material, vol = elastic.kinematics, elastic.material, elastic.volumetric
    F0, F1 = K.deformation_gradients(x0), K.deformation_gradients(x1)
    Fa = 0.5 * (F0 + F1)
    Fa_inv = np.linalg.inv(Fa)
    J = det(Fa)
    theta_1, _, dU_1, _, b_1, _, _ = _patch_pressure(elastic, F1, 1)
    b_y = _patch_pressure(elastic, Fa, 1)[4]
    # FEBio's stress: the law's at F_{n+1/2} with its point pressure U'(J) replaced by the
    # element's at x_{n+1}
    P = material.evaluate(Fa, 1).stress
    s = np.einsum("qij,qkj->qik", P, Fa) / J[:, None, None]
    p_end = (elastic.CT @ dU_1) / K.weights  # per point: its element's U'(theta_e(x_{n+1}))
    s = s + (p_end - vol.energy(J, 1)[1])[:, None, None] * np.eye(3)
    L = np.einsum("qij,qjk->qik", F1 - F0, Fa_inv) / h
    D = 0.5 * (L + np.swapaxes(L, 1, 2))
    DD = np.einsum("qij,qij->q", D, D)
    dW = material.evaluate(F1, 0).energy - material.evaluate(F0, 0).energy
    c = np.zeros_like(DD)
    on = DD > np.finfo(float).eps  # FEBio: only where D : D is above round-off
    c[on] = (dW[on] / (h * J[on]) - np.einsum("qij,qij->q", s[on], D[on])) / DD[on]
    dP = (J * c)[:, None, None] * np.einsum("qij,qkj->qik", D, Fa_inv)  # J (D c) F^-T
    local = K.per_cell_sum(K.stress_to_gradient(dP)) + dU_1[:, None] * (b_y - b_1)
    return np.bincount(K.cell_stencil.ravel(), weights=local.ravel(), minlength=K.n_dofs)
