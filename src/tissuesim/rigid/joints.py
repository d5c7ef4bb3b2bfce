"""Joints and springs between two rigid bodies (FEBio's rigid connectors), as energies on their
twelve DOFs.

A joint's constraints are residuals g of features attached to the bodies: the joint's origin
as a point of each body (p = c + R r) and its axes as directions of each (e = R e0), all at
rest where the joint is given. Every residual is linear or bilinear in the features:

    spherical    p_b - p_a                                          (3)
    revolute     p_b - p_a, e_b - e_a; a prescribed rotation phi(t) about e:
                 t_b - cos(phi) t_a - sin(phi) s_a                   (+3)
    prismatic    t_a . d, s_a . d (d = p_b - p_a), e_b - e_a, t_b - t_a; a prescribed
                 translation u(t) along e: e_a . d - u                 (+1)
    cylindrical  t_a . d, s_a . d, e_b - e_a; prescribed translation and / or rotation
    planar       e_a . d, e_b - e_a (e the plane's normal)

(e the joint's axis, t its transverse axis, s = e x t), and each joint adds the augmented
Lagrangian k/2 |g|^2 - lambda . g; after each Newton solve lambda <- lambda - k g until every
residual is below TOLERANCE x the length scale (``time/lags.py``'s re-lags), so the joint
holds to that tolerance whatever k. Under FEBio's solver (which iterates after every update)
the updates also end when two solves in a row move the bodies and leave g where it was (moved
by less than STALLED of it): redundant constraints that do not quite agree. tissuesim's Newton
keeps updating: the multipliers carry over to the next steps, and stopping there left FEBio's
rj13 2.5e-3 from FEBio's norm instead of 4.5e-7.
A joint given an ``Enforcement`` (FEBio's ``laugon``, ``tolerance``, ``penalty``, ``gaptol``,
``minaug``, ``maxaug``; the converter's) follows
FEBio's rule instead (``FERigidJoint::Augment``, ``FERigidSphericalJoint::Augment``): its
penalty on the point residuals, and after the n-th solve of a step (n = 0, 1, ...) the joint
has converged unless the multipliers' norm would change by ``tolerance`` or more
(| |lambda - k g| - |lambda| | / |lambda - k g|, 0 where |lambda - k g| <= 1e-10), |g| of the
point is ``gap_tolerance`` or more, or n < ``min_augmentations``; n >= ``max_augmentations``
converges; else lambda <- lambda - k g and the step is solved again. Such joints are augmented
at converged points only (``time/steps.py``), as FEBio does, and left as loose as that
tolerance leaves them, as FEBio leaves them (FEBio's ri02: -2.8e-8 from its norm; held to
1e-9 of the size, -1.6e-3).
A spring is k/2 (|p_b - p_a| - L0)^2 between two insertion points (FEBio's ``rigid spring``:
L0 = 0 takes the rest length).

A feature y on a body moves with its tangent (dc, dtheta) by dy = J dq, J = [I, -[y - c]x]
for a point and [0, -[y]x] for a direction; its curvature along dtheta, contracted with the
force g on it, is (g v^T + v g^T) / 2 - (g . v) I with v = y - c or y (``rigid/links.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tissuesim.errors import InputError
from tissuesim.frames.rotations import skew

__all__ = [
    "RigidJoint", "RigidSpring", "Enforcement", "augment", "JOINT_KINDS", "TOLERANCE",
    "MAX_UPDATES",
]  # fmt: skip

JOINT_KINDS = ("spherical", "revolute", "prismatic", "cylindrical", "planar")
#: a joint holds when every residual is below this times the length scale
TOLERANCE = 1e-9
MAX_UPDATES = 30
#: two updates in a row that move a joint's residual by less than this fraction of it end the
#: updates (at that rate MAX_UPDATES updates would shrink it by less than a third)
STALLED = 0.01

# features: 0 p_a, 1 p_b (points); 2 e_a, 3 t_a, 4 s_a, 5 e_b, 6 t_b (directions)
_POINT = (True, True, False, False, False, False, False)
_BODY = (0, 1, 0, 0, 0, 1, 1)


def _unit(v, what: str) -> np.ndarray:
    v = np.asarray(v, dtype=float).reshape(3)
    n = float(np.linalg.norm(v))
    if not np.isfinite(n) or n == 0.0:
        raise InputError(f"a rigid joint's {what} must be a non-zero vector, not {v.tolist()}")
    return v / n


def _axes(axis, transverse) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    e = _unit(axis, "axis")
    t = np.asarray(transverse if transverse is not None else np.eye(3)[np.argmin(abs(e))], float)
    t = t - (t @ e) * e
    t = _unit(t, "transverse axis (it must not be along the axis)")
    return e, t, np.cross(e, t)


_ENFORCEMENT_KEYS = (
    "penalty", "augmented", "tolerance", "gap_tolerance", "min_augmentations",
    "max_augmentations",
)  # fmt: skip


@dataclass(frozen=True)
class Enforcement:
    """FEBio's enforcement of a joint (module docstring): ``penalty`` (N/m, on the joint's
    point residuals; its direction residuals keep tissuesim's), ``augmented`` (False: the
    penalty alone, FEBio's laugon 0), ``tolerance`` (relative change of the multipliers'
    norm; 0: unused), ``gap_tolerance`` (m; 0: unused), ``min_augmentations``,
    ``max_augmentations`` (None: no limit, as FEBio's ``rigid joint``)."""

    penalty: float
    augmented: bool = True
    tolerance: float = 0.0
    gap_tolerance: float = 0.0
    min_augmentations: int = 0
    max_augmentations: int | None = None

    @classmethod
    def of(cls, spec: object, where: str) -> Enforcement | None:
        """An Enforcement from a mapping of its fields (None: tissuesim's tight default)."""
        if spec is None or isinstance(spec, Enforcement):
            return spec
        if not isinstance(spec, dict):
            raise InputError(f"{where}: enforcement must be a table of "
                             f"{', '.join(_ENFORCEMENT_KEYS)}, not {spec!r}")  # fmt: skip
        for key in spec:
            if key not in _ENFORCEMENT_KEYS:
                raise InputError(f"{where}: enforcement takes {', '.join(_ENFORCEMENT_KEYS)}, "
                                 f"not {key!r}")  # fmt: skip
        if "penalty" not in spec:
            raise InputError(f"{where}: enforcement needs its penalty (N/m)")

        def number(key: str, low: float, open_: bool) -> float:
            x = spec.get(key, 0.0)
            ok = isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x)
            if not ok or x < low or (open_ and x == low):
                raise InputError(f"{where}: enforcement {key} must be a number "
                                 f"{'>' if open_ else '>='} {low:g}, not {x!r}")  # fmt: skip
            return float(x)

        def count(key: str, default: int | None) -> int | None:
            x = spec.get(key, default)
            if x is not None and (isinstance(x, bool) or not isinstance(x, int) or x < 0):
                raise InputError(f"{where}: enforcement {key} must be a count >= 0, not {x!r}")
            return x

        augmented = spec.get("augmented", True)
        if not isinstance(augmented, bool):
            raise InputError(f"{where}: enforcement augmented must be true or false, not "
                             f"{augmented!r}")  # fmt: skip
        return cls(
            number("penalty", 0.0, True), augmented, number("tolerance", 0.0, False),
            number("gap_tolerance", 0.0, False), count("min_augmentations", 0),
            count("max_augmentations", None),
        )  # fmt: skip

    def as_table(self) -> dict:
        out = {k: getattr(self, k) for k in _ENFORCEMENT_KEYS}
        return {k: v for k, v in out.items() if v is not None}


@dataclass(eq=False)
class RigidJoint:
    """A joint of ``kind`` between rigid bodies ``a`` and ``b`` (names) at ``origin`` (m, at
    rest) with ``axis`` (revolute: the rotation axis; prismatic: the translation axis;
    cylindrical: both; planar: the plane's normal) and ``transverse`` axis; ``rotation`` (rad)
    and ``translation`` (m): functions of t prescribing the relative motion, or None;
    ``enforcement``: FEBio's augmented Lagrangian rule, or None (held to TOLERANCE)."""

    name: str
    kind: str
    a: str
    b: str
    origin: np.ndarray
    axis: np.ndarray | None = None
    transverse: np.ndarray | None = None
    rotation: Callable[[float], float] | None = None
    translation: Callable[[float], float] | None = None
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))
    enforcement: Enforcement | None = None
    augmentations: int = 0  # the multiplier updates tried in the step so far (FEBio's naug)
    last_gap: np.ndarray | None = field(default=None, repr=False)  # g at the last update
    stalls: int = field(default=0, repr=False)  # updates in a row that left g where it was

    def __post_init__(self) -> None:
        self.enforcement = Enforcement.of(self.enforcement, f"rigid joint {self.name!r}")
        if self.kind not in JOINT_KINDS:
            raise InputError(f"rigid joint {self.kind!r}: the kinds are {', '.join(JOINT_KINDS)}")
        self.origin = np.asarray(self.origin, dtype=float).reshape(3)
        if self.kind != "spherical" and self.axis is None:
            raise InputError(f"a {self.kind} joint needs its axis")
        self.frame = _axes(self.axis if self.axis is not None else (0, 0, 1), self.transverse)
        if self.rotation is not None and self.kind not in ("revolute", "cylindrical"):
            raise InputError(f"a {self.kind} joint takes no prescribed rotation")
        if self.translation is not None and self.kind not in ("prismatic", "cylindrical"):
            raise InputError(f"a {self.kind} joint takes no prescribed translation")

    def rest_features(self, centres: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        """(7, 3): the origin's offsets from each centre, then the axes (rest directions)."""
        e, t, s = self.frame
        return np.array([self.origin - centres[0], self.origin - centres[1], e, t, s, e, t])

    def point_rows(self, t: float) -> np.ndarray:
        """(m,) bool: the residuals that are lengths (they involve the origin's points; the
        rest are directions' differences)."""
        _, D, _ = self.residuals(np.ones((7, 3)), t)
        return np.abs(D[:, :2]).sum(axis=(1, 2)) > 0

    def residuals(self, y: np.ndarray, t: float):
        """(g (m,), dg/dy (m, 7, 3), [(i, j, c, w)]: bilinear terms w * y_i . y_j of row c)."""
        rows: list[tuple[dict, float]] = []  # ({feature: coefficient vector (3,)}, constant)
        bilinear: list[tuple[int, int, int, float]] = []
        eye = np.eye(3)

        def linear(pairs: dict, comps=range(3)) -> None:
            for k in comps:
                rows.append(({f: c * eye[k] for f, c in pairs.items()}, 0.0))

        def dot(f: int, constant: float = 0.0) -> None:
            # y_f . (p_b - p_a): bilinear in (f, 1) and (f, 0)
            c = len(rows)
            rows.append(({}, constant))
            bilinear.extend([(f, 1, c, 1.0), (f, 0, c, -1.0)])

        kind = self.kind
        if kind in ("spherical", "revolute"):
            linear({1: 1.0, 0: -1.0})
        if kind in ("prismatic", "cylindrical"):
            dot(3)
            dot(4)
        if kind == "planar":
            dot(2)
        if kind != "spherical":
            linear({5: 1.0, 2: -1.0})
        if kind == "prismatic":
            linear({6: 1.0, 3: -1.0})
        if self.translation is not None:
            dot(2, -float(self.translation(t)))
        if self.rotation is not None:
            phi = float(self.rotation(t))
            linear({6: 1.0, 3: -np.cos(phi), 4: -np.sin(phi)})
        m = len(rows)
        g = np.zeros(m)
        D = np.zeros((m, 7, 3))
        for c, (coeffs, constant) in enumerate(rows):
            g[c] = constant
            for f, v in coeffs.items():
                D[c, f] += v
                g[c] += v @ y[f]
        for i, j, c, w in bilinear:
            g[c] += w * (y[i] @ y[j])
            D[c, i] += w * y[j]
            D[c, j] += w * y[i]
        return g, D, bilinear


def augment(
    joint: RigidJoint,
    g: np.ndarray,
    k: np.ndarray,
    points: np.ndarray,
    tight: float,
    moved: bool = True,
) -> bool:
    """The joint's multiplier update after a solve with residuals g (penalties k, ``points``
    the rows of the point residuals); whether it changed (then the step is solved again).
    Without an enforcement: every |g| below ``tight`` (TOLERANCE x the length scale), or two
    solves in a row that ``moved`` the bodies (False: the solve stayed where the last update
    was made) and left g where it was; with one: FEBio's rule (module docstring)."""
    if joint.multipliers.size != g.size:
        joint.multipliers = np.zeros(g.size)
    lam = joint.multipliers
    trial = lam - k * g
    rule = joint.enforcement
    if rule is None:
        if np.abs(g).max() <= tight:
            return False
        # two solves in a row moved the bodies but the residual by less than STALLED of itself
        # (a solve that did not move says nothing: Newton stays put while the multipliers'
        # change is below its tolerance): the updates cannot close it (redundant constraints
        # that do not quite agree, as the closed loop of revolute joints of FEBio's rj13, given
        # to six digits), so the joint holds
        last, joint.last_gap = joint.last_gap, g.copy()
        if moved and last is not None and last.shape == g.shape:
            still = np.abs(g - last).max() <= max(tight, STALLED * np.abs(last).max())
            joint.stalls = joint.stalls + 1 if still else 0
            if joint.stalls >= 2:
                return False
        joint.multipliers = trial
        return True
    if not rule.augmented:
        return False
    n, joint.augmentations = joint.augmentations, joint.augmentations + 1
    n0, n1 = float(np.linalg.norm(lam)), float(np.linalg.norm(trial))
    change = abs(n1 - n0) / n1 if n1 > 1e-10 else 0.0
    done = not (rule.tolerance > 0.0 and change >= rule.tolerance)
    if rule.gap_tolerance > 0.0 and np.linalg.norm(g[points]) >= rule.gap_tolerance:
        done = False
    if n < rule.min_augmentations:
        done = False
    if rule.max_augmentations is not None and n >= rule.max_augmentations:
        done = True
    if not done:
        joint.multipliers = trial
    return not done


@dataclass(eq=False)
class RigidSpring:
    """A linear spring k (N/m) between point ``point_a`` of rigid body ``a`` and ``point_b``
    of ``b`` (m, at rest), of free length ``free_length`` (None: the rest distance)."""

    name: str
    a: str
    b: str
    point_a: np.ndarray
    point_b: np.ndarray
    stiffness: float
    free_length: float | None = None

    def __post_init__(self) -> None:
        self.point_a = np.asarray(self.point_a, dtype=float).reshape(3)
        self.point_b = np.asarray(self.point_b, dtype=float).reshape(3)
        if not (np.isfinite(self.stiffness) and self.stiffness > 0):
            raise InputError(f"a rigid spring's stiffness must be > 0 N/m, not {self.stiffness}")
        if self.free_length is None or self.free_length == 0:
            self.free_length = float(np.linalg.norm(self.point_b - self.point_a))


def feature_maps(y: np.ndarray, centres: np.ndarray, points: tuple, bodies: tuple):
    """J (f, 3, 12) of each feature over both bodies' tangents, and the arm v of each (the
    offset from its centre for a point, itself for a direction)."""
    f = len(y)
    J = np.zeros((f, 3, 12))
    arms = np.empty((f, 3))
    for i in range(f):
        k = bodies[i]
        arms[i] = y[i] - centres[k] if points[i] else y[i]
        if points[i]:
            J[i, :, 6 * k : 6 * k + 3] = np.eye(3)
        J[i, :, 6 * k + 3 : 6 * k + 6] = -skew(arms[i])
    return J, arms


def curvature(g: np.ndarray, arms: np.ndarray, bodies: tuple) -> np.ndarray:
    """(12, 12): each feature's curvature along its body's rotation, contracted with its force."""
    H = np.zeros((12, 12))
    for gi, v, k in zip(g, arms, bodies, strict=True):
        block = 0.5 * (np.outer(gi, v) + np.outer(v, gi)) - (gi @ v) * np.eye(3)
        H[6 * k + 3 : 6 * k + 6, 6 * k + 3 : 6 * k + 6] += block
    return H


def joint_energy(joint: RigidJoint, y: np.ndarray, centres, t: float, k: np.ndarray):
    """(value, gradient (12,), Hessian (12, 12), residuals) of k/2 |g|^2 - lambda . g (k per
    residual: the force or the moment penalty)."""
    g, D, bilinear = joint.residuals(y, t)
    lam = joint.multipliers if joint.multipliers.size == g.size else np.zeros(g.size)
    force = k * g - lam  # d energy / d g
    value = float(0.5 * (k * g) @ g - lam @ g)
    J, arms = feature_maps(y, centres, _POINT, _BODY)
    Dq = np.einsum("cfi,fiq->cq", D, J)  # dg/dq (m, 12)
    grad = Dq.T @ force
    hess = Dq.T @ (k[:, None] * Dq)
    # the bilinear terms' second derivatives: w (J_i^T J_j + J_j^T J_i) per row
    for i, j, c, w in bilinear:
        block = w * force[c] * (J[i].T @ J[j])
        hess += block + block.T
    # the features' own curvature, contracted with the force on each
    gy = np.einsum("c,cfi->fi", force, D)
    hess += curvature(gy, arms, _BODY)
    return value, grad, hess, g


def spring_energy(spring: RigidSpring, y: np.ndarray, centres):
    """(value, gradient (12,), Hessian (12, 12), the force on b (3,)) of k/2 (L - L0)^2."""
    d = y[1] - y[0]
    L = float(np.linalg.norm(d))
    k, L0 = spring.stiffness, spring.free_length
    n = d / L if L > 0 else np.zeros(3)
    gd = k * (L - L0) * n
    Hd = k * ((1 - L0 / L) * np.eye(3) + (L0 / L) * np.outer(n, n)) if L > 0 else k * np.eye(3)
    J, arms = feature_maps(y, centres, (True, True), (0, 1))
    Jd = J[1] - J[0]
    grad = Jd.T @ gd
    hess = Jd.T @ Hd @ Jd + curvature(np.array([-gd, gd]), arms, (0, 1))
    return 0.5 * k * (L - L0) ** 2, grad, hess, -gd
