"""The contact problem of a step on the compliance W: Signorini with Coulomb friction, by
projected block Gauss-Seidel (Jourdan, Alart & Jean 1998; Duriez et al. 2006, SOFA's
``GenericConstraintSolver``), warm-started.

Per pair i, unknown force lambda_i = (normal, tangents) in newtons, values u_i = b_i + sum_j
W_ij lambda_j (m) (+ soft_i lambda_i,n in the normal: a compliance of the pair's own): the gap
above its target (normal) and the slip over the step (tangents). Sought:

    0 <= lambda_n  _|_  u_n >= 0                           (Signorini: target gap in b)
    |lambda_t| <= mu lambda_n, and u_t = -s lambda_t, s >= 0, where |lambda_t| = mu lambda_n
                                                           (Coulomb: stick or slide against)

Each sweep visits the pairs in turn: the normal force from its own row with the others held,
clamped at 0, then the tangential force from the 2 x 2 (2D: 1 x 1) block, projected onto the
disc of radius mu lambda_n: in 2D by clamping, in 3D (two tangents) as the point of the disc's
edge where the block's slip opposes the force, (A + sigma I) t = -c, |t| = mu lambda_n (a
radial clamp would not: the block A is not isotropic). The sweeps stop when no force changes
by more than ``tolerance`` of the largest, or no value u by more than ``tolerance`` of the
largest free value |b| over 10 (pairs that share a load redundantly: the forces drift, the motion
does not). Compiled with numba when installed
(``tissuesim[fast]``), else the same function runs in Python (fine for tens of pairs, slow for
hundreds).
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["solve_signorini_coulomb", "SignoriniResult"]


def _gauss_seidel(
    W, b, mu, soft, smooth, lam, d, max_sweeps, tolerance, value_tolerance
):  # pragma: no cover
    # w = W lambda kept up to date as forces change (W symmetric: row r is column r), so a
    # pair whose force stays zero costs O(1) a sweep, a changed one O(rows)
    n = b.shape[0]
    m = n // d
    w = np.zeros(n)
    for j in range(n):
        if lam[j] != 0.0:
            for k in range(n):
                w[k] += W[j, k] * lam[j]
    sweeps = 0
    for sweep in range(max_sweeps):
        sweeps = sweep + 1
        change = 0.0
        largest = 1e-300
        w_start = w.copy()
        for i in range(m):
            r = i * d
            # normal: u_n = b_n + (W lambda)_n (+ soft lambda_n) = 0 when the force is positive
            u = b[r] + w[r] + soft[i] * lam[r]
            old = lam[r]
            new = old - u / (W[r, r] + soft[i])
            if new < 0.0:
                new = 0.0
            if new != old:
                delta = new - old
                lam[r] = new
                for k in range(n):
                    w[k] += W[r, k] * delta
            if abs(new - old) > change:
                change = abs(new - old)
            if new > largest:
                largest = new
            if d == 1:
                continue
            limit = mu[i] * new
            nt = d - 1
            t0, t1 = 0.0, 0.0
            old0 = lam[r + 1]
            old1 = lam[r + 2] if nt == 2 else 0.0
            if limit > 0.0:
                # tangents: the block's own solve for zero slip, then onto the disc; IPC's
                # smoothed static friction lets a pair slip up to eps_v h at a force growing
                # as 2 mu lambda_n / (eps_v h) per metre: a compliance of the pair's own
                own = smooth[i] / limit
                u0 = b[r + 1] + w[r + 1] + own * old0
                if nt == 1:
                    t0 = old0 - u0 / (W[r + 1, r + 1] + own)
                    if abs(t0) > limit:
                        t0 = limit if t0 > 0.0 else -limit
                else:
                    u1 = b[r + 2] + w[r + 2] + own * old1
                    a11, a12 = W[r + 1, r + 1] + own, W[r + 1, r + 2]
                    a22 = W[r + 2, r + 2] + own
                    det = a11 * a22 - a12 * a12
                    t0 = old0 - (a22 * u0 - a12 * u1) / det
                    t1 = old1 - (a11 * u1 - a12 * u0) / det
                    norm = np.sqrt(t0 * t0 + t1 * t1)
                    if norm > limit:
                        # sliding: the force on the disc's edge whose slip opposes it, the
                        # block's (A + sigma I) t = -c with |t| = limit (Newton on sigma >= 0),
                        # c = u_t - A t_old the slip without this pair's tangential force
                        c0 = u0 - a11 * old0 - a12 * old1
                        c1 = u1 - a12 * old0 - a22 * old1
                        sigma = 0.0
                        for _ in range(30):
                            p11, p22 = a11 + sigma, a22 + sigma
                            dd = p11 * p22 - a12 * a12
                            t0 = -(p22 * c0 - a12 * c1) / dd
                            t1 = -(p11 * c1 - a12 * c0) / dd
                            norm = np.sqrt(t0 * t0 + t1 * t1)
                            # d|t|/dsigma = -t.(A + sigma I)^-1 t / |t|
                            q0 = (p22 * t0 - a12 * t1) / dd
                            q1 = (p11 * t1 - a12 * t0) / dd
                            slope = -(t0 * q0 + t1 * q1) / norm
                            sigma = max(sigma - (norm - limit) / slope, 0.5 * sigma)
                            if abs(norm - limit) <= 1e-12 * limit:
                                break
                        t0 *= limit / norm
                        t1 *= limit / norm
                    norm = np.sqrt(t0 * t0 + t1 * t1)
                    if norm > limit:
                        t0 *= limit / norm
                        t1 *= limit / norm
            for a, (new_t, old_t) in enumerate(((t0, old0), (t1, old1))):
                if a >= nt:
                    break
                if new_t != old_t:
                    lam[r + 1 + a] = new_t
                    delta = new_t - old_t
                    for k in range(n):
                        w[k] += W[r + 1 + a, k] * delta
                    if abs(delta) > change:
                        change = abs(delta)
        if change <= tolerance * largest:
            return sweeps, True
        # or no gap or slip moved: redundant pairs (a body resting on many points) share
        # their load in ways W cannot tell apart, where the forces drift but not the motion
        moved = 0.0
        for k in range(n):
            if abs(w[k] - w_start[k]) > moved:
                moved = abs(w[k] - w_start[k])
        if moved <= value_tolerance:
            return sweeps, True
    return sweeps, False


@functools.cache
def _kernel():
    """The compiled sweep (numba, cached on disk) or the Python function."""
    try:
        import numba
    except ImportError:
        return _gauss_seidel
    return numba.njit(cache=True, nogil=True)(_gauss_seidel)  # nogil: a haptic thread


class SignoriniResult:
    """``force`` (m, d) per pair [normal, tangents] (N); ``values`` (m, d) u = b + W lambda
    (m): gaps above their targets and slips; ``sweeps``; ``converged``."""

    def __init__(self, force: np.ndarray, values: np.ndarray, sweeps: int, converged: bool):
        self.force, self.values, self.sweeps, self.converged = force, values, sweeps, converged


def solve_signorini_coulomb(
    W: np.ndarray,
    b: np.ndarray,
    mu: np.ndarray,
    warm: np.ndarray | None = None,
    soft: np.ndarray | None = None,
    smoothing: float | np.ndarray = 0.0,
    *,
    max_sweeps: int = 200,
    tolerance: float = 1e-5,
) -> SignoriniResult:
    """Forces for m pairs of dimension d: W (m d, m d) compliance (m/N), b (m, d) the values
    without force (gap minus its target, slips), mu (m,), ``warm`` (m, d) a start, ``soft``
    (m,) a compliance of each pair's own (m/N, >= 0) added to its normal: the pair's gap
    target falls by soft lambda_n as it is loaded (a barrier's gap, linearised);
    ``smoothing`` (m, scalar or (m,)): half the slip over which friction reaches mu lambda_n,
    eps_v h / 2 for IPC's smoothed friction (0: exact Coulomb, no slip while sticking)."""
    m, d = b.shape
    lam = np.zeros(m * d) if warm is None else np.array(warm, dtype=float).reshape(-1)
    if m == 0:
        return SignoriniResult(np.zeros((0, d)), np.zeros((0, d)), 0, True)
    W = np.ascontiguousarray(W, dtype=float)
    rhs = np.ascontiguousarray(b, dtype=float).reshape(-1)
    soft = np.zeros(m) if soft is None else np.ascontiguousarray(soft, dtype=float)
    mu = np.ascontiguousarray(mu, dtype=float)
    smooth = np.ascontiguousarray(np.broadcast_to(np.asarray(smoothing, dtype=float), (m,)))
    # values to the tolerance of the largest free value (the step's largest gap or slip)
    value_tolerance = 0.1 * float(tolerance) * float(np.max(np.abs(rhs), initial=0.0))
    sweeps, converged = _kernel()(
        W, rhs, mu, soft, smooth, lam, d, int(max_sweeps), float(tolerance), value_tolerance
    )
    values = (rhs + W @ lam).reshape(m, d)
    values[:, 0] += soft * lam.reshape(m, d)[:, 0]
    return SignoriniResult(lam.reshape(m, d), values, int(sweeps), bool(converged))
