"""The generalised-alpha method (Chung & Hulbert 1993) as FEBio runs it, as an incremental
potential: Newmark's update with the inertia taken at a_{n+alpha_m} and the internal forces at
x_{n+alpha_f} (FEBio's ``FESolidSolver2`` and ``FEElasticSolidDomain``).

FEBio's weights are those of the new state (``FESolidSolver2::Init``): with rhoi = rho_inf in
[0, 1] (the spectral radius at infinite step), alpha_f = 1 / (1 + rho), alpha_m = (2 - rho) /
(1 + rho), beta = (1 + alpha_m - alpha_f)^2 / 4, gamma = 1/2 + alpha_m - alpha_f; rhoi = -1
is the trapezoidal rule (all weights 1, beta = 1/4, gamma = 1/2) and any other rhoi (FEBio's
default -2) takes beta, gamma and alpha_f = alpha_m = alpha as given. Chung & Hulbert's
alpha's are 1 - these. The step solves

    M (alpha_m a_{n+1} + (1 - alpha_m) a_n) + f_int(y) = f(t_{n+1}),
    y = alpha_f x_{n+1} + (1 - alpha_f) x_n,

with Newmark's a_{n+1} = (x_{n+1} - x_pred) / (beta h^2), x_pred = x_n + h v_n + h^2 (1/2 -
beta) a_n (the elastic stresses at F_{n+alpha_f}, ``UpdateElementStress``; the loads at
t_{n+1}, ``FESolidSolver2::InitStep``). Solved for y instead of x_{n+1} (x_{n+1} = x_n +
(y - x_n) / alpha_f), the inertia is alpha_m / (beta h^2 alpha_f) M (y - y_pred) with
y_pred = x_n + alpha_f (x_pred - x_n - (1 - alpha_m) / alpha_m beta h^2 a_n), and the equation
is the stationarity condition of

    Phi(y) = 1 / (2 h_e^2) |y - y_pred|_M^2 + E(y) - f(t_{n+1}) . y,   h_e^2 = beta alpha_f
    h^2 / alpha_m,

Backward Euler's incremental potential in y (the same Phi's gradient is the residual of the
equation above, unscaled). Over x_{n+1} this is W(x_{n+alpha_f}) / alpha_f plus the quadratic
inertia: an incremental potential, exactly. The step is Backward Euler's minimisation
(``time/steps.py implicit_step``: contact, line search and all) in y with the step h_e and the
prediction y_pred; the prescribed values of y are those at t_n + alpha_f h (exact for values
linear over the step, FEBio's load curves between their points), and x_{n+1} gets them at
t_{n+1}. Rotations (rigid bodies) go through the system's retraction and difference as in
Newmark's step (``newmark.py``): y = x_n (+) alpha_f (x_{n+1} (-) x_n).

Rigid bodies: FEBio's connectors (springs, joints: ``FERigidSpring``, ``FERigidRevoluteJoint``
...) act at x_{n+alpha_f} too, with the bodies' points interpolated linearly, their inertia with
alpha_m (``FERigidSolverNew::InertialForces``). tissuesim's y interpolates a rotation on the
rotation manifold: the same for translations, O(h^2) apart for rotations (a joint held at y
leaves x_{n+1} that far off it; FEBio's linear interpolation holds x_{n+1} itself).

Contact acts at y too (FEBio's sliding interfaces at x_{n+1}); a rigid body's prescribed motion
under contact (pulled to its values by a spring) is refused with alpha_f < 1.

At alpha_f = 1/2 (rhoi = 1, the midpoint rule) FEBio corrects the Cauchy stress at each point
so that the step's internal work is the change of strain energy (``FEElasticSolidDomain::
UpdateElementStress``): s <- s + D ((W_{n+1} - W_n) / (h J) - s : D) / (D : D), with s and J
at F_{n+1/2}, D = sym((F_{n+1} - F_n) F_{n+1/2}^-1) / h. That force has no potential: it is
added as a dead load fixed during one minimisation and updated from its x_{n+1} until it no
longer changes (a fixed point, the solution FEBio's Newton reaches). Bodies whose elastic
energy is the plain point rule (``energies/elastic.py``) get it. A mean-dilatation body with a
patch per element gets FEBio's three-field element's (``three_field_midpoint.py``: the element
pressure at x_{n+1} and the correction with the points' energy); its fixed point is updated
with Anderson's mixing and, where it does not settle (the points' U(J) against the element's
pressure is as stiff as the bulk modulus: non-uniform J in an element), that step is the plain
midpoint rule, as before. Other bodies run the plain midpoint rule.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np

from tissuesim.energies.loads import ExternalForce
from tissuesim.errors import InputError, InvertedElementError
from tissuesim.time.integrators.three_field_midpoint import (
    EndPressure,
    end_pressure_correction,
    takes_end_pressure,
)
from tissuesim.time.state import State, StepOutcome

__all__ = [
    "generalized_alpha_step",
    "check_generalized_alpha",
    "febio_weights",
    "midpoint_correction",
]


def febio_weights(rho_inf: float) -> tuple[float, float, float, float]:
    """(alpha_f, alpha_m, beta, gamma) of FEBio's rhoi = rho_inf in [0, 1]
    (``FESolidSolver2::Init``; the weights of the new state)."""
    af = 1.0 / (1.0 + rho_inf)
    am = (2.0 - rho_inf) / (1.0 + rho_inf)
    return af, am, (1.0 + am - af) ** 2 / 4.0, 0.5 + am - af


def check_generalized_alpha(
    parameters: float | Sequence[float],
) -> tuple[float, float, float, float]:
    """(alpha_f, alpha_m, beta, gamma) from rho_inf (a number in [0, 1]) or from the four
    given in FEBio's weights (those of the new state), checked to lie where the method is
    unconditionally stable for linear systems (Chung & Hulbert: 1/2 <= alpha_f <= alpha_m,
    gamma >= 1/2 + alpha_m - alpha_f, beta >= gamma / 2)."""
    if isinstance(parameters, (int, float)) and not isinstance(parameters, bool):
        rho = float(parameters)
        if not 0.0 <= rho <= 1.0:
            raise InputError(
                f"generalized_alpha rho_inf = {rho:g}: the spectral radius at infinite step must "
                "lie in [0, 1] (1 keeps every frequency, 0 damps the highest in one step)"
            )
        return febio_weights(rho)
    try:
        af, am, beta, gamma = (float(v) for v in parameters)
    except (TypeError, ValueError):
        raise InputError(
            "generalized_alpha must be rho_inf (a number in [0, 1]) or (alpha_f, alpha_m, beta, "
            f"gamma), not {parameters!r:.60}"
        ) from None
    if not (0.5 <= af <= 1.0 and af <= am and gamma >= 0.5 + am - af - 1e-12
            and 2.0 * beta >= gamma - 1e-12):  # fmt: skip
        raise InputError(
            f"generalized_alpha (alpha_f, alpha_m, beta, gamma) = ({af:g}, {am:g}, {beta:g}, "
            f"{gamma:g}): tissuesim runs the unconditionally stable range 1/2 <= alpha_f <= 1, "
            "alpha_f <= alpha_m, gamma >= 1/2 + alpha_m - alpha_f, 2 beta >= gamma"
        )
    return af, am, beta, gamma


#: the midpoint correction's fixed point: updates at most, and its tolerance on the force
#: (relative to the body's force scale)
MIDPOINT_UPDATES, MIDPOINT_TOLERANCE = 8, 1e-10


def midpoint_correction(
    model, x0: np.ndarray, x1: np.ndarray, h: float, three_field: bool = True
) -> np.ndarray | None:
    """FEBio's energy-conserving correction of the midpoint rule (``FEElasticSolidDomain::
    UpdateElementStress`` with alpha_f = 1/2) as nodal forces (n_dofs,) of one FEM body, the
    gradient's share: sum_q w_q J (D c) F^-T : grad N; a three-field body's
    (``three_field_midpoint.end_pressure_correction``; None with ``three_field`` False); None
    where the body's elastic energy is neither."""
    from tissuesim.energies.elastic import ElasticEnergy

    elastic = getattr(model, "elastic", None)
    if takes_end_pressure(elastic):  # FEBio's three-field shell: three_field_midpoint.py
        return end_pressure_correction(elastic, x0, x1, h) if three_field else None
    if not isinstance(elastic, ElasticEnergy):
        return None
    K, material = model.kinematics, model.material
    F0, F1 = K.deformation_gradients(x0), K.deformation_gradients(x1)
    Fa = 0.5 * (F0 + F1)
    Fa_inv = np.linalg.inv(Fa)
    J = np.linalg.det(Fa)
    P = material.evaluate(Fa, 1).stress
    s = np.einsum("qij,qkj->qik", P, Fa) / J[:, None, None]  # Cauchy, J^-1 P F^T
    L = np.einsum("qij,qjk->qik", F1 - F0, Fa_inv) / h
    D = 0.5 * (L + np.swapaxes(L, 1, 2))
    DD = np.einsum("qij,qij->q", D, D)
    dW = material.evaluate(F1, 0).energy - material.evaluate(F0, 0).energy
    c = np.zeros_like(DD)
    on = DD > np.finfo(float).eps  # FEBio: only where D : D is above round-off
    c[on] = (dW[on] / (h * J[on]) - np.einsum("qij,qij->q", s[on], D[on])) / DD[on]
    dP = (J * c)[:, None, None] * np.einsum("qij,qkj->qik", D, Fa_inv)  # J (D c) F^-T
    local = K.stress_to_gradient(dP)
    return np.bincount(K.stencil.ravel(), weights=local.ravel(), minlength=model.n_dofs)


class _Intermediate:
    """The system as the step in y sees it: everything the system's, except that the
    prescribed values are those at t_n + alpha_f h (y's), whatever time is asked."""

    def __init__(self, system, t_alpha: float) -> None:
        object.__setattr__(self, "_system", system)
        object.__setattr__(self, "_t_alpha", t_alpha)

    def __getattr__(self, name: str):
        return getattr(self._system, name)

    def __setattr__(self, name: str, value) -> None:
        setattr(self._system, name, value)

    def apply_prescribed(self, c: np.ndarray, t: float) -> np.ndarray:
        return self._system.apply_prescribed(c, self._t_alpha)


def generalized_alpha_step(
    system,
    state: State,
    h: float,
    solver,
    options,
    *,
    alpha_f: float,
    alpha_m: float,
    beta: float,
    gamma: float,
    implicit_step,
    **kwargs,
) -> StepOutcome:
    """One generalised-alpha step of h s: Backward Euler's minimisation over the intermediate
    configuration y (inertia of h_e about y_pred), then x_{n+1}, Newmark's acceleration and
    velocity."""
    if alpha_f < 1.0 and any(
        r.soft is not None and any(f is not None for f in r.held.values())
        for r in getattr(system, "rigid", ())
    ):
        raise InputError(
            "generalized_alpha with alpha_f < 1 (rho_inf > 0) and a rigid body's prescribed "
            "motion under contact (pulled to its values by a spring, rigid/body.py): the spring "
            "would pull x_{n+alpha_f} to the step's end values; use rho_inf = 0 or 'newmark'"
        )
    a_n = np.zeros(system.n_dofs) if state.a is None else state.a
    t1 = state.time + h
    # tangent steps from x_n (rotations on the left, rigid/body.py): to x_pred, and to y_pred
    to_pred = h * state.v + h * h * (0.5 - beta) * a_n
    to_y_pred = alpha_f * (to_pred - (1.0 - alpha_m) / alpha_m * beta * h * h * a_n)
    h_e = h * math.sqrt(beta * alpha_f / alpha_m)
    carried = State(state.time, state.x, to_y_pred / h_e)
    intermediate = _Intermediate(system, state.time + alpha_f * h)
    energies = kwargs.pop("energies")
    solve_y = functools.partial(implicit_step, intermediate, carried, h_e, solver, options,
                                dynamic=True, t_end=t1, friction_h=h, **kwargs)  # fmt: skip
    swaps = _end_pressures(system, state.x, alpha_f)
    outcome, x1, settled = _solve(system, state, h, alpha_f, t1, solve_y, energies, swaps)
    if swaps is not None and settled is not True:
        # FEBio's three-field correction did not settle (its pointwise U(J) against the
        # element's pressure is as stiff as the bulk modulus): the plain midpoint rule there
        outcome, x1, settled = _solve(system, state, h, alpha_f, t1, solve_y, energies, None)
    if settled is None:
        return outcome
    x_pred = system.retract(state.x, to_pred)
    a1 = system.difference(x1, x_pred) / (beta * h * h)
    v1 = state.v + h * ((1.0 - gamma) * a_n + gamma * a1)
    outcome.state = State(t1, x1, v1, a1)
    return outcome


def _solve(system, state, h: float, alpha_f: float, t1: float, solve_y, energies, swaps):
    """The step in y with the midpoint correction updated to its fixed point: (outcome,
    x_{n+1}, settled: True, False (not within MIDPOINT_UPDATES or an inverted midpoint with
    three-field swaps) or None (failed: the outcome says why))."""
    corrections: list | None = None  # the midpoint correction's forces per body, or None
    three_field = swaps is not None
    x1, changes = None, []  # the largest change of the correction per update
    history = None  # Anderson's last (input, output) of the update
    for _ in range(MIDPOINT_UPDATES + 1):

        def step_energies(t, c_pred, h_step, corrections=corrections):
            out = energies(t, c_pred, h_step)
            if swaps is not None:
                out = [[*e, w] if w is not None else e for e, w in zip(out, swaps, strict=True)]
            if corrections is None:
                return out
            return [
                [*e, ExternalForce(-f)] if f is not None else e
                for e, f in zip(out, corrections, strict=True)
            ]

        outcome = solve_y(energies=step_energies)
        if not outcome.converged:
            return outcome, None, False if three_field else None
        y = outcome.state.x
        x1 = system.retract(state.x, system.difference(y, state.x) / alpha_f)
        x1 = system.apply_prescribed(x1, t1)
        if alpha_f != 0.5:
            return outcome, x1, True
        try:
            updated = _corrections(system, state.x, x1, h, three_field)
        except InvertedElementError:
            updated = [np.array([np.nan])]
        if updated is not None and not all(f is None or np.isfinite(f).all() for f in updated):
            # an element inverted at x_n, x_{n+1} or between: a smaller step
            failed = StepOutcome(None, False, outcome.newton, "the midpoint configuration inverts")
            return failed, None, False if three_field else None
        # settled: unchanged since the last solve (from none: nothing to correct, e.g. bodies
        # that move rigidly)
        if updated is None or _settled(system, corrections, updated):
            return outcome, x1, True
        change = _change(corrections, updated)
        if three_field and len(changes) >= 2 and change > 0.9 * changes[-1]:
            return outcome, x1, False  # not contracting: the fallback at once
        changes.append(change)
        if three_field:  # Anderson's mixing of depth 1 (the update is slow, 0.5 to 0.9)
            updated, history = _mixed(corrections, updated, history)
        corrections = updated
    return outcome, x1, False if three_field else True


def _end_pressures(system, x0: np.ndarray, alpha_f: float) -> list | None:
    """At alpha_f = 1/2, each three-field body's ``EndPressure`` energy (None for the others;
    None where no body has one)."""
    if alpha_f != 0.5:
        return None
    out = [
        EndPressure(body.elastic, x0[system.config_slices[j]], alpha_f)
        if takes_end_pressure(getattr(body, "elastic", None))
        else None
        for j, body in enumerate(system.bodies)
    ]
    return out if any(w is not None for w in out) else None


def _corrections(
    system, x0: np.ndarray, x1: np.ndarray, h: float, three_field: bool = True
) -> list | None:
    """The midpoint correction of every FEM body (None entries for the others; None where no
    body has one)."""
    out = []
    for j, body in enumerate(system.bodies):
        sc = system.config_slices[j]
        out.append(midpoint_correction(body, x0[sc], x1[sc], h, three_field))
    return out if any(f is not None for f in out) else None


def _mixed(inputs: list | None, outputs: list, history):
    """Anderson's mixing (depth 1) of the fixed point c = G(c) over the bodies' corrections:
    from the residuals r = G(c) - c of this update and the last, the next input G(c) - theta
    (G(c) - G(c_last)), theta minimising |r - theta (r - r_last)|; and the history."""
    c = [np.zeros_like(g) if g is not None and (inputs is None or inputs[j] is None) else
         (inputs[j] if g is not None else None) for j, g in enumerate(outputs)]  # fmt: skip
    if history is None:
        return outputs, (c, outputs)
    c_last, g_last = history
    keep = [j for j, g in enumerate(outputs) if g is not None and g_last[j] is not None]
    r = np.concatenate([outputs[j] - c[j] for j in keep])
    dr = r - np.concatenate([g_last[j] - c_last[j] for j in keep])
    denominator = float(dr @ dr)
    theta = float(r @ dr) / denominator if denominator > 0 else 0.0
    mixed = [g if g is None or g_last[j] is None else g - theta * (g - g_last[j])
             for j, g in enumerate(outputs)]  # fmt: skip
    return mixed, (c, outputs)


def _change(old: list | None, new: list) -> float:
    """The largest change of any body's correction from ``old`` (None: from zero)."""
    old = old if old is not None else [None if f is None else 0.0 for f in new]
    return max(float(np.abs(a - b).max(initial=0.0)) for a, b in zip(old, new, strict=True)
               if b is not None)  # fmt: skip


def _settled(system, old: list | None, new: list) -> bool:
    scale = MIDPOINT_TOLERANCE * system.force_scale
    old = old if old is not None else [None if f is None else 0.0 for f in new]
    return all(
        b is None or float(np.abs(a - b).max(initial=0.0)) <= scale
        for a, b in zip(old, new, strict=True)
    )
