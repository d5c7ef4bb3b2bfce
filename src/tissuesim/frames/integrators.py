"""Time steps of frame-based bodies: quasistatic, Backward Euler (Newton) and explicit.

State: x is the configuration z (12 per frame), v the tangent velocity (6 or 12 per frame; for
rigid frames (v_i, omega_i) with omega the spatial angular velocity, Rdot = omega^ R).

Backward Euler (Bosman et al. section 3.3.2, as an incremental potential over the integration
points' positions p = E z):

    z_{n+1} = argmin_z 1/(2 h^2) (z - z_pred)^T M_z (z - z_pred) + E(z) - f(t_{n+1}) . z + springs,
    z_pred = z_n (+) h v_n  (rotations advanced by exp(h omega^)),
    v_{n+1} = (z_{n+1} (-) z_n) / h  (rotations by log(R_{n+1} R_n^T)).

The inertia term is sum_s m_s / (2 h^2) |p_s(z) - p_s(z_pred)|^2, exact for any rotation; with
affine frames the whole scheme is the usual linear-mass Backward Euler. Newton minimises it over
tangent steps with the multiplicative update (``solve/newton.py``'s ``retract``).

Explicit (eq. 18, symplectic Euler): M_q(z_n) a = T^T (f_ext - dE/dz - M_z c), c = zdd - T qdd the
centripetal part (omega x (omega x A[:, b]) for rigid frames, 0 for affine), then
v_{n+1} = v_n + h a, z_{n+1} = z_n (+) h v_{n+1}. M_q = T^T M_z T is the (sparse) generalised mass
at z_n; it is factorised every step for rigid frames and once for affine frames (constant).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from tissuesim.energies.loads import ExternalForce
from tissuesim.energies.mass import Inertia
from tissuesim.solve.newton import minimize
from tissuesim.time.implicit import choose_start
from tissuesim.time.state import State, StepOutcome

__all__ = [
    "frame_quasistatic_step",
    "frame_backward_euler_step",
    "frame_explicit_step",
    "frame_critical_time_step",
]


def _solve(model, state: State, h: float, energies, candidates, solver, options) -> StepOutcome:
    t1 = state.time + h

    def evaluate(z: np.ndarray, order: int, project: bool):
        return model.evaluate(z, order, project, energies)

    z0 = choose_start(evaluate, candidates, lambda z: model.apply_prescribed(z, t1))
    z1, record = minimize(
        evaluate,
        z0,
        model.elimination,
        solver,
        options,
        force_scale=model.force_scale,
        length_scale=model.length_scale,
        retract=model.frame_type.retract,
    )
    if not record.converged:
        return StepOutcome(None, False, [record], record.reason)
    v1 = model.frame_type.difference(z1, state.x) / h
    return StepOutcome(State(t1, z1, v1), True, [record])


def frame_quasistatic_step(model, state: State, h: float, solver, options) -> StepOutcome:
    t1 = state.time + h
    energies = (ExternalForce(model.external_force(t1)), *model.spring_energies(t1))
    outcome = _solve(model, state, h, energies, (state.x,), solver, options)
    if outcome.converged:  # quasistatics has no velocity
        outcome.state = State(outcome.state.time, outcome.state.x, np.zeros_like(state.v))
    return outcome


def frame_backward_euler_step(model, state: State, h: float, solver, options) -> StepOutcome:
    t1 = state.time + h
    z_pred = model.frame_type.retract(state.x, h * state.v)
    energies = (
        Inertia(model.mass, z_pred, h),
        ExternalForce(model.external_force(t1)),
        *model.spring_energies(t1),
    )
    return _solve(model, state, h, energies, (z_pred, state.x), solver, options)


def _free_mass_factor(model, z: np.ndarray, free: np.ndarray):
    M = model.tangent_mass(z)
    return spla.splu(M[free][:, free].tocsc())


def frame_explicit_step(model, state: State, h: float, solver=None, options=None) -> StepOutcome:
    z, v, ft = state.x, state.v, model.frame_type
    t0, t1 = state.time, state.time + h
    acc = model.evaluate_z(z, 1, False, model.spring_energies(t0))
    f_z = model.external_force(t0) - acc.gradient
    f_z -= model.mass.dot(ft.centripetal(z, v))
    rhs = ft.tangent_gradient(z, f_z)
    free = np.ones(model.n_dofs, dtype=bool)
    free[model.prescribed_dofs] = False
    cache = getattr(model, "_explicit_factor", None)
    if ft.rigid or cache is None or cache[0] is not model.elimination:
        cache = (model.elimination, _free_mass_factor(model, z, free))
        if not ft.rigid:
            model._explicit_factor = cache  # affine frames: M_q = M_z is constant
    a = np.zeros_like(v)
    a[free] = cache[1].solve(rhs[free])
    v1 = v + h * a
    v1[~free] = 0.0
    z1 = ft.retract(z, h * v1)
    if model.prescribed:
        z1 = model.apply_prescribed(z1, t1)
        v1 = np.where(free, v1, ft.difference(z1, z) / h)
    if not (np.all(np.isfinite(z1)) and np.isfinite(acc.value)):
        return StepOutcome(
            None,
            False,
            [],
            f"explicit step blew up; time_step {h:g} s exceeds the stability limit "
            f"(estimate {frame_critical_time_step(model, z, t0):.3g} s)",
        )
    return StepOutcome(State(t1, z1, v1), True, [])


def frame_critical_time_step(model, z: np.ndarray | None = None, t: float = 0.0) -> float:
    """2 / omega_max of K_q v = omega^2 M_q v at z (rest by default), springs included, free
    DOFs only."""
    z = model.rest_config() if z is None else z
    acc = model.evaluate(z, 2, False, model.spring_energies(t))
    free = np.ones(model.n_dofs, dtype=bool)
    free[model.prescribed_dofs] = False
    K = model.assembly.q_pattern.matrix(acc.hessian)[free][:, free]
    M = model.tangent_mass(z)[free][:, free]
    if K.shape[0] <= 400:
        from scipy.linalg import eigh

        lam = eigh(K.toarray(), M.toarray(), eigvals_only=True)[-1]
    else:
        lam = spla.eigsh(K.tocsc(), k=1, M=M.tocsc(), which="LM", return_eigenvectors=False)[0]
    return float(2.0 / np.sqrt(max(lam, 1e-300)))
