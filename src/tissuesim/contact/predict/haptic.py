"""An instrument's force for a haptic device at 1 kHz between deformation steps (20-60 Hz):
the last step's contact problem solved again for the instrument's displacement since the step,
as SOFA's ``LCPForceFeedback`` does.

The step kept its pairs' compliance W, their rows and the right-hand side b of the contact
problem (free gaps less targets, slips; ``predictor.py``). A rigid translation d of the
instrument changes pair i's gap and slip by A_i d, A_i = s_i D_i with s_i = sum of the
stencil coefficients on the instrument's vertices (-1 or +1: which side of the pair it is)
and D_i the pair's [normal; tangents] (d x d). Each call solves the Signorini-Coulomb problem
on W for b + A d, warm-started from the last call (a few sweeps), and returns the force the
instrument exerts on the bodies, -sum_i A_i^T lambda_i, the same quantity as the step's
report. Pairs near contact but not touching at the step are in W too, so a contact that
appears or vanishes as the device moves changes the force continuously. The bodies answer
with the step's compliance (linear): the force is the step's to first order in d, and exact
in which pairs touch and how they slide.
"""

from __future__ import annotations

import time

import numpy as np

from tissuesim.contact.predict.signorini import solve_signorini_coulomb
from tissuesim.errors import InputError

__all__ = ["HapticContact"]

#: a device needs the force to about a percent, on time: sweeps per call at most, and the
#: relative change of the forces at which a call stops (warm-started from the last call, a
#: few sweeps suffice while the device moves smoothly)
SWEEPS = 60
TOLERANCE = 1e-4


class HapticContact:
    """The contact problem of the last step for obstacle ``name`` (a snapshot: later steps do
    not change it; take a new one after each step). ``force(d)`` (N) for a translation d (m)
    of the instrument since the step; ``time`` the step's end (s); ``last_solve_s`` the
    seconds of the last call."""

    def __init__(self, contact, prediction, name: str, time_s: float) -> None:
        rows = prediction.rows
        where = contact.slices[name][0]
        d = contact.dim
        on_instrument = (rows.vertices >= where.start) & (rows.vertices < where.stop)
        side = np.where(on_instrument, rows.coefficients, 0.0).sum(axis=1)  # (m,)
        directions = np.concatenate([rows.normals[:, None, :], rows.tangents], axis=1)
        self.name = name
        self.time = float(time_s)
        self._A = side[:, None, None] * directions  # (m, d, d): d -> change of [gap, slips]
        self._W = prediction.W
        self._b = np.zeros((rows.n_pairs, d)) if prediction.rhs is None else prediction.rhs
        self._mu = rows.mu
        self._soft = prediction.soft
        self._smoothing = prediction.smoothing
        self._lam = prediction.force.copy()
        self.dim = d
        self.force0 = self.force(np.zeros(d))
        self.last_solve_s = 0.0

    @property
    def n_pairs(self) -> int:
        """The pairs of the step's contact problem (touching or near)."""
        return len(self._b)

    def force(self, displacement) -> np.ndarray:
        """The force (N, d-vector) the instrument exerts on the bodies after a further
        translation ``displacement`` (m) since the step; a device renders its negative."""
        start = time.perf_counter()
        disp = np.asarray(displacement, dtype=float)
        if disp.shape != (self.dim,) or not np.all(np.isfinite(disp)):
            given = np.array2string(np.ravel(disp)[:6], precision=4)
            raise InputError(
                f"haptic force of {self.name!r}: displacement must be {self.dim} finite numbers "
                f"(m), not {given}"
            )
        if len(self._b) == 0:
            self.last_solve_s = time.perf_counter() - start
            return np.zeros(self.dim)
        b = self._b + self._A @ disp
        out = solve_signorini_coulomb(
            self._W, b, self._mu, self._lam, self._soft, self._smoothing,
            max_sweeps=SWEEPS, tolerance=TOLERANCE,
        )  # fmt: skip
        self._lam = out.force
        force = -np.einsum("mad,ma->d", self._A, out.force)
        self.last_solve_s = time.perf_counter() - start
        return force
