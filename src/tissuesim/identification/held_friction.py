"""Sensitivities through IPC's lagged friction, its lag converged or held (``sensitivity.py``).

A step with friction ends where the gradient of its potential, barrier and friction included,
vanishes; the friction's part is the lagged potential

    D(V, V_start) = sum_k mu_k lambda_k f0(|T_k^T (V - V_start)|)

of the collision vertices V (bodies' and obstacles'), with the normal forces lambda_k and tangent
bases T_k fixed at the lag point V_lag (the step's start, then Newton's converged points:
``contact/barrier/friction_lag.py``) and the slip measured from the step's start V_start.

What is differentiated: D's Hessian in V (exact, not PSD-clamped) in the step's Hessian; its
dependence on V_start, whose derivative is the last step's sensitivity (and the obstacles'
motion at the step's start): d(dD/dV)/dV_start = -d2D/dV2; a coefficient mu varied by a
parameter (the copies' lags are rebuilt at the base's V_lag with their own mu); and the lag
point V_lag, either taken as the step's solution ("converged", ``lag_stiffness``: IPC's
``force_jacobian`` with respect to the lagged displacements, the derivative of a run whose
friction iterations converged) or held (lambda_k and T_k constants, as IPC's lagged solve
treats them: the derivative of the solves with their lags as they were, ``hold_lags`` makes
such runs). Measured against whole runs: tests/identification/test_sensitivities_friction.py,
benchmarks/friction_sensitivity.py.
"""

from __future__ import annotations

import numpy as np

__all__ = ["HeldFriction", "hold_lags", "lag_stiffness", "start_motion"]


class HeldFriction:
    """The base run's friction lag of the step just solved, to hold in its parameter copies
    and to differentiate through its slip's start."""

    def __init__(self, contact) -> None:
        tangential, V_start, potential = contact._reported_friction
        self.V_start = np.asfortranarray(V_start)
        self.V_lag = np.asfortranarray(contact._friction_lag_at)
        self.potential = potential
        # the normal collisions at the lag point, from which each copy's lag is rebuilt
        self.collisions = contact._collisions(self.V_lag)
        # the step's terms over the collision vertices (sensitivity.py sets them): d2D/dV2
        # applied to the slip start's motion (n_V d, p), and d(dD/dV)/dV_lag where the lag
        # point is taken as the converged state (None when held)
        self.start_motion_term: np.ndarray | None = None
        self.lag_term = None

    @classmethod
    def of(cls, contact) -> HeldFriction | None:
        """The lag of the step just solved, or None (no friction, or no pair in it)."""
        if contact is None or not contact.has_friction:
            return None
        state = contact._reported_friction
        if state is None or len(state[0]) == 0:
            return None
        return cls(contact)

    def unsettled(self, contact, x: np.ndarray) -> float:
        """How far (m) the lag point is from the vertices at the state x."""
        return float(np.abs(contact.vertices(x) - self.V_lag).max())

    def install(self, contact) -> None:
        """A parameter copy's contact lagged as the base's step: the base's lag point and slip
        start, the copy's own coefficients (a varied mu) and barrier stiffness (the base's,
        ``_sync``)."""
        tangential = contact.tangential_collisions(self.V_lag, self.collisions)
        contact._friction = (tangential, self.V_start, self.potential)
        contact._friction_lag_at = self.V_lag

    def hessian(self, contact, V: np.ndarray):
        """d2D/dV2 at V (sparse, exact), with the base's lag (``contact.last_step_lag``)."""
        with contact.last_step_lag():
            return contact._friction_terms(V, 2, False)[2]

    def start_term(self, contact, x: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(C (n_dofs, p), H_D W (n_V d, p)): the derivative of the step's gradient through its
        slip's start moving by W = dV_start/dtheta: C = J^T (-d2D/dV2) W, J = dV/dx; and the
        vertices' part (for an obstacle's force)."""
        V = contact.vertices(x)
        H_D = self.hessian(contact, V)
        HW = np.asarray(H_D @ W)
        return -np.asarray(contact.selection(x).T @ HW), HW


def lag_stiffness(contact, x: np.ndarray, held: HeldFriction):
    """d(dD/dV)/dV_lag (sparse, over the collision vertices): how the friction's gradient at
    the state x moves with its lag point (its normal forces, tangent bases and weights),
    IPC's ``force_jacobian`` with respect to the lagged displacements, negated."""
    ipctk = contact._ipctk
    with contact.last_step_lag():
        tangential, V_start, potential = contact._friction
    rest = np.asfortranarray(contact.mesh.rest_positions)
    U = np.asfortranarray(contact.vertices(x) - V_start)
    lagged = np.asfortranarray(held.V_lag - rest)
    wrt = ipctk.FrictionPotential.DiffWRT.LAGGED_DISPLACEMENTS
    return -potential.force_jacobian(tangential, contact.mesh, rest, lagged, U, contact.barrier,
                                     wrt)  # fmt: skip


def start_motion(contact, x_prev: np.ndarray, S_prev: np.ndarray, Y_prev: np.ndarray):
    """dV_start/dtheta (n_V d, p): the bodies' vertices at the step's start moved by the last
    step's sensitivity S_prev through the surfaces' map at x_prev, the obstacles' by their
    motion's derivative Y_prev at the step's start."""
    W = np.asarray(contact.selection(x_prev) @ S_prev)
    W[contact.n_deformable * contact.dim :] += Y_prev
    return W


def hold_lags(sim, lags: list[HeldFriction | None]) -> None:
    """Make ``sim``'s k-th step lag its friction at ``lags[k]`` (another run's
    ``HeldFriction.of`` after its k-th step): that run's normal forces and tangent bases at its
    lag point, with ``sim``'s own coefficients and slip start; a step past the list, or with
    None, has no friction. Whole runs so held are what ``friction_lag="held"`` differentiates
    (tests/identification/test_sensitivities_friction.py, benchmarks/friction_sensitivity.py)."""
    contact = sim.system.contact
    step = len(sim.history)

    def lag(V_start: np.ndarray, V_lag: np.ndarray, h: float) -> int:
        k = len(sim.history) - step
        fixed = lags[k] if k < len(lags) else None
        if fixed is None:
            contact._friction = None
            return 0
        tangential = contact.tangential_collisions(fixed.V_lag, fixed.collisions)
        contact._friction = (tangential, np.asfortranarray(V_start), fixed.potential)
        contact._friction_lag_at = fixed.V_lag
        return len(tangential)

    contact.lag_friction = lag
