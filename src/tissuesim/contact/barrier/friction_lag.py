"""IPC's lagged friction on the contact model (a mixin of ``contact.model.ContactModel``): the
normal forces and tangent bases fixed at a lag point (the step's start, then each loosely
converged Newton iterate), each pair's coefficient, and the lagged potential's value, gradient
and (PSD-clamped) Hessian over the collision mesh's vertices."""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp

__all__ = ["FrictionLag"]


class FrictionLag:
    """Mixed into ``ContactModel`` (uses its ipctk module, mesh, barrier, table, settings)."""

    def lag_friction(self, V_start: np.ndarray, V_lag: np.ndarray, h: float) -> int:
        """Fix the friction's normal forces and tangent bases at V_lag (the step's start, then
        each Newton solution) for displacements from V_start; returns the active pairs."""
        if not self.has_friction:
            self._friction = None
            return 0
        tangential = self.tangential_collisions(V_lag, self._collisions(V_lag))
        potential = self._ipctk.FrictionPotential(self.settings.eps_v * h)
        self._friction = (tangential, np.asfortranarray(V_start), potential)
        self._friction_lag_at = np.asfortranarray(V_lag)
        return len(tangential)

    def tangential_collisions(self, V_lag: np.ndarray, col):
        """The friction's collisions lagged at V_lag from the normal collisions ``col`` there:
        normal forces, tangent bases and each pair's mu."""
        tangential = self._ipctk.TangentialCollisions()
        mu = self.table.uniform_mu
        tangential.build(self.mesh, V_lag, col, self.barrier, 0.0 if mu is None else mu)
        if mu is None:
            self._pair_friction(tangential)
        return tangential

    def _pair_friction(self, tangential) -> None:
        """Each collision's mu from its pair of groups (the first and last vertex of a stencil
        lie on its two sides)."""
        E, F = self.mesh.edges, self.mesh.faces
        group, mu = self.group, self.table.mu
        for k in range(len(tangential)):
            c = tangential[k]
            ids = [i for i in c.vertex_ids(E, F) if i >= 0]
            value = float(mu[group[ids[0]], group[ids[-1]]])
            # the potential reads the lagged effective coefficients, set at build time
            c.mu_s = c.mu_k = c.mu_s_effective_lagged = c.mu_k_effective_lagged = value

    def clear_friction(self) -> None:
        """End of a step: the lagged friction is dropped, kept only to report its forces."""
        self._reported_friction, self._friction = self._friction, None

    @contextmanager
    def last_step_lag(self):
        """Within: the friction lagged as in the last step (its forces and Hessian)."""
        kept, self._friction = self._friction, self._friction or self._reported_friction
        try:
            yield
        finally:
            self._friction = kept

    def _friction_terms(self, V: np.ndarray, order: int, project: bool):
        """(value, dD/dV, d2D/dV2) of the lagged friction potential D (zeros when none)."""
        if self._friction is None or len(self._friction[0]) == 0:
            return 0.0, None, None
        tangential, V_start, potential = self._friction
        U = np.asfortranarray(V - V_start)
        value = float(potential(tangential, self.mesh, U))
        grad = potential.gradient(tangential, self.mesh, U) if order >= 1 else None
        hess = None
        if order >= 2:
            method = self._ipctk.PSDProjectionMethod
            H = potential.hessian(
                tangential, self.mesh, U, method.CLAMP if project else method.NONE
            )
            hess = sp.csr_matrix(H)
        return value, grad, hess
