"""Derivatives of what a run reports with respect to its parameters, by differentiating the
steps as they were solved (the direct, forward method of the discrete sensitivities).

Each implicit step ends where the gradient of its incremental potential vanishes at the free
DOFs: g_f(x_n, x_pred, theta) = 0 (quasistatics: x_n alone; Backward Euler: the inertia
M (x_n - x_pred) / h^2 with x_pred = x_{n-1} + h v_{n-1}; Newmark: over beta h^2 with
x_pred = x_{n-1} + h v_{n-1} + h^2 (1/2 - beta) a_{n-1}, its a and v updates differentiated
alongside, and the first step's initial acceleration M^-1 f(t_0) through the copies).
Differentiating that equality in a parameter theta gives the step's sensitivity s_n = dx_n/dtheta:

    H_ff s_f = -b_f,   b = dg/dtheta at fixed free DOFs: the parameter's own term, the
                       prescribed DOFs moved by their own derivative s_p, and (Backward Euler)
                       the prediction moved by s_{n-1} + h ds_{n-1}/dt,

with H the exact Hessian of the step's potential at the converged x_n (factorised once per
step). b is the derivative of the assembled gradient along the parameter: central differences
of the step's gradient between two copies of the simulation built at theta +- delta (relative
1e-6) and evaluated at x_n with their own prescribed values and prediction (the gradient is
linear in the prescribed values and the prediction, and smooth in the laws' parameters, so
the difference is exact to about 1e-10 of the gradient). A reaction's derivative is the sum of
H_pf s_f + b_p over its DOFs; a displacement's is s at its DOFs. Every parameter costs one
back-solve and two gradient assemblies a step; the step's Hessian one assembly and one
factorisation, whatever the number of parameters.

With barrier contact the step's potential holds the barrier too (its exact Hessian, not the
PSD-projected one Newton uses, joins H; it is smooth, C2, where the step ended), with the
stiffness kappa the step was solved with (IPC's adaptive kappa is raised between steps: a
numerical constant, held); the copies' obstacles move along their own motions, so an
instrument's depth or path is a parameter like any other, and ``ContactForce`` observes an
obstacle's force (differentiated through the barrier's Hessian: observations.py). A moving
obstacle ends a step within ``kinematic.py``'s TOLERANCE (0.01 dhat) of its target, where the
augmented Lagrangian that drives it stopped: the copies' obstacles end as far off theirs
(that offset held, not differentiated).

IPC's friction (``held_friction.py``): its Hessian joins H, its slip's start (the step's start)
moves with the last step's sensitivity (a term of b), the copies are lagged as the base's step
(their own mu), and its lag point (normal forces, tangent bases) either moves with the state
(``friction_lag="converged"``, the default: d(dD/dV)/dV_lag joins H, which is then not
symmetric) or is held.

Laws with internal variables (viscoelasticity, damage, ...) carry their variables' derivative
from step to step (``history.py``): b holds the gradient's dependence on the last step's
variables along their derivative, and the update's derivative is taken through the copies.

What is differentiated: FEM bodies under quasistatics, Backward Euler or Newmark, any law
(internal variables included), supports, prescribed motions, graspers, loads and springs,
barrier contact (against obstacles and between bodies) with or without friction, FEBio's
penalty contact (an energy of the state: its exact Hessian joins H), its current-area
weights (sliding-elastic's, lagged to the converged state) followed through their own
derivative (``contact/penalty/area_coupling.py``: an unsymmetric term of H; the copies are
given the base's weights), Rayleigh damping (the copies' about the step's start moved along
its derivative: C(x_n) (x - x_n) / h), a reactive viscoelastic law's bond recruitment (its
forming bonds' brf lagged within the step to FEBio's fixed point X_lag = X(F(x_n)): the
copies are set at that lag and its derivative joins H, ``Model.lag_coupling``, unsymmetric);
penalty contact with other lagged terms (augmented,
friction, sticky),
interactive contact steps (a prediction, not a minimum), rigid bodies in
dynamic runs or with joints, and dynamic, friction or history steps that
halved are refused in one line (the derivative would be of a different sequence of solves).
Rigid bodies (quasistatic) are differentiated in the tangent space (configurations moved by
``retract`` and compared by ``difference``): their held DOFs and linked vertices as supports,
their free DOFs solved with the rest, ``RigidForce`` the gradient's derivative at a DOF.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from contextlib import nullcontext
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from tissuesim.errors import InputError
from tissuesim.identification.held_friction import HeldFriction, lag_stiffness, start_motion
from tissuesim.identification.history import HistoryDerivative
from tissuesim.identification.observations import linearize
from tissuesim.identification.refusals import check_taken
from tissuesim.identification.step_terms import (
    area_coupling,
    damping_from,
    follower_stiffness,
    lag_coupling,
)

__all__ = ["Sensitivities", "sensitivities"]

#: a friction lag point farther than this times dhat from a step's solution is reported
#: (``friction_lag="converged"`` assumes they coincide)
UNSETTLED_LAG = 1e-3

#: the relative step of the parameters' central differences (of the assembled gradient)
RELATIVE_STEP = 1e-6


@dataclass
class Sensitivities:
    """A run's observed values and their derivatives: ``values`` (steps, m), ``jacobian``
    (steps, m, p) d value / d parameter, ``times`` (steps,) s, ``labels`` (m,) and
    ``parameters`` (p,) names; wall times of the run and of the derivatives (s)."""

    parameters: list[str]
    labels: list[str]
    times: np.ndarray
    values: np.ndarray
    jacobian: np.ndarray
    forward_s: float = 0.0
    sensitivity_s: float = 0.0
    simulations: int = 1
    records: list = field(default_factory=list, repr=False)


def _sync(sim, t_prev: float, t: float, kappa=None, offset=None, friction=None,
          areas=None) -> None:  # fmt: skip
    """Set a parameter copy's supports to the step from t_prev to t (as ``step`` does), and
    its contact to the step's end: its obstacles where its own motion puts them at t (plus
    ``offset``: where the base run's moving obstacles ended off their targets), the
    barrier's stiffness ``kappa`` the base run's step used (a numerical constant held, as
    the step was solved with it), its friction lagged as the base's step (``friction``, a
    ``HeldFriction``), its penalty contacts' current-area weights the base's (``areas``:
    per pair, per pass)."""
    tol = 1e-9 * sim.time_step
    for pair, weights in zip(sim.system.penalty_contacts, areas or (), strict=False):
        for p, w in zip(getattr(pair, "passes", ()), weights, strict=True):
            p.weights = w
    for body in sim.bodies.values():
        body.release_graspers(t_prev + tol)
        body.set_condition_time(t, tol)
    contact = sim.system.contact
    if contact is not None:
        contact.time, contact.obstacle_state = t, None
        if offset is not None:
            contact.obstacle_state = contact.obstacle_positions(t) + offset
        if kappa is not None and contact.kappa != kappa:
            contact.set_stiffness(kappa)
        if friction is not None:
            friction.install(contact)


def sensitivities(
    build: Callable[[dict], object],
    parameters: Mapping[str, float],
    observations: Sequence,
    steps: int,
    *,
    relative_step: float = RELATIVE_STEP,
    scales: Mapping[str, float] | None = None,
    friction_lag: str = "converged",
) -> Sensitivities:
    """Run ``build(parameters)`` (a function returning a ``Simulation``) for ``steps`` steps
    and return the ``observations`` (``Reaction``, ``Displacement``, ``SurfaceDistance``, or
    any with ``values(sim, x)``: module docstring) after each step with their derivatives with
    respect to every parameter. A parameter's difference is ``relative_step`` times its value,
    or times (|value| + its ``scales`` entry) where one is given (FEBio's
    ``f_diff_scale (|b| + |a|)``: a parameter that may be 0); without a scale it must be
    non-zero. ``friction_lag`` (IPC friction, ``held_friction.py``): "converged" (the lag
    point taken as the step's solution, its normal forces and tangent bases moving with it:
    the derivative of a run whose friction iterations converged) or "held" (constants: the
    derivative of the solves with their lags as they were)."""
    if friction_lag not in ("converged", "held"):
        raise InputError(
            f"sensitivities: friction_lag must be 'converged' or 'held', got {friction_lag!r}"
        )
    names = list(parameters)
    if not names:
        raise InputError("sensitivities: give at least one parameter")
    scales = dict(scales or {})
    theta = {}
    for k in names:
        v = parameters[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            raise InputError(f"sensitivities: parameter {k!r} must be a number, got {v!r}")
        if v == 0 and not scales.get(k):
            raise InputError(
                f"sensitivities: parameter {k!r} is 0: give it a scale (scales={{{k!r}: ...}}) "
                "for its difference, or a non-zero value"
            )
        theta[k] = float(v)
    from tissuesim.sweep import cache

    cache.install()
    start = time.perf_counter()
    with cache.enabled():  # the copies share the base's meshes and sparsity analysis
        base = build(dict(theta))
    check_taken(base, "sensitivities")
    copies = []
    for k in names:
        delta = relative_step * (abs(theta[k]) + abs(scales.get(k, 0.0)))
        pair = []
        for sign in (1.0, -1.0):
            with cache.enabled():
                sim = build({**theta, k: theta[k] + sign * delta})
            if sim.system.n_dofs != base.system.n_dofs:
                raise InputError(
                    f"sensitivities: parameter {k!r} changes the model's DOFs: only values "
                    "that keep the mesh and its supports can be differentiated"
                )
            pair.append(sim)
        copies.append((delta, pair))
    history = HistoryDerivative.of(base, copies)  # laws with internal variables
    build_s = time.perf_counter() - start
    labels: list[str] = []
    dynamic = base.integrator in ("backward_euler", "newmark")
    newmark = base.integrator == "newmark"
    beta, gamma = base.newmark if newmark else (0.0, 0.0)
    n, p = base.system.n_dofs, len(names)
    S_x, S_v, S_a = np.zeros((n, p)), np.zeros((n, p)), np.zeros((n, p))
    for j, (delta, pair) in enumerate(copies):  # the start's own (rest positions varied)
        S_x[:, j] = base.system.difference(pair[0].state.x, pair[1].state.x) / (2 * delta)
        S_v[:, j] = (pair[0].state.v - pair[1].state.v) / (2 * delta)
    contact = base.system.contact
    Y = None if contact is None else _obstacle_motion(base, copies, base.time)
    a_n = np.zeros(n)
    if newmark and base._state.a is None and not base.history:
        # the run's first step starts from FEBio's initial acceleration M^-1 f(t_0): its
        # derivative by the copies' (linear in the loads)
        from tissuesim.time.integrators.newmark import initial_acceleration

        a_n = initial_acceleration(base.system, base.system.bodies, base.time)
        for j, (delta, pair) in enumerate(copies):
            a_pm = [initial_acceleration(c.system, c.system.bodies, base.time) for c in pair]
            S_a[:, j] = (a_pm[0] - a_pm[1]) / (2 * delta)
    values, jac, times, records = [], [], [], []
    solver = _StepSolver()  # one analysis of the pattern for every step
    forward_s, sens_s = 0.0, 0.0
    unsettled = 0.0  # how far the friction's last lag point was from a step's solution (m)
    for _ in range(int(steps)):
        if base.finished:  # an adaptive run in phases: ``steps`` is an upper bound, as in run
            break
        x_prev, v_prev, t_prev = base._state.x.copy(), base._state.v.copy(), base.time
        Y_prev = Y
        if history is not None:
            history.start_step(base)
        tick = time.perf_counter()
        record = base.step()
        # the barrier's stiffness the step was solved with (IPC's adaptive one is raised after)
        kappa = None if contact is None else getattr(contact, "step_kappa", contact.kappa)
        # moving obstacles end within kinematic.py's TOLERANCE of their targets: the copies'
        # are put as far off theirs (the offset held)
        offset = None
        if contact is not None and contact.moving and contact.obstacle_state is not None:
            offset = contact.obstacle_state - contact.obstacle_positions(base.time)
        forward_s += time.perf_counter() - tick
        records.append(record)
        tick = time.perf_counter()
        t, x = base.time, base._state.x
        h = t - t_prev
        friction = HeldFriction.of(contact)
        # FEBio's sliding-elastic weighs its points by their current areas, lagged: held
        areas = [[p.weights.copy() for p in getattr(pair, "passes", ())]
                 for pair in base.system.penalty_contacts]  # fmt: skip
        if (dynamic or friction is not None or history is not None) and record.substeps != 1:
            why = base.integrator
            if friction is not None:
                why = "its friction slips from a sub-step"
            elif history is not None:
                why = "its laws' history was updated at its sub-steps"
            raise InputError(
                f"sensitivities: the step to t = {t:.6g} s halved ({why}): the "
                "derivative follows the steps as solved; use a smaller time_step"
            )
        s = base.system
        # the step's prediction and inertia step (Newmark's: x_n + h v_n + h^2 (1/2 - beta)
        # a_n over sqrt(beta) h, time/integrators/newmark.py) and their derivatives
        c_pred, h_in, dc = None, h, None
        if dynamic:
            c_pred = x_prev + h * v_prev + h * h * (0.5 - beta) * a_n
            dc = S_x + h * S_v + h * h * (0.5 - beta) * S_a
            h_in = np.sqrt(beta) * h if newmark else h
        # the step's own energies, as its solve built them (time/steps.py keeps them), and its
        # barrier with the stiffness it was solved with (the next step's may be raised)
        kept_kappa = None
        if contact is not None and contact.kappa != kappa:
            kept_kappa = contact.kappa
            contact.set_stiffness(kappa)
        with (
            contact.last_step_lag() if friction is not None else nullcontext(),
            history.as_solved(base, x_prev, h, x) if history is not None else nullcontext(),
            damping_from(base, x_prev, h),
        ):  # the step's potential as solved: its friction lag, its laws' history, its damping
            acc = s.evaluate(x, 2, False, s.last_step_energies)
            lag_move = lag_coupling(s, x)  # a recruitment's lag, as the step saw it
        g = acc.gradient
        B = np.zeros((n, p))
        Sp = np.zeros((n, p))
        dofs = np.asarray(s.elimination.dofs)
        if history is not None:  # the copies' internal variables along their derivative
            history.set_copies(x_prev, h, x)
        for j, (delta, pair) in enumerate(copies):
            grads, placed = [], []
            for sign, sim in zip((1.0, -1.0), pair, strict=True):
                _sync(sim, t_prev, t, kappa, offset, friction, areas)
                xs = sim.system.apply_prescribed(x, t)
                cs = None
                if dynamic:  # the prediction moved along its own derivative
                    cs = c_pred + sign * delta * dc[:, j]
                energies = sim.step_energies(t, cs, h_in)
                # Rayleigh damping about the step's start moved along its derivative (C(x_n)
                # and x_n in C (x - x_n) / h): the start's dependence and the law's in one
                with damping_from(sim, x_prev, h, sign * delta, S_x[:, j]):
                    grads.append(sim.system.evaluate(xs, 1, False, energies).gradient)
                placed.append(xs)
            B[:, j] = (grads[0] - grads[1]) / (2 * delta)
            Sp[dofs, j] = s.difference(placed[0], placed[1])[dofs] / (2 * delta)
        K = acc.pattern.matrix(acc.hessian).tocsr()
        H = acc.hessian.copy()
        s.elimination.apply(H, np.zeros(n))  # H_ff, and a diagonal at the prescribed DOFs
        A = acc.pattern.matrix(H)
        keep = sp.diags((~np.isin(np.arange(n), dofs)).astype(float))
        if acc.extra_hessian is not None:  # the barrier's (exact, not PSD-projected) Hessian
            K = (K + acc.extra_hessian).tocsr()
            A = (A + keep @ acc.extra_hessian @ keep).tocsc()
        follow = follower_stiffness(s, x)
        if follow is not None:  # a lagged pressure: the follower load's own (skew) stiffness
            K = K + follow
            A = (A + keep @ follow @ keep).tocsc()
        Y = _obstacle_motion(base, copies) if contact is not None else None
        symmetric = follow is None
        areas_move = area_coupling(s, x)
        if areas_move is not None:  # current-area weights follow the state (sliding-elastic)
            B = B + areas_move @ Sp  # with the prescribed DOFs' motion (the copies' are held)
            K = (K + areas_move).tocsr()
            A = (A + keep @ areas_move @ keep).tocsc()
            symmetric = False
        if lag_move is not None:  # a recruitment's lag at its fixed point follows the state
            B = B + lag_move @ Sp  # with the prescribed DOFs' motion (the copies' lag is held)
            K = (K + lag_move).tocsr()
            A = (A + keep @ lag_move @ keep).tocsc()
            symmetric = False
        if friction is not None:  # the slip's start moved by the last step's sensitivity
            W = start_motion(contact, x_prev, S_x, Y_prev)
            C, friction.start_motion_term = friction.start_term(contact, x, W)
            B = B + C
            if friction_lag == "converged":  # the lag point moves with the state
                unsettled = max(unsettled, friction.unsettled(contact, x))
                L = friction.lag_term = lag_stiffness(contact, x, friction)
                J = contact.selection(x)
                KL = (J.T @ L @ J).tocsr()
                B = B + KL @ Sp  # with the prescribed DOFs' motion (the copies' lag is held)
                if contact.n_obstacle:  # and with the obstacles' own motion
                    dY = np.zeros((L.shape[0], p))
                    dY[contact.n_deformable * contact.dim :] = Y
                    B = B + np.asarray(J.T @ (L @ dY))
                K = (K + KL).tocsr()
                A = (A + keep @ KL @ keep).tocsc()
                symmetric = False
        rhs = -B.copy()
        rhs[dofs] = 0.0
        Sf = solver.solve(A, rhs, symmetric=symmetric)
        Sf[dofs] = 0.0
        dG = K @ Sf + B  # the gradient's total derivative (B holds H_:p s_p)
        S = Sf + Sp
        if history is not None:  # the internal variables' update, then the copies at q_n
            history.update(x, S)
        vals, ders = [], []
        for i, ob in enumerate(observations):
            if hasattr(ob, "derivative"):
                with contact.last_step_lag() if friction is not None else nullcontext():
                    y, D = ob.derivative(base, x, S, Y, friction, copies)
            elif not hasattr(ob, "values") or hasattr(ob, "rows"):  # a linear read-out
                y, X, R = linearize(ob, base, x, g)
                D = X @ S + R @ dG
                if hasattr(ob, "rest"):  # a displacement from rest positions a parameter moves
                    for j, (delta, pair) in enumerate(copies):
                        D[:, j] -= (ob.rest(pair[0]) - ob.rest(pair[1])) / (2 * delta)
            else:
                y, D = _state_function(ob, base, x, S, copies)
            vals.append(np.asarray(y, dtype=float))
            ders.append(np.asarray(D).reshape(len(vals[-1]), p))
            if not times:
                labels += [f"{type(ob).__name__.lower()}[{i}]"] * len(vals[-1])
        if kept_kappa is not None:
            contact.set_stiffness(kept_kappa)
        values.append(np.concatenate(vals))
        jac.append(np.concatenate(ders))
        times.append(t)
        if newmark:  # a_{n+1} = (x_{n+1} - x_pred) / (beta h^2), v by gamma
            S_a1 = (S - dc) / (beta * h * h)
            S_v = S_v + h * ((1.0 - gamma) * S_a + gamma * S_a1)
            S_a, a_n = S_a1, base._state.a if base._state.a is not None else np.zeros(n)
        elif dynamic:
            S_v = (S - S_x) / h
        S_x = S
        sens_s += time.perf_counter() - tick
    if contact is not None and unsettled > UNSETTLED_LAG * contact.dhat:
        warnings.warn(
            f"sensitivities: the friction's last lag point was up to {unsettled:.2g} m from a "
            f"step's solution (dhat {contact.dhat:g} m): the derivative takes them as one and "
            "may be off the run's by per cents; raise the contact's friction_iterations "
            "(docs/guide/identify.md, Friction)",
            stacklevel=2,
        )
    return Sensitivities(names, labels, np.asarray(times), np.asarray(values), np.asarray(jac),
                         forward_s, sens_s + build_s, 1 + 2 * p, records)  # fmt: skip


def _obstacle_motion(base, copies: list, t: float | None = None) -> np.ndarray:
    """d y / d theta (n_obstacle coordinates, p): where each parameter's copies put the
    obstacles at the step's end (``_sync``), or where their motions put them at time t, by
    central differences (exact: their places are the motions' values)."""
    contact = base.system.contact
    Y = np.zeros((contact.n_obstacle, len(copies)))
    for j, (delta, pair) in enumerate(copies):
        at = []
        for sim in pair:
            c = sim.system.contact
            if t is not None:
                at.append(c.obstacle_positions(t))
                continue
            at.append(c.obstacle_state if c.obstacle_state is not None
                      else c.obstacle_positions(c.time))  # fmt: skip
        Y[:, j] = (at[0] - at[1]) / (2 * delta)
    return Y


#: the displacement (relative to the model's size) of a state function's directional difference
DIRECTIONAL_STEP = 1e-6


def _state_function(ob, sim, x: np.ndarray, S: np.ndarray, copies: list):
    """(y, dy/dtheta) of an observation y = ob.values(sim, x), a function of the state and the
    parameters (an element's stress): along each parameter's sensitivity S_j by central
    differences of the state, plus its own dependence on the parameter by the copies' values
    at the same state (both smooth: the differences are exact to about 1e-9 of y)."""
    y = np.asarray(ob.values(sim, x), dtype=float)
    D = np.zeros((y.size, S.shape[1]))
    scale = sim.system.length_scale
    for j, (delta, pair) in enumerate(copies):
        size = float(np.max(np.abs(S[:, j]), initial=0.0))
        if size > 0.0:
            eps = DIRECTIONAL_STEP * scale / size
            up = np.asarray(ob.values(sim, sim.system.retract(x, eps * S[:, j])), dtype=float)
            down = np.asarray(ob.values(sim, sim.system.retract(x, -eps * S[:, j])), dtype=float)
            D[:, j] = (up - down) / (2.0 * eps)
        if getattr(ob, "explicit", True):
            plus, minus = (np.asarray(ob.values(c, x), dtype=float) for c in pair)
            D[:, j] += (plus - minus) / (2.0 * delta)
    return y, D


class _StepSolver:
    """Solves with each step's eliminated Hessian (symmetric, positive definite at a stable
    equilibrium): PARDISO's Cholesky where pypardiso is installed, its analysis made once for
    the pattern the steps share; else (or where a matrix is not positive definite) SciPy's LU.
    Any number of right-hand sides."""

    def __init__(self) -> None:
        from tissuesim.solve.linear import PardisoSolver, has_pardiso

        self.pardiso = PardisoSolver() if has_pardiso() else None

    def solve(self, A, rhs: np.ndarray, symmetric: bool = True) -> np.ndarray:
        import scipy.sparse.linalg as spla

        from tissuesim.solve.linear import NotPositiveDefiniteError

        if self.pardiso is not None and not symmetric:  # PARDISO's real non-symmetric LU
            import pypardiso

            X = pypardiso.spsolve(sp.csr_matrix(A), np.asarray(rhs, dtype=float))
            return np.asarray(X).reshape(rhs.shape)
        if self.pardiso is not None:
            try:
                self.pardiso.factorize(A.tocsr())
                return self.pardiso.solve(rhs)
            except (NotPositiveDefiniteError, RuntimeError):
                pass
        # structurally symmetric (a follower load's skew part): the order of A + A^T and
        # pivots near the diagonal keep the fill of a Cholesky (COLAMD's was 20x slower)
        options = {"SymmetricMode": True, "DiagPivotThresh": 0.01}
        return spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", options=options).solve(rhs)
