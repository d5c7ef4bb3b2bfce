"""The forces and distances the contact model reports (a mixin of
``contact.model.ContactModel``): the smallest distance within dhat, each body's force from
each other body, each obstacle's force on the bodies (the barrier's and the lagged friction's
parts, or an interactive step's multipliers)."""

from __future__ import annotations

import numpy as np

__all__ = ["ContactForces"]


class ContactForces:
    """Mixed into ``ContactModel`` (uses its ipctk collisions, barrier, friction lag,
    obstacles' slices and the interactive step's kept forces)."""

    def proximity(self, c: np.ndarray) -> tuple[float, int]:
        """(the smallest distance (m) between surface elements within dhat, inf if none; the
        number of collision pairs within dhat), from one collision build."""
        V = self.vertices(c)
        col = self._collisions(V)
        if len(col) == 0:
            return float("inf"), 0
        return float(np.sqrt(col.compute_minimum_distance(self.mesh, V))), len(col)

    def min_distance(self, c: np.ndarray) -> float:
        return self.proximity(c)[0]

    def body_forces(self, c: np.ndarray) -> dict[str, np.ndarray]:
        """Per enabled pair of bodies, the contact force each receives from the other
        (``contact/readout/body_forces.py``)."""
        from tissuesim.contact.readout.body_forces import body_contact_forces

        state = self._friction or self._reported_friction
        lag = None
        if self.has_friction and state is not None and len(state[0]):
            lag = (self._friction_lag_at, state[1], state[2])
        return body_contact_forces(self, self.vertices(c), lag)

    def obstacle_forces(self, c: np.ndarray) -> dict[str, np.ndarray]:
        """Force (N, 3-vector) each obstacle exerts on the bodies, as ``name``, and with
        friction its parts ``name.normal`` (the barrier's gradient with respect to the
        obstacle's vertices, summed: the bodies' side is its negative) and ``name.friction``
        (the last step's lagged friction potential's, likewise)."""
        predicted = self._predicted_forces(c)
        if predicted is not None:
            return predicted
        V = self.vertices(c)
        col = self._collisions(V)
        normal = (
            self.barrier.gradient(col, self.mesh, V).reshape(-1, self.dim)
            if len(col)
            else np.zeros_like(V)
        )
        friction = None
        state = self._friction or self._reported_friction
        if self.has_friction and state is not None and len(state[0]):
            tangential, V_start, potential = state
            U = np.asfortranarray(V - V_start)
            friction = potential.gradient(tangential, self.mesh, U).reshape(-1, self.dim)
        out = {}
        for ob in self.obstacles:
            rows = self.slices[ob.name][0]
            n = normal[rows].sum(axis=0)
            f = np.zeros(self.dim) if friction is None else friction[rows].sum(axis=0)
            out[ob.name] = n + f
            if self.has_friction:
                out[f"{ob.name}.normal"] = n
                out[f"{ob.name}.friction"] = f
        return out

    def _predicted_forces(self, c: np.ndarray) -> dict[str, np.ndarray] | None:
        """An interactive step's obstacle forces, its multipliers (``time/contact_step.py``),
        when c is the state it accepted; else None."""
        if self.predicted_forces is None:
            return None
        x, prediction = self.predicted_forces
        if x.shape != c.shape or not np.array_equal(x, c):
            return None
        out = {}
        for name, force in prediction.forces.items():
            out[name] = force
            if self.has_friction:
                normal = prediction.normal_forces[name]
                out[f"{name}.normal"] = normal
                out[f"{name}.friction"] = force - normal
        return out
