"""Newmark's method as an incremental potential (FEBio's dynamic integrator; with beta = 1/4,
gamma = 1/2 the trapezoidal rule, which keeps the energy of a linear system instead of
damping it as Backward Euler does).

Newmark's update a_{n+1} = (x_{n+1} - x_pred) / (beta h^2) with the predictor
x_pred = x_n + h v_n + h^2 (1/2 - beta) a_n turns the equation of motion
M a_{n+1} + dE/dx(x_{n+1}) = f(t_{n+1}) into the stationarity condition of

    Phi(x) = 1/(2 beta h^2) |x - x_pred|_M^2 + E(x) - f(t_{n+1}) . x,

Backward Euler's incremental potential with the time step sqrt(beta) h in the inertia term
and x_pred as the prediction. The step is therefore Backward Euler's minimisation
(``time/steps.py implicit_step``, contact, line search and all) from a state whose velocity
carries x_n to x_pred in sqrt(beta) h, with the loads, prescribed values, obstacles and the
friction's smoothing at the real step's end and length; then
v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1}).

The first step of a run starts from FEBio's initial acceleration a_0 = M^-1 f(t_0) on the
free DOFs (the external loads only, as FEBio's ``InitAccelerations``); a dynamic phase after
a quasistatic one starts from rest (a = 0, v = 0), as FEBio's does after a static step.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse.linalg as spla

from tissuesim.errors import InputError
from tissuesim.time.state import State, StepOutcome

__all__ = ["newmark_step", "check_newmark", "initial_acceleration"]


def check_newmark(parameters) -> tuple[float, float]:
    """(beta, gamma) checked: the range 1/2 <= gamma <= 2 beta <= 2 where Newmark's method is
    unconditionally stable (the trapezoidal rule is (1/4, 1/2)); beta = 0, the explicit
    central difference, has no incremental potential."""
    try:
        beta, gamma = (float(v) for v in parameters)
    except (TypeError, ValueError):
        raise InputError(
            f"newmark must be (beta, gamma), e.g. (0.25, 0.5), not {parameters!r:.60}"
        ) from None
    if not (0.5 <= gamma <= 2.0 * beta <= 2.0):
        raise InputError(
            f"newmark (beta, gamma) = ({beta:g}, {gamma:g}): tissuesim runs the unconditionally "
            "stable range 1/2 <= gamma <= 2 beta <= 2 (the trapezoidal rule is (0.25, 0.5))"
        )
    return beta, gamma


def initial_acceleration(system, models, t: float) -> np.ndarray:
    """a_0 = M^-1 f(t) on each FEM body's free DOFs (zero on its prescribed ones), f its
    external loads (gravity, body forces, tractions, nodal forces) at time t."""
    if getattr(system, "links", None) is not None:
        return _initial_acceleration_with_rigid(system, models, t)
    a = np.zeros(system.n_dofs)
    for j, model in enumerate(models):
        f = model.external_force(t)
        if not np.any(f):
            continue
        free = np.ones(model.n_dofs, dtype=bool)
        free[model.prescribed_dofs] = False
        M = model.mass.matrix().tocsr()[free][:, free].tocsc()
        block = np.zeros(model.n_dofs)
        block[free] = spla.spsolve(M, f[free])
        a[system.config_slices[j]] = block
    return a


def _initial_acceleration_with_rigid(system, models, t: float) -> np.ndarray:
    """a_0 = M^-1 f over the reduced DOFs of a system with rigid bodies (their glued vertices
    follow them: x = P q, M_q = P^T M P, f_q = P^T f plus their own loads); the glued
    vertices' a_0 is then T a_0 of their rigid body."""
    import scipy.sparse as sp

    n = system.n_dofs
    blocks, f = [], np.zeros(n)
    for j, model in enumerate(models):
        st = system.tangent_slices[j]
        blocks.append((st.start, model.mass.matrix().tocoo()))
        f[st] = model.external_force(t)
    rows = np.concatenate([b.row + o for o, b in blocks])
    cols = np.concatenate([b.col + o for o, b in blocks])
    M = sp.csr_matrix((np.concatenate([b.data for _, b in blocks]), (rows, cols)), shape=(n, n))
    for r, st in zip(system.rigid, system.rigid_tangent_slices, strict=True):
        force, moment = r.loads(t)
        f[st] += np.concatenate([force, moment])
    links = system.links
    T = links.tangent_map(links.arms(system.rest_config()))
    keep = np.ones(n)
    keep[links.dofs.ravel()] = 0.0
    P = (sp.diags(keep) + T).tocsr()
    free = np.ones(n, dtype=bool)
    free[system.prescribed_dofs] = False
    Mq = (P.T @ M @ P).tocsr()[free][:, free].tocsc()
    fq = (P.T @ f)[free]
    q = np.zeros(n)
    if np.any(fq):
        q[free] = spla.spsolve(Mq, fq)
    return P @ q


def newmark_step(
    system,
    state: State,
    h: float,
    solver,
    options,
    *,
    beta: float,
    gamma: float,
    implicit_step,
    **kwargs,
) -> StepOutcome:
    """One Newmark step of h s: Backward Euler's minimisation with the inertia of
    sqrt(beta) h about x_pred, then Newmark's acceleration and velocity updates."""
    a_n = np.zeros(system.n_dofs) if state.a is None else state.a
    # over the tangent DOFs (a rigid body's rotation on the left, rigid/body.py); for FEM
    # bodies the retraction is x + dx and the difference x1 - x0
    step = h * state.v + h * h * (0.5 - beta) * a_n
    x_pred = system.retract(state.x, step)
    h_inertia = math.sqrt(beta) * h
    # the velocity that carries x_n to x_pred in h_inertia: Backward Euler's prediction is then
    # Newmark's, and contact sweeps the predicted motion
    carried = State(state.time, state.x, system.difference(x_pred, state.x) / h_inertia)
    outcome = implicit_step(
        system,
        carried,
        h_inertia,
        solver,
        options,
        dynamic=True,
        t_end=state.time + h,
        friction_h=h,
        **kwargs,
    )
    if not outcome.converged:
        return outcome
    x1 = outcome.state.x
    a1 = system.difference(x1, x_pred) / (beta * h * h)
    v1 = state.v + h * ((1.0 - gamma) * a_n + gamma * a1)
    outcome.state = State(state.time + h, x1, v1, a1)
    return outcome
