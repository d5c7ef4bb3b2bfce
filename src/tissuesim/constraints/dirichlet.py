"""Prescribed displacements u = g(X, t) on vertex sets, and their elimination from Newton.

Elimination as in the notes (section 1.4), done in place on the fixed CSR pattern so that the
linear solver's symbolic analysis stays valid: rows and columns of prescribed DOFs are zeroed,
their diagonal set to a representative stiffness, and their gradient entries to zero, so the
Newton step leaves them where the condition put them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.errors import InputError
from tissuesim.validate import short

__all__ = ["DirichletCondition", "PrescribedDofs", "Displacement"]

#: g(X, t): rest positions (k, d) and time -> displacements (k, d).
Displacement = Callable[[np.ndarray, float], np.ndarray]


@dataclass(frozen=True, eq=False)
class DirichletCondition:
    """u = g(X, t) on ``vertices`` for the selected ``components`` (default: all)."""

    vertices: np.ndarray
    displacement: Displacement
    components: tuple[int, ...] | None = None
    name: str = "a prescribed set"  # in error messages


def constant_displacement(value: Sequence[float]) -> Displacement:
    v = np.asarray(value, dtype=float)
    if v.ndim != 1 or not np.all(np.isfinite(v)):
        raise InputError(f"a constant displacement must be finite numbers (m), not {short(value)}")

    def g(X: np.ndarray, t: float) -> np.ndarray:
        return np.broadcast_to(v, X.shape).copy()

    return g


@dataclass(frozen=True, eq=False)
class PrescribedDofs:
    """All Dirichlet conditions of a model, resolved to DOFs; later conditions win."""

    conditions: tuple[DirichletCondition, ...]
    rest_positions: np.ndarray  # (n, d)
    dofs: np.ndarray  # (k,) sorted unique prescribed DOFs
    free: np.ndarray  # (n_dofs,) bool

    @classmethod
    def build(cls, conditions: Sequence[DirichletCondition], rest_positions: np.ndarray):
        n, d = rest_positions.shape
        free = np.ones(n * d, dtype=bool)
        for c in conditions:
            comps = np.arange(d) if c.components is None else np.asarray(c.components)
            if comps.size and (comps.min() < 0 or comps.max() >= d):
                raise InputError(f"components {c.components} out of range for a {d}D mesh")
            free[(c.vertices[:, None] * d + comps).ravel()] = False
        dofs = np.flatnonzero(~free)
        return cls(tuple(conditions), rest_positions, dofs, free)

    def positions(self, t: float) -> np.ndarray:
        """Prescribed current positions X + g(X, t) of ``dofs`` at time t, (k,)."""
        n, d = self.rest_positions.shape
        x = np.full(n * d, np.nan)
        for c in self.conditions:
            X = self.rest_positions[c.vertices]
            u = np.asarray(c.displacement(X, t), dtype=float)
            if u.shape != X.shape:
                try:
                    u = np.broadcast_to(u, X.shape)
                except ValueError:
                    raise InputError(
                        f"the displacement of {c.name} gives shape {u.shape}; it must give "
                        f"one {d}-vector per vertex, shape {X.shape}"
                    ) from None
            comps = np.arange(d) if c.components is None else np.asarray(c.components)
            bad = ~np.isfinite(u[:, comps]).all(axis=1)
            if bad.any():
                k = int(np.flatnonzero(bad)[0])
                raise InputError(
                    f"the displacement of {c.name} is not finite at t = {t:g} s at "
                    f"{int(bad.sum())} of its vertices (first: rest position "
                    f"{X[k].tolist()}, u = {u[k].tolist()}); check its expression"
                )
            idx = c.vertices[:, None] * d + comps
            x[idx.ravel()] = (X[:, comps] + u[:, comps]).ravel()
        return x[self.dofs]


@dataclass(frozen=True, eq=False)
class Elimination:
    """Precomputed positions, in the CSR data array, of the entries elimination touches."""

    zero_entries: np.ndarray  # entries in a prescribed row or column
    diagonal_entries: np.ndarray  # diagonal entries of prescribed DOFs
    free_diagonal_entries: np.ndarray
    dofs: np.ndarray

    @classmethod
    def build(cls, pattern: SparsityPattern, dofs: np.ndarray) -> Elimination:
        fixed = np.zeros(pattern.n, dtype=bool)
        fixed[dofs] = True
        zero = np.zeros(0, dtype=np.int64)
        if fixed.any():  # entries in a prescribed row (the row's flag repeated) or column
            in_row = np.repeat(fixed, np.diff(pattern.indptr))
            zero = np.flatnonzero(in_row | fixed[pattern.indices])
        return cls(zero, pattern.diagonal[dofs], pattern.diagonal[~fixed], dofs)

    def eliminate_matrix(self, matrix):
        """A sparse (n, n) matrix with the rows and columns of prescribed DOFs zeroed."""
        import scipy.sparse as sp

        keep = np.ones(matrix.shape[0])
        keep[self.dofs] = 0.0
        D = sp.diags(keep)
        return D @ matrix @ D

    def apply(self, hessian: np.ndarray, gradient: np.ndarray) -> None:
        """Eliminate in place; the diagonal of prescribed DOFs gets the mean free diagonal."""
        free = hessian[self.free_diagonal_entries]  # none where every DOF is prescribed
        scale = (float(np.mean(np.abs(free))) if free.size else 0.0) or 1.0
        hessian[self.zero_entries] = 0.0
        hessian[self.diagonal_entries] = scale
        gradient[self.dofs] = 0.0
