"""An instrument's force for a small further motion, linearised at the last step's solution:
what a haptic device loop (1 kHz) renders between two deformation steps (20-100 Hz).

At the step's solution x* the free gradient of the step's incremental potential Phi(x, y)
vanishes; y are the instrument's vertex coordinates, translated rigidly by d (m). The force
the instrument exerts on the bodies, F = sum over its vertices of dPhi/dy (the barrier's and
the lagged friction's), then changes to first order as

    F(d) = F* + K d,   K = A - C^T H^-1 C   (N/m, 3 x 3, symmetric),

with H the step's Hessian over the free DOFs (inertia M / h^2, elasticity, contact: the
matrix of the last Newton iteration, solved through the kept factorisation), C = d2Phi/dx dy T
(T: the rigid translation of the instrument's vertices) and A = T^T d2Phi/dy2 T: A is the
stiffness with the organ frozen, C^T H^-1 C the part the organ's own response gives back (the
Schur complement of the step's Hessian over bodies and instrument). Three linear solves per
step, one per axis; the friction is held at its lag (as in the step: with friction_iterations
1 K is the exact derivative, with more the re-lag moves with d and K is within about 2 %). The
device loop renders -F(d) (the force on the instrument) for the device's displacement d since
the step, until the next step reports a new F* and K.

K is the derivative of the exact barrier, whose Hessian is not convex everywhere: K may have a
small negative eigenvalue (a frictionless probe sliding over a dimple). A haptic device must
render a passive (positive semi-definite) stiffness, or it feeds energy into the user's hand:
``passive_stiffness`` is K with its negative eigenvalues clamped to zero, what ``force_at``
uses unless asked for the exact K.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tissuesim.errors import InputError

__all__ = ["InstrumentLinearization", "linearize_instrument"]


@dataclass(frozen=True)
class InstrumentLinearization:
    """``force`` (N): the force the instrument exerts on the bodies at the last step's end (as
    ``Simulation.forces()``); ``stiffness`` (N/m, 3 x 3): dF/dd for a translation d of the
    instrument; ``time`` (s): the step's end."""

    name: str
    force: np.ndarray
    stiffness: np.ndarray
    time: float

    def force_at(self, displacement: Any, passive: bool = True) -> np.ndarray:
        """F* + K d (N) for a further translation d (m, 3-vector) of the instrument; K the
        ``passive_stiffness`` (for a haptic device) or with ``passive`` False the exact one."""
        d = np.asarray(displacement, dtype=float)
        if d.shape != (3,) or not np.all(np.isfinite(d)):
            given = np.array2string(np.ravel(d)[:6], precision=4)
            raise InputError(f"force_at: displacement must be 3 finite numbers (m), not {given}")
        K = self.passive_stiffness if passive else self.stiffness
        return self.force + K @ d

    @property
    def passive_stiffness(self) -> np.ndarray:
        """K with its negative eigenvalues set to zero (N/m): a stiffness a haptic device can
        render without feeding energy into the hand."""
        w, Q = np.linalg.eigh(self.stiffness)
        return (Q * np.maximum(w, 0.0)) @ Q.T

    @property
    def compliance(self) -> np.ndarray:
        """The passive K's pseudo-inverse (m/N): the instrument's motion per unit force where
        it touches (zero along directions without contact)."""
        return np.linalg.pinv(self.passive_stiffness, rcond=1e-9, hermitian=True)


def linearize_instrument(system, x: np.ndarray, name: str, energies, solver, time: float):
    """F* and K (module docstring) of obstacle ``name`` at the solution x of a step whose
    body energies (inertia about its prediction, loads) are ``energies``; ``solver`` the
    step's linear solver (a reused factor answers by CG on the current matrix)."""
    contact = system.contact
    with contact.last_step_lag():
        return _linearize(system, contact, x, name, energies, solver, time)


def _linearize(system, contact, x, name, energies, solver, time):
    import scipy.sparse as sp

    from tissuesim.solve.linear import NotPositiveDefiniteError
    from tissuesim.solve.reuse import factorize_with_update

    rows = contact.slices[name][0]
    dim = contact.dim
    force = np.asarray(contact.obstacle_forces(x)[name], dtype=float)
    V = contact.vertices(x)
    H_V = contact.vertex_terms(V, 2, False)[2]  # over every collision vertex, exact
    n_vertices = len(V)
    # T: the instrument's vertex coordinates per unit translation
    coords = dim * np.arange(rows.start, rows.stop)[:, None] + np.arange(dim)
    T = sp.csr_matrix(
        (np.ones(coords.size), (coords.ravel(), np.tile(np.arange(dim), len(coords)))),
        shape=(dim * n_vertices, dim),
    )
    HT = (H_V @ T).toarray() if H_V is not None else np.zeros((dim * n_vertices, dim))
    A = T.T @ HT
    C = contact.selection(x).T @ HT  # (n_dofs, 3): the bodies' side of d2Phi/dx dy T
    C[system.elimination.dofs] = 0.0
    stiffness = np.asarray(A, dtype=float)
    if np.any(C):
        acc = None
        for project in (False, "contact"):  # an indefinite exact Hessian: IPC's projection
            acc = system.evaluate(x, 2, project, energies)
            system.elimination.apply(acc.hessian, acc.gradient)
            matrix = acc.pattern.matrix(acc.hessian)
            update = None
            if acc.extra_hessian is not None:
                update = system.elimination.eliminate_matrix(acc.extra_hessian).tocsr()
                matrix = matrix + update
            try:  # the kept factor stays the elasticity's (solve/reuse.py)
                factorize_with_update(solver, matrix.tocsr(), update)
                Z = np.column_stack([solver.solve(C[:, k]) for k in range(dim)])
                break
            except NotPositiveDefiniteError:
                Z = None
        if Z is None:
            raise InputError(
                f"instrument {name!r}: the step's Hessian is not positive definite even with "
                "the contact part projected; no linearised force"
            )
        stiffness = stiffness - C.T @ Z
    stiffness = 0.5 * (stiffness + stiffness.T)
    return InstrumentLinearization(name, force, stiffness, float(time))
