"""A rigid body's own six DOFs in the system: its configuration (centre c, rotation R), its
fixed and prescribed DOFs, and the dead force and moment on it.

Configuration z = [c (3), R (9, row-major)]; tangent DOFs q = [dc (3), dtheta (3)] with the
rotation advanced on the left, R <- exp([dtheta]x) R (a spatial rotation vector), so that a
point of the body at r from the centre (in the rest configuration) is at c + R r and moves by
dc + dtheta x (R r). DOF names: "x", "y", "z" (the centre's translation) and "rx", "ry", "rz"
(rotation about the global axes through the centre: FEBio's Ru, Rv, Rw).

A prescribed translation is the centre's displacement u(t) from its rest place; a prescribed
rotation the rotation vector's component (rad). Where some rotation DOFs are held and others
free, the held components of the rotation vector log(R) are replaced and R rebuilt: exact for
rotations about one axis, which is what FEBio's models prescribe.

The inertia of a rigid body is its vertices' (``rigid/links.py``: the FEM bodies' mass mapped
onto the six DOFs); its own energy here is the dead load: -f(t) . (c - C) - m(t) . theta, with
theta = log(R) (for a moment about a fixed axis this is its work; FEBio applies a moment as a
load vector, which is this gradient).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tissuesim.frames.rotations import exp_map, log_map

__all__ = ["DOF_NAMES", "RigidModel"]

#: the six DOFs' names in order: translation of the centre, rotation about the global axes
DOF_NAMES = ("x", "y", "z", "rx", "ry", "rz")

#: a scalar function of time (prescribed value) or a vector one (loads)
TimeFunction = Callable[[float], float]


@dataclass(eq=False)
class RigidModel:
    """The six-DOF block of one rigid body: ``center`` C (its rest reference point),
    ``held`` DOF index -> value function of t (None: fixed at its rest value), ``force`` and
    ``moment`` functions of t giving 3-vectors (None: none)."""

    name: str
    center: np.ndarray
    held: dict[int, TimeFunction | None] = field(default_factory=dict)
    force: Callable[[float], np.ndarray] | None = None
    moment: Callable[[float], np.ndarray] | None = None
    #: with contact, a prescribed DOF is pulled to its value by a stiff spring (N/m; times the
    #: length scale squared per radian) instead of being set: a rigid indenter driven into a
    #: body then moves inside the step's Newton solve, its line searches limited by CCD, as
    #: IPC moves kinematic objects, where set at its end place it would cross the surface
    soft: float | None = None
    length: float = 1.0

    n_config = 12
    n_dofs = 6

    def __post_init__(self) -> None:
        self.center = np.asarray(self.center, dtype=float).reshape(3)

    @property
    def prescribed_dofs(self) -> np.ndarray:
        return np.array(sorted(self._set()), dtype=np.int64)

    def _set(self) -> dict:
        """The held DOFs set to their values (the soft ones are pulled there instead)."""
        if self.soft is None:
            return self.held
        return {k: f for k, f in self.held.items() if f is None}

    def _pulled(self) -> dict:
        return {} if self.soft is None else {k: f for k, f in self.held.items() if f is not None}

    def rest_config(self) -> np.ndarray:
        return np.concatenate([self.center, np.eye(3).ravel()])

    @staticmethod
    def split(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(centre (3,), rotation (3, 3)) of a configuration."""
        return z[:3], z[3:12].reshape(3, 3)

    @staticmethod
    def retract(z: np.ndarray, dq: np.ndarray) -> np.ndarray:
        c, R = RigidModel.split(z)
        out = np.empty(12)
        out[:3] = c + dq[:3]
        out[3:] = (exp_map(dq[3:6])[0] @ R).ravel() if np.any(dq[3:6]) else R.ravel()
        return out

    @staticmethod
    def difference(z1: np.ndarray, z0: np.ndarray) -> np.ndarray:
        c1, R1 = RigidModel.split(z1)
        c0, R0 = RigidModel.split(z0)
        return np.concatenate([c1 - c0, log_map(R1 @ R0.T)[0]])

    def values(self, t: float) -> dict[int, float]:
        """Each held DOF's value at t: the centre's displacement (m) or the rotation (rad)."""
        return {k: 0.0 if f is None else float(f(t)) for k, f in self.held.items()}

    def apply_prescribed(self, z: np.ndarray, t: float) -> np.ndarray:
        held = self._set()
        if not held:
            return z
        out = z.copy()
        values = {k: v for k, v in self.values(t).items() if k in held}
        for k in range(3):
            if k in values:
                out[k] = self.center[k] + values[k]
        turned = [k for k in range(3, 6) if k in values]
        if turned:
            theta = log_map(z[3:12].reshape(3, 3))[0]
            for k in turned:
                theta[k - 3] = values[k]
            out[3:] = exp_map(theta)[0].ravel()
        return out

    def loads(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        f = np.zeros(3) if self.force is None else np.asarray(self.force(t), dtype=float)
        m = np.zeros(3) if self.moment is None else np.asarray(self.moment(t), dtype=float)
        return f, m

    def load_energy(self, z: np.ndarray, t: float, order: int):
        """(value, gradient (6,) or None, Hessian diagonal (6,) or None) of the dead load at z
        (no Hessian) and of the springs pulling soft DOFs to their values."""
        f, m = self.loads(t)
        pulled = self._pulled()
        if not (f.any() or m.any() or pulled):
            return 0.0, (np.zeros(6) if order >= 1 else None), None
        c, R = self.split(z)
        theta = log_map(R)[0] if (m.any() or pulled) else np.zeros(3)
        value = -float(f @ (c - self.center)) - float(m @ theta)
        gradient = np.concatenate([-f, -m])
        diagonal = np.zeros(6)
        q = np.concatenate([c - self.center, theta])
        for k, fn in pulled.items():
            stiffness = self.soft * (1.0 if k < 3 else self.length**2)
            gap = q[k] - float(fn(t))
            value += 0.5 * stiffness * gap * gap
            gradient[k] += stiffness * gap
            diagonal[k] += stiffness
        return value, (gradient if order >= 1 else None), (diagonal if pulled else None)

    def spring_forces(self, z: np.ndarray, t: float) -> np.ndarray:
        """The force and moment (6,) the springs of the soft DOFs apply (0 on the others)."""
        out = np.zeros(6)
        pulled = self._pulled()
        if not pulled:
            return out
        c, R = self.split(z)
        q = np.concatenate([c - self.center, log_map(R)[0]])
        for k, fn in pulled.items():
            stiffness = self.soft * (1.0 if k < 3 else self.length**2)
            out[k] = -stiffness * (q[k] - float(fn(t)))
        return out
