"""The lagged terms of an implicit step (``time/steps.py``), re-lagged together at Newton's
converged points: IPC friction, follower pressures on open surfaces, rigid joints'
multipliers, the penalty contact's augmentations, current areas and friction, and the
materials' lagged terms (a reactive viscoelastic law's bond recruitment)."""

from __future__ import annotations

import numpy as np

__all__ = ["StepLags", "lagged_pressure", "penalty_relags", "PENALTY_AREA_RELAGS"]


def lagged_pressure(body_energies) -> bool:
    """Whether a follower pressure is lagged this step (its lag is set at Newton's start)."""
    from tissuesim.energies.pressure_lag import LaggedPressureEnergy

    return any(isinstance(e, LaggedPressureEnergy) for body in body_energies for e in body)


#: re-lags of a penalty pair's current-area weights beyond its augmentations
PENALTY_AREA_RELAGS = 10
#: re-lags of the materials' lagged terms (a fixed point that settles in a few)
MATERIAL_RELAGS = 20


def penalty_relags(pair) -> int:
    """A penalty pair's re-lags in a step: its augmentations, its current areas' and its
    friction's lags."""
    from tissuesim.contact.penalty.friction import FRICTION_RELAGS

    friction = FRICTION_RELAGS if getattr(pair, "friction", 0) > 0 else 0
    return pair.max_augmentations + PENALTY_AREA_RELAGS + friction


class StepLags:
    """The lagged terms of one step, re-lagged together by Newton's ``relag``: friction (IPC,
    ``friction_iterations`` - 1 re-lags, then kept) and the follower pressures on open
    surfaces (``energies/pressure_lag.py``: re-lagged until each settles to Newton's
    ``gradient_tolerance``, at most ``MAX_RELAGS`` times; ``check`` fails a solve that ends
    with one unsettled, so the step is halved and retried instead of accepted)."""

    def __init__(self, system, body_energies, c0, options, contact=None, friction=None,
                 x_start=None):  # fmt: skip
        from tissuesim.energies.pressure_lag import MAX_RELAGS, PressureLags

        self.friction = friction  # relag(c, y) of _start_friction, or None
        self.friction_max = contact.settings.friction_iterations - 1 if friction else 0
        self.friction_relags = 0
        self.pressures = PressureLags.of(
            system.config_slices, body_energies, options.gradient_tolerance
        )
        if self.pressures is not None:
            self.pressures.start(c0)
        self.system = system
        self.joints = bool(getattr(system, "joints", ()))  # rigid/joints.py: their multipliers
        self.stall_rule = getattr(options, "method", "newton") == "febio"  # joints.py
        # joints held by FEBio's rule (their enforcement) augment at converged points, as FEBio
        joints = getattr(system, "joints", ()) or ()
        self.febio_joints = any(getattr(j, "enforcement", None) for j in joints)
        # contact/penalty/pair.py: augmentations and lagged current areas, counted per solve
        self.penalty = list(getattr(system, "penalty_contacts", ()))
        if self.penalty:  # friction anchored at the last converged positions
            at = None if x_start is None else system.body_positions_and_dofs(x_start)[0]
            for pair in self.penalty:
                pair.begin_step(at)
        # FEM bodies whose materials lag a term in the step (reactive viscoelastic recruitment)
        self.materials = [(system.config_slices[j], b) for j, b in
                          enumerate(getattr(system, "bodies", ()))
                          if hasattr(b, "lagged_materials") and b.lagged_materials()]  # fmt: skip
        self.material_tolerance = options.gradient_tolerance
        from tissuesim.rigid.joints import MAX_UPDATES

        self.max_relags = max(
            self.friction_max,
            MAX_RELAGS if self.pressures else 0,
            MAX_UPDATES if self.joints else 0,
            max((penalty_relags(p) for p in self.penalty), default=0),
            MATERIAL_RELAGS if self.materials else 0,
        )

    def relag(self, c: np.ndarray, y: np.ndarray | None = None) -> bool:
        """Re-lag at c (obstacles at y); whether anything changed."""
        changed = False
        if self.friction is not None and self.friction_relags < self.friction_max:
            self.friction_relags += 1
            changed = self.friction(c, y)
        if self.pressures is not None:
            changed = self.pressures.relag(c) or changed
        if self.joints:
            changed = self.system.update_joints(c, self.stall_rule) or changed
        if self.penalty:
            changed = self.system.update_penalty_contacts(c) or changed
        for where, body in self.materials:
            changed = body.relag_materials(c[where], self.material_tolerance) or changed
        return changed

    def newton_relag(self):
        """The relag(c) for ``minimize`` (None when nothing is lagged)."""
        lagged = self.friction is not None or self.pressures is not None
        if not (lagged or self.joints or self.penalty or self.materials):
            return None
        return lambda c: self.relag(c)

    def check(self, c1: np.ndarray, record) -> None:
        """A converged solve whose pressures or materials' lags have not settled at c1
        becomes a failed one (the step is then halved)."""
        if not record.converged:
            return
        for where, body in self.materials:
            moved = body.materials_lag_moved(c1[where])
            if moved > max(1e3 * self.material_tolerance, 1e-6):
                record.converged = False
                record.reason = (f"a bond recruitment's lagged weight did not settle in "
                                 f"{self.max_relags} re-lags (moved by {moved:.3g})")  # fmt: skip
                return
        if self.pressures is None:
            return
        reason = self.pressures.unsettled(c1, self.pressures.relags)
        if reason is not None:
            record.converged, record.reason = False, reason
