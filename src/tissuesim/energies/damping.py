"""Rayleigh damping as a dissipation potential in Backward Euler's incremental potential.

The damping force -C v with C = alpha M + beta K_n (M the mass matrix, K_n the elastic
stiffness at the step's start x_n), with v = (x - x_n) / h, is the gradient of

    D(x) = 1/(2 h) (x - x_n)^T (alpha M + beta K_n) (x - x_n),

so adding D to Phi keeps the step a minimisation: its stationarity is the Backward Euler
balance M (x - x_pred)/h^2 + C (x - x_n)/h + dE/dx = f. K_n is the elastic Hessian at x_n with
each point's tangent projected to positive semi-definite (``materials/psd.py``): D is then never
negative, and K_n equals the stiffness at a stable state (at rest, for small vibrations). For a
linear system each mode (M phi = K phi / omega^2) then gets the damping ratio
alpha / (2 omega) + beta omega / 2, as Rayleigh damping does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.energies.accumulator import Accumulator

__all__ = ["RayleighDamping"]


@dataclass(frozen=True, eq=False)
class RayleighDamping:
    """D(x) = 1/(2h) (x - x_n)^T (alpha M + beta K_n) (x - x_n) over a model's pattern."""

    pattern: object  # SparsityPattern
    data: np.ndarray  # (nnz,) alpha M + beta K_n
    x_n: np.ndarray
    time_step: float

    @classmethod
    def at(cls, model, x_n: np.ndarray, h: float, alpha: float, beta: float) -> RayleighDamping:
        """The damping of a step of ``h`` s of ``model`` (``model.py``) starting at x_n."""
        data = alpha * model.mass.data
        if beta:
            acc = model.new_accumulator(2, True)
            model.elastic.accumulate(np.asarray(x_n, dtype=float), acc)
            data = data + beta * acc.hessian
        return cls(model.pattern, data, np.array(x_n, dtype=float), float(h))

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        """Add D, its gradient C (x - x_n)/h and Hessian C/h to ``acc``."""
        dx = x - self.x_n
        Cdx = self.pattern.matrix(self.data) @ dx
        acc.add_value("damping", 0.5 * float(dx @ Cdx) / self.time_step)
        if acc.order >= 1:
            acc.gradient += Cdx / self.time_step
        if acc.order >= 2:
            acc.hessian += self.data / self.time_step
