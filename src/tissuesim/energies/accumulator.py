"""Where energies add their value, gradient and Hessian during one evaluation."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tissuesim.assembly.pattern import SparsityPattern

__all__ = ["Accumulator"]


@dataclass(eq=False)
class Accumulator:
    """Sum of energies at one point x.

    order 0: value only; 1: + gradient (n_dofs,); 2: + Hessian data (nnz,) over ``pattern``.
    project: ask energies with indefinite Hessians to project them to positive semi-definite.
    """

    pattern: SparsityPattern
    order: int
    project: bool = False
    value: float = 0.0
    gradient: np.ndarray | None = None
    hessian: np.ndarray | None = None
    terms: dict[str, float] = field(default_factory=dict)
    # Hessian terms whose sparsity changes between evaluations (contact pairs): a sparse
    # (n, n) matrix added to the pattern's matrix when Newton solves
    extra_hessian: object = None

    def __post_init__(self) -> None:
        if self.order >= 1:
            self.gradient = np.zeros(self.pattern.n)
        if self.order >= 2:
            self.hessian = np.zeros(self.pattern.nnz)

    def add_value(self, name: str, value: float) -> None:
        self.value += value
        self.terms[name] = self.terms.get(name, 0.0) + value
