"""Coulomb friction of a penalty contact pass, as FEBio's sliding contacts enforce it
(``FESlidingElasticInterface::ContactTraction``, ``FESlidingInterface::ContactNodalForce``):
each point is anchored to a place on the secondary surface (a facet and natural coordinates,
moving with that facet): where it projects at each step's start (``ANCHORS`` "step", FEBio's
sliding-elastic) or where it first projected, kept while it projects ("contact", FEBio's
sliding-node-on-facet), and the trial tangential traction

    tau = P (Lt + eps_t d),     d = x - a,     P = I - n n^T,

(x the point, a its anchor, n the contact normal, Lt FEBio's tangential multiplier: 0 for a
penalty method, the last converged traction for the augmented Lagrangian) is returned to the
Coulomb cone |tau| <= mu p_n. That return map is the derivative of one convex energy per point,

    W phi(tau),   phi = |tau|^2 / (2 eps_t)                    if |tau| <= m = mu p_n (stick)
                  phi = (m |tau| - m^2 / 2) / eps_t            otherwise (slip),

C1 across the cone, so the friction is one more energy in the incremental potential once the
normal pressure p_n and the normal n are lagged; they are re-lagged at converged solutions
(``lag``) until they settle, which is FEBio's fixed point (FEBio evaluates them at the current
iterate, with a non-symmetric stiffness). Its gradient on the point is W (tau, or m tau/|tau|);
Hessian W eps_t P (stick) or W (m eps_t / |tau|) (P - t t^T) (slip, t = tau/|tau|), on the
stencil weights (H of the point, -H of the anchor).

A fresh point (FEBio's sliding-elastic: one not in contact at the step's start) slides in
its first step whatever its traction, at m along its slip direction: here that direction is
lagged too (the traction m s, s the last lag's unit trial traction, 0 at first: a linear energy
W m s . d), since m |tau| is not smooth where the slip is zero.

With ``ANCHORS`` "contact" (FEBio's sliding-node-on-facet, ``FESlidingInterface::
ContactNodalForce``) the slip is FEBio's: the change of the point's natural coordinates on
the anchor's facet since it first projected there, Delta = r - r_a (r its closest point now),
measured in the facet's reference metric M (``Metric0`` at r, held), the traction covariant,
T = Lt + eps_t M Delta, and its cone |T|_{M^-1} <= m; the energy is phi(T) of the same form in
that norm, |T|^2_{M^-1} / (2 eps_t) or (m |T| - m^2 / 2) / eps_t, its gradient dr/dy^T T_ret
(dr/dy from the projection's optimality: ``projection.projection_jacobian``) and its Hessian
dr/dy^T phi'' dr/dy (phi'' = eps_t M in stick, (m eps_t / |T|) (M - T T^T / |T|^2) in slip):
the projection's second derivative times T_ret is left out, as FEBio's stiffness leaves it
(exact along the point's own DOFs on a flat parallelogram facet, where r is linear in x).

Where FEBio differs: its sliding-elastic stick couples the normal gap into the same vector
penalty and pushes along the primary's normal; here the normal stays the pair's gap penalty
(the secondary's normal at the closest point) and the slip of "step" anchors is measured in
the current configuration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.contact.penalty.faces import shape, shape_derivatives
from tissuesim.contact.penalty.projection import gap_derivatives, project, projection_jacobian

__all__ = ["FrictionState", "anchor", "augment", "force", "friction_terms", "lag", "return_map"]

#: relative change of a lagged normal pressure (to the largest) or normal below which the
#: friction lag has settled
LAG_SETTLED = 1e-8
#: a fresh point's slip below this fraction of its size (square root of its area weight) has
#: no direction
SLIP_ROUNDOFF = 1e-9
#: friction re-lags per step beyond the augmentations (then the lag is kept)
FRICTION_RELAGS = 15


@dataclass(eq=False)
class FrictionState:
    """A pass's friction, per point of the pass: its anchor (a facet of the secondary, -1
    for none, and natural coordinates there), the lagged pressure and normal, whether it
    slides whatever its traction (``fresh``: FEBio's sliding-elastic slides a point in the
    step it comes into contact), and the tangential multiplier Lt (kept across steps)."""

    traction: np.ndarray  # Lt (points, 3), Pa
    facet: np.ndarray  # (points,), -1: not anchored
    rs: np.ndarray  # (points, 2)
    pressure: np.ndarray  # (points,), Pa
    normal: np.ndarray  # (points, 3)
    fresh: np.ndarray  # (points,) bool
    direction: np.ndarray  # (points, 3): a fresh point's slip direction, lagged
    relags: int = 0  # in this step
    #: FEBio's node-on-facet slip ("contact" anchors): the target body's rest positions (the
    #: reference metric); Lt is then covariant, in traction[:, :2]
    rest: np.ndarray | None = None
    #: the points and M^-1 of the multipliers last augmented (FEBio's norm of the old ones)
    metric_inverse: tuple | None = None

    @classmethod
    def empty(cls, n_points: int) -> FrictionState:
        return cls(np.zeros((n_points, 3)), np.full(n_points, -1), np.zeros((n_points, 2)),
                   np.zeros(n_points), np.zeros((n_points, 3)), np.zeros(n_points, bool),
                   np.zeros((n_points, 3)))  # fmt: skip


def _pressures(p, contacts, positions, eps, multipliers):
    """(points, p_n, n) of pass p's points with a facet now."""
    pts, facet, rs, x = contacts
    if len(pts) == 0:
        return pts, np.zeros(0), np.zeros((0, 3))
    X = positions[p.target.body][p.target.facets.nodes[facet]]
    g, nu, _ = gap_derivatives(x, None, X, rs, p.target.facets.kind[facet], 0)
    return pts, np.maximum(multipliers[pts] + eps[pts] * g, 0.0), nu


#: where a point is anchored: "step": where it projects at each step's start (FEBio's
#: sliding-elastic; a point not in contact then slides in this step); "contact": where it first
#: projected, kept while it projects (FEBio's sliding-node-on-facet)
ANCHORS = ("step", "contact")


def anchor(state: FrictionState, p, contacts, positions, eps, multipliers, how: str) -> None:
    """At a step's start (the last converged positions): the anchors (``ANCHORS``), the
    lagged pressures and normals; a point that loses its anchor (``contact``) or its contact
    (``step``) loses its tangential multiplier, as FEBio resets it."""
    pts, facet, rs, _ = contacts
    _, pn, nu = _pressures(p, contacts, positions, eps, multipliers)
    n = len(state.facet)
    now = np.zeros(n, bool)
    now[pts] = True
    if how == "step":
        touching = np.zeros(n, bool)
        touching[pts[pn > 0]] = True
        state.traction[~touching] = 0.0
        state.facet[:] = -1
        state.facet[pts], state.rs[pts] = facet, rs
        state.fresh = ~touching
    else:
        state.facet[~now] = -1
        state.traction[~now] = 0.0
        new = pts[state.facet[pts] < 0]
        k = np.searchsorted(pts, new)
        state.facet[new], state.rs[new] = facet[k], rs[k]
        state.fresh[:] = False
    state.pressure[:] = 0.0
    state.pressure[pts], state.normal[pts] = pn, nu
    state.direction[:] = 0.0
    state.relags = 0


def lag(state: FrictionState, p, contacts, positions, eps, multipliers, eps_t) -> bool:
    """At a converged solution: the anchored points' pressures and normals now (and fresh
    points' slip directions); whether they moved by more than ``LAG_SETTLED`` (then Newton
    solves again, at most ``FRICTION_RELAGS`` times a step)."""
    turned = _turn(state, p, positions, eps_t)
    pts, pn, nu = _pressures(p, contacts, positions, eps, multipliers)
    new_p = np.zeros_like(state.pressure)
    new_n = state.normal.copy()
    new_p[pts], new_n[pts] = pn, nu
    new_p[state.facet < 0] = 0.0
    scale = max(float(np.max(new_p, initial=0.0)), float(np.max(state.pressure, initial=0.0)))
    on = new_p > 0
    moved = scale > 0 and (
        float(np.max(np.abs(new_p - state.pressure), initial=0.0)) > LAG_SETTLED * scale
        or float(np.max(np.abs(new_n - state.normal)[on], initial=0.0)) > LAG_SETTLED
    )
    state.pressure, state.normal = new_p, new_n
    if (moved or turned) and state.relags < FRICTION_RELAGS:
        state.relags += 1
        return True
    return False


def _turn(state: FrictionState, p, positions, eps_t) -> bool:
    """Fresh points' slip directions re-lagged to their unit trial tractions; whether any
    turned by more than ``LAG_SETTLED``."""
    pts, _, d = _geometry(state, p, positions)
    pts_f = state.fresh[pts]
    if not pts_f.any():
        return False
    pts, d = pts[pts_f], d[pts_f]
    tau, _ = _trial(state, pts, d, eps_t[pts])
    size = np.linalg.norm(tau, axis=1)
    # a slip below 1e-9 of the point's size is round-off (a point pressed straight in): no
    # direction, no friction (FEBio's zero slip direction)
    tiny = SLIP_ROUNDOFF * np.sqrt(p.weights[pts]) * eps_t[pts]
    s = np.where((size > tiny)[:, None], tau / np.where(size > 0, size, 1.0)[:, None], 0.0)
    turned = float(np.max(np.abs(s - state.direction[pts]))) > LAG_SETTLED
    state.direction[pts] = s
    return turned


def _geometry(state: FrictionState, p, positions):
    """(points anchored and pressed, stencil weights (n, k + m), d = x - a (n, 3))."""
    pts = np.flatnonzero((state.facet >= 0) & (state.pressure > 0))
    facet, rs = state.facet[pts], state.rs[pts]
    sf, tf = p.sampled.facets, p.target.facets
    Hs = p.points.H[pts]
    x = np.einsum("na,nad->nd", Hs, positions[p.sampled.body][sf.nodes[p.points.facet[pts]]])
    Ha = shape(rs[:, 0], rs[:, 1], tf.kind[facet], tf.nodes.shape[1])
    a = np.einsum("na,nad->nd", Ha, positions[p.target.body][tf.nodes[facet]])
    return pts, np.concatenate([Hs, -Ha], axis=1), x - a


def _stencil(state: FrictionState, p, dofs, pts: np.ndarray) -> np.ndarray:
    """(n, 3 (k + m)) DOFs of each point's sampled facet, then its anchor's facet."""
    return np.concatenate(
        [
            dofs[p.sampled.body][p.sampled.facets.nodes[p.points.facet[pts]]],
            dofs[p.target.body][p.target.facets.nodes[state.facet[pts]]],
        ],
        axis=1,
    ).reshape(len(pts), -1)


def return_map(tau: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the traction on the cone |t| <= m, whether each point sticks)."""
    size = np.linalg.norm(tau, axis=1)
    stick = size <= m
    scale = np.where(stick, 1.0, m / np.where(size > 0, size, 1.0))
    return tau * scale[:, None], stick


def _trial(state, pts, d, eps_t):
    n = state.normal[pts]
    v = state.traction[pts] + eps_t[:, None] * d
    return v - n * np.einsum("nd,nd->n", v, n)[:, None], n


def friction_terms(state: FrictionState, p, positions, dofs, eps_t, mu: float, order: int,
                   grad, rows_out, cols_out, vals_out) -> float:  # fmt: skip
    """The pass's friction energy; its gradient and Hessian added in place (``order``).
    ``eps_t``: the tangential penalty per point of the pass."""
    if state.rest is not None:
        return _natural_terms(state, p, positions, dofs, eps_t, mu, order, grad, rows_out,
                              cols_out, vals_out)  # fmt: skip
    pts, w, d = _geometry(state, p, positions)
    if len(pts) == 0:
        return 0.0
    et = eps_t[pts]
    W = p.weights[pts]
    m = mu * state.pressure[pts]
    tau, n = _trial(state, pts, d, et)
    fresh = state.fresh[pts]
    t, stick = return_map(tau, m)
    size = np.linalg.norm(tau, axis=1)
    phi = np.where(stick, size**2 / (2 * et), (m * size - m**2 / 2) / et)
    s = state.direction[pts]
    phi[fresh] = m[fresh] * np.einsum("nd,nd->n", s[fresh], d[fresh])  # lagged: linear
    t[fresh] = m[fresh, None] * s[fresh]
    value = float(np.sum(W * phi))
    if order < 1:
        return value
    stencil = _stencil(state, p, dofs, pts)
    width = stencil.shape[1]
    np.add.at(grad, stencil, (w[:, :, None] * (W[:, None] * t)[:, None, :]).reshape(-1, width))
    if order >= 2:
        P = np.eye(3)[None] - n[:, :, None] * n[:, None, :]
        safe = np.where(size > 0, size, 1.0)
        that = tau / safe[:, None]
        slip = ~stick
        k = np.where(stick, W * et, np.where(size > 0, W * m * et / safe, 0.0))
        k[fresh] = 0.0
        D = P.copy()
        D[slip] -= that[slip, :, None] * that[slip, None, :]
        h = np.einsum("nab,nij->naibj", k[:, None, None] * w[:, :, None] * w[:, None, :], D)
        rows_out.append(np.repeat(stencil, width, axis=1).ravel())
        cols_out.append(np.tile(stencil, (1, width)).ravel())
        vals_out.append(h.reshape(len(pts), width, width).ravel())
    return value


def force(state: FrictionState, p, positions, eps_t, mu: float) -> np.ndarray:
    """The friction force the secondary surface puts on this pass's points (N, 3)."""
    if state.rest is not None:
        pts, W, D, T = _natural(state, p, positions, eps_t, mu)[:4]
        if len(pts) == 0:
            return np.zeros(3)
        k = p.sampled.facets.nodes.shape[1]
        on_point = np.einsum("naj,na->nj", D[:, :, : 3 * k].reshape(len(pts), 2, k, 3).sum(2), T)
        return -np.sum(W[:, None] * on_point, axis=0)
    pts, _, d = _geometry(state, p, positions)
    if len(pts) == 0:
        return np.zeros(3)
    return -np.sum(p.weights[pts][:, None] * _traction(state, pts, d, eps_t, mu), axis=0)


def _traction(state, pts, d, eps_t, mu):
    """The returned tractions of anchored points (fresh ones: along their lagged slip)."""
    tau, _ = _trial(state, pts, d, eps_t[pts])
    m = mu * state.pressure[pts]
    t, _ = return_map(tau, m)
    fresh = state.fresh[pts]
    t[fresh] = m[fresh, None] * state.direction[pts][fresh]
    return t


def augment(state: FrictionState, p, positions, eps_t, mu: float) -> tuple:
    """FEBio's augmentation of the tangential multipliers at a converged solution: Lt <- the
    returned traction. (old and new squared norms, for the pair's convergence check, and the
    new multipliers, which the pair keeps if it augments)."""
    if state.rest is not None:  # covariant multipliers, FEBio's norm Lt . M^-1 Lt
        pts, _, _, T, Mi = _natural(state, p, positions, eps_t, mu)[:5]
        old = 0.0
        if state.metric_inverse is not None:
            at, mi = state.metric_inverse
            Lt = state.traction[at, :2]
            old = float(np.einsum("na,nab,nb->", Lt, mi, Lt))
        out = state.traction.copy()
        out[pts, :2] = T
        state.metric_inverse = (pts, Mi)
        return old, float(np.einsum("na,nab,nb->", T, Mi, T)), out
    pts, _, d = _geometry(state, p, positions)
    old = float(np.sum(state.traction**2))
    out = state.traction.copy()
    if len(pts):
        out[pts] = _traction(state, pts, d, eps_t, mu)
    return old, float(np.sum(out**2)), out


def _natural(state: FrictionState, p, positions, eps_t, mu: float):
    """FEBio's node-on-facet slip (module docstring) of the anchored, pressed points: (points,
    weights W, dr/dy (n, 2, 3(k + m)), the returned covariant tractions T_ret (n, 2), M^-1
    (n, 2, 2), the trial T (n, 2), stick (n,), M, |T|, the cone m, eps_t)."""
    pts = np.flatnonzero((state.facet >= 0) & (state.pressure > 0))
    sf, tf = p.sampled.facets, p.target.facets
    facet = state.facet[pts]
    kind, m = tf.kind[facet], tf.nodes.shape[1]
    Hs = p.points.H[pts]
    x = np.einsum("na,nad->nd", Hs, positions[p.sampled.body][sf.nodes[p.points.facet[pts]]])
    X = positions[p.target.body][tf.nodes[facet]]
    rs = project(x, X, kind)
    _, D = projection_jacobian(x, Hs, X, rs, kind)
    Hr, Hsd = shape_derivatives(rs[:, 0], rs[:, 1], kind, m)[:2]
    X0 = state.rest[tf.nodes[facet]]
    tangents = np.stack([np.einsum("na,nad->nd", Hr, X0), np.einsum("na,nad->nd", Hsd, X0)], 1)
    M = np.einsum("nad,nbd->nab", tangents, tangents)  # the reference metric at r, held
    Mi = np.linalg.inv(M)
    et = eps_t[pts]
    T = state.traction[pts, :2] + et[:, None] * np.einsum("nab,nb->na", M, rs - state.rs[pts])
    size = np.sqrt(np.maximum(np.einsum("na,nab,nb->n", T, Mi, T), 0.0))
    cone = mu * state.pressure[pts]
    stick = size <= cone
    scale = np.where(stick, 1.0, cone / np.where(size > 0, size, 1.0))
    return pts, p.weights[pts], D, T * scale[:, None], Mi, T, stick, M, size, cone, et


def _natural_terms(state, p, positions, dofs, eps_t, mu, order, grad, rows_out, cols_out,
                   vals_out) -> float:  # fmt: skip
    """``friction_terms`` with FEBio's node-on-facet slip (module docstring)."""
    pts, W, D, T_ret, _, T, stick, M, size, cone, et = _natural(state, p, positions, eps_t, mu)
    if len(pts) == 0:
        return 0.0
    phi = np.where(stick, size**2 / (2 * et), (cone * size - cone**2 / 2) / et)
    value = float(np.sum(W * phi))
    if order < 1:
        return value
    stencil = _stencil(state, p, dofs, pts)
    np.add.at(grad, stencil, W[:, None] * np.einsum("nai,na->ni", D, T_ret))
    if order >= 2:
        safe = np.where(size > 0, size, 1.0)
        slip = (cone * et / safe)[:, None, None] * (
            M - np.einsum("na,nb->nab", T, T) / (safe**2)[:, None, None]
        )
        second = np.where(stick[:, None, None], et[:, None, None] * M, slip)
        h = W[:, None, None] * np.einsum("nai,nab,nbj->nij", D, second, D)
        width = stencil.shape[1]
        rows_out.append(np.repeat(stencil, width, axis=1).ravel())
        cols_out.append(np.tile(stencil, (1, width)).ravel())
        vals_out.append(h.ravel())
    return value
