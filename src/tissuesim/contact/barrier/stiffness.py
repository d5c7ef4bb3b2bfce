"""IPC's adaptive barrier stiffness (Li et al. 2020, sec. 4.3 and its supplement), in
tissuesim's units (the area-weighted barrier's kappa is a pressure, Pa).

When contact first appears (the first step that starts with pairs within dhat), kappa is set to
balance the other energies' gradient against the barrier's,

    kappa_0 = argmin_k |g_E + k g_B|^2 = -(g_E . g_B) / |g_B|^2   (g_B at kappa = 1),

clamped to [kappa_min, kappa_max], over the free DOFs (``ipctk.initial_barrier_stiffness``
does the same with a mass-based kappa_min; here kappa_min is the physical scale, the largest
Young's modulus E of the bodies in contact, so the barrier is never softer than a layer of the
stiffest material dhat thick, and kappa_max = MAX_FACTOR x E). After every step, if the
smallest surface distance is below EPSILON x the scene's diagonal and still shrinking, kappa
doubles (up to kappa_max; ``ipctk.update_barrier_stiffness``): the surfaces may not get closer
than round-off can tell apart. The value is reported per step (``extra.contact.stiffness_Pa``).
It is the default; a number given as the contact ``stiffness`` fixes kappa instead. In every
scene measured (a block on a floor, a fast drop, the self-contact fold, Hertz) the balance
stayed at kappa_min = E: the physical scale already balances elasticity there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["AdaptiveStiffness", "MAX_FACTOR", "EPSILON"]

MAX_FACTOR = 100.0  # kappa_max / kappa_min, as IPC
EPSILON = 1e-9  # of the diagonal: the distance below which a shrinking gap doubles kappa


@dataclass
class AdaptiveStiffness:
    kappa_min: float
    diagonal: float
    initialized: bool = False
    previous_distance: float = float("inf")
    doublings: int = 0

    @property
    def kappa_max(self) -> float:
        return MAX_FACTOR * self.kappa_min

    def initial(self, g_energy: np.ndarray, g_barrier: np.ndarray) -> float:
        """kappa_0 from the free DOFs' gradients (g_barrier at kappa = 1)."""
        self.initialized = True
        gg = float(g_barrier @ g_barrier)
        balance = -float(g_energy @ g_barrier) / gg if gg > 0 else self.kappa_min
        return float(np.clip(balance, self.kappa_min, self.kappa_max))

    def update(self, kappa: float, distance: float) -> float:
        """kappa after a step whose smallest surface distance is ``distance`` (m)."""
        import ipctk

        new = kappa
        if np.isfinite(distance) and np.isfinite(self.previous_distance):
            new = float(  # ipctk compares squared distances (as compute_minimum_distance gives)
                ipctk.update_barrier_stiffness(
                    self.previous_distance**2,
                    distance**2,
                    self.kappa_max,
                    kappa,
                    self.diagonal,
                    EPSILON,
                )
            )
        self.previous_distance = distance
        if new > kappa:
            self.doublings += 1
        return new
