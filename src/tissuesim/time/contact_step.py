"""An implicit step with contact in stages (``contact/predict/``): free motion, detection,
compliance, the contact problem, correction, certification; then either the barrier's Newton
from there (accurate) or nothing more (interactive).

    free motion:   the step without contact: interactive, one step on the kept factor's
                   matrix (``lagged_free_motion``: a gradient and a back-solve); accurate,
                   Newton to convergence
    predict:       pairs from x_n towards x_free, W = J K^-1 J^T, Signorini-Coulomb on W,
                   x = x_free + K^-1 J^T lambda          (contact/predict/predictor.py)
    gaps:          each pair held at the gap where the barrier's force equals its multiplier
                   (linearised per pair, GAP_PASSES passes), so the prediction lands on the
                   barrier's own equilibrium; the gaps linearised again at x (RELINEARIZE)
    interactive:   x, refined by lagged-matrix passes of the step with its contacts (REFINE),
                   its gaps at least MIN_GAP dhat, certified (``certify``), is the step;
                   forces = lambda; the barrier's weights learnt at x for the next step
    accurate:      x (gaps at least ACCURATE_MIN_GAP dhat), certified, is the start of the
                   barrier's Newton (time/steps.py): the barrier's answer and guarantee

A prediction that fails certification (after REDETECT detections more) or a free motion that
fails falls back to the barrier's Newton, within the step's budget; the step's report says so
(``record.extra["contact"]["prediction"]``, ``ContactModel.prediction_report``).
"""

from __future__ import annotations

import time

import numpy as np

from tissuesim.energies.loads import ExternalForce
from tissuesim.solve.newton import minimize
from tissuesim.time.attempts.start import choose_start
from tissuesim.time.state import State, StepOutcome

__all__ = ["resolve_mode", "free_motion", "interactive_step", "accurate_start"]

#: the gap (of dhat) an interactive step holds each pair at: inside the barrier's range, far
#: enough from zero that the linearised gaps' error (curvature, rotation over a step) does not
#: close it
INTERACTIVE_GAP = 0.5
#: the smallest gap (of dhat) an interactive step holds a pair at, however hard it presses:
#: room for the linearised gaps' error
MIN_GAP = 0.1
#: the same for an accurate step's start (Newton closes the rest): a start at the barrier's
#: own gap of a few micrometres crossed surfaces by the linearisation's error
ACCURATE_MIN_GAP = 0.05
#: detections with the gaps linearised at the last prediction (``rows.detect_rows``'s at)
RELINEARIZE = 1
#: detections again from the corrected positions when the prediction crosses a surface
REDETECT = 2
#: how far (of dhat) past a face's plane an end may lie and count as not through it
#: (``rows.sides_kept``): a point grazing the edge between two faces
SIDE_SLACK = 0.1
#: steps on the kept factor's matrix an interactive free motion takes at most, and the
#: factor by which one must shrink the gradient to end it (``lagged_free_motion``)
LAGGED_STEPS = 2
LAGGED_CONTRACTION = 0.5
#: Newton iterations of an interactive step's free motion, at most
FREE_ITERATIONS = 1
#: passes of the prediction on the nonlinear elasticity (``_refined``), at most, and when to
#: stop (the free point's move against the contact correction's largest)
REFINE = 3
REFINE_TOLERANCE = 1e-2
#: passes between the multipliers and the barrier's equilibrium gaps (``_barrier_gaps``)
GAP_PASSES = 2


def resolve_mode(contact, budget: dict | None) -> str:
    """ "accurate", "interactive" or "barrier" for this step ("auto": interactive with a
    budget, else the barrier: the accurate mode's start does not yet save more than it costs,
    docs/guide/contact.md)."""
    mode = contact.settings.mode
    if mode == "auto":
        return "interactive" if budget else "barrier"
    return mode


def free_motion(system, state: State, h, solver, options, dynamic, body_energies, t1, budget):
    """(x_free, Newton record): the step without contact, from the better of the prediction
    and x_n."""
    c_pred = system.retract(state.x, h * state.v) if dynamic else None

    def evaluate(c, order, project):
        return system.evaluate(c, order, project, body_energies, contact=False)

    candidates = (c_pred, state.x) if dynamic else (state.x,)
    c0 = choose_start(evaluate, candidates, lambda c: system.apply_prescribed(c, t1))
    return minimize(
        evaluate,
        c0,
        system.elimination,
        solver,
        options,
        force_scale=system.force_scale,
        length_scale=system.length_scale,
        retract=system.retract,
        budget=budget,
    )


def lagged_free_motion(system, state: State, h, solver, dynamic, body_energies, t1):
    """(x_free, record) by one step on the kept factor's matrix K from the prediction
    x_n + h v_n: x_free = x0 - K^-1 g(x0), a gradient and a back-solve (Newton's first
    iteration costs an assembly and a preconditioned CG on the current matrix); the
    refinement passes that follow are the same kind of step with the contacts in. A step
    that does not shrink the gradient by LAGGED_CONTRACTION is followed by another, at most
    LAGGED_STEPS in all; None when there is no kept factor yet or they do not (an organ
    swinging under gravity: the lagged step folded its surface)."""
    from tissuesim.solve.newton import NewtonResult
    from tissuesim.solve.reuse import ReusedFactorSolver

    if not isinstance(solver, ReusedFactorSolver) or not solver._factored:
        return None
    held = system.elimination.dofs

    def gradient(c):
        g = system.evaluate(c, 1, False, body_energies, contact=False).gradient.copy()
        g[held] = 0.0
        return g

    x = system.retract(state.x, h * state.v) if dynamic else state.x
    x = system.apply_prescribed(x, t1)
    g = gradient(x)
    record = NewtonResult(converged=True, reason="lagged matrix")
    record.gradient_norms.append(float(np.linalg.norm(g)))
    for _ in range(LAGGED_STEPS):
        x = system.retract(x, np.asarray(solver.direct.solve(-g)))
        g = gradient(x)
        record.iterations += 1
        record.gradient_norms.append(float(np.linalg.norm(g)))
        if record.gradient_norms[-1] <= LAGGED_CONTRACTION * record.gradient_norms[-2]:
            return x, record
    return None  # the kept matrix is too far from the step's: Newton's free motion


def _predictor(contact):
    from tissuesim.contact.predict.predictor import ContactPredictor

    if getattr(contact, "predictor", None) is None:
        contact.predictor = ContactPredictor()
    return contact.predictor


def interactive_step(
    system, state, h, solver, options, dynamic, body_energies, t1, y0, y1, budget
) -> StepOutcome | None:
    """The certified prediction as the step, or None (the caller falls back to the barrier's
    Newton; ``contact.prediction_report`` says why). The free motion is first one step on the
    kept factor's matrix; a prediction from it that fails certification is made again from
    Newton's free motion (FREE_ITERATIONS on the current matrix: an organ swinging under
    gravity folded its own surface in the lagged one) before the step falls back."""
    contact = system.contact
    predictor = _predictor(contact)
    report: dict = {"mode": "interactive"}
    contact.prediction_report = report
    predictor.clock.clear()
    predictor.columns = 0
    predictor.smoothing = 0.5 * contact.settings.eps_v * h
    clock = predictor.clock
    # the free motion under the last step's contact forces (held as dead loads): it ends
    # near where this step does, a short sweep and a small, more nearly linear correction
    carried = _carried(system, predictor, state.time)
    free_energies = body_energies
    if carried is not None:
        free_energies = [
            [*energies, ExternalForce(carried[where])]
            for energies, where in zip(body_energies, system.tangent_slices, strict=True)
        ]
    # tries: on the kept factor's matrix, with the carried forces, then without (a landing
    # step's forces change wholesale: carried, they can lead the prediction through a
    # surface), then Newton's free motion (an organ swinging under gravity folded its own
    # surface in the lagged one) likewise; each from the last step's multipliers
    tries = [(kind, carry) for kind in ("lagged", "newton") for carry in (carried, None)]
    tries = [(k, c) for k, c in tries if (c is None or carried is not None)]
    tries = [(k, c) for k, c in tries if not (k == "lagged" and predictor.refresh)]
    warm = predictor.warm_start
    for kind, carry in tries:
        predictor.warm_start = warm
        energies = free_energies if carry is not None else body_energies
        start = time.perf_counter()
        if kind == "lagged":
            free = lagged_free_motion(system, state, h, solver, dynamic, energies, t1)
            if free is None:
                clock["free_motion"] += time.perf_counter() - start
                continue
        else:
            free_budget = dict(budget or {})
            free_budget["iterations"] = min(
                free_budget.get("iterations", FREE_ITERATIONS), FREE_ITERATIONS
            )
            free = free_motion(
                system, state, h, solver, options, dynamic, energies, t1, free_budget
            )
            predictor.refresh = False
        x_free, record = free
        clock["free_motion"] += time.perf_counter() - start
        report.update(
            free_motion=kind, free_iterations=record.iterations, carried=carry is not None
        )
        if not (record.converged or record.budget_stop):
            report["outcome"] = f"fell back to the barrier: free motion failed ({record.reason})"
            predictor.carry(t1, None)
            return None
        prediction, x, certified = _predict_and_certify(
            system, predictor, solver, state, x_free, y0, y1, t1, body_energies, report, carry
        )
        if certified:
            break
    report.update(_figures(prediction), columns_solved=predictor.columns, certificate=certified)
    # how far the contact moved the bodies from the free motion (m): the sweep's excess
    report["correction_m"] = float(np.max(np.abs(system.difference(x, x_free)), initial=0.0))
    report.update({f"{k}_s": v for k, v in clock.items()})
    if not certified:
        report["outcome"] = "fell back to the barrier: the prediction crosses a surface"
        predictor.carry(t1, None)
        return None
    report["outcome"] = "certified"
    if prediction.rows.n_pairs:
        predictor.carry(t1, prediction.J.T @ prediction.force.reshape(-1))
    else:
        predictor.carry(t1, None)
    contact.predicted_forces = (x.copy(), prediction)
    if contact.moving:
        contact.obstacle_state = y1
    start = time.perf_counter()
    predictor.calibrate(contact, x, lambda d: barrier_pull(contact, d))
    clock["calibrate"] += time.perf_counter() - start
    # the reactions at prescribed DOFs: the elastic gradient at x less the contact forces
    start = time.perf_counter()
    g = system.evaluate(x, 1, False, body_energies, contact=False).gradient
    if prediction.rows.n_pairs:
        g = g - prediction.J_all.T @ prediction.force.reshape(-1)
    record.gradient = g
    clock["reactions"] += time.perf_counter() - start
    report.update({f"{k}_s": v for k, v in clock.items()})
    system.last_step_energies = body_energies
    v1 = system.difference(x, state.x) / h if dynamic else np.zeros(system.n_dofs)
    return StepOutcome(State(t1, x, v1), True, [record])


def _barrier_gaps(contact, predictor, system, prediction, floor: float):
    """The prediction with each pair at the barrier's own equilibrium: its gap for a force f
    is the barrier's, g(f) with w ``barrier_pull``(g) = f, linearised at the last pass's force
    (GAP_PASSES passes): g ~ a - c f, a compliance c of the pair's own in the contact problem,
    so that the load spreads over neighbouring pairs as the barrier spreads it (holding every
    pair at dhat / 2 pressed a probe 4-8 % harder than the barrier at 1e4 tetrahedra; rigid
    gaps from the forces oscillated between pairs that share a load). Pairs are then kept at
    least ``floor`` dhat apart. Returns (prediction, its gap targets (m,), compliances (m,))."""
    m = prediction.rows.n_pairs
    target, soft = np.full(m, INTERACTIVE_GAP * contact.dhat), np.zeros(m)
    if m == 0:
        return prediction, target, soft
    weights = prediction.rows.weights
    for _ in range(GAP_PASSES):
        force = prediction.force[:, 0]
        loaded = force[force > 0]
        reference = 0.1 * float(loaded.mean()) if loaded.size else 1e-9
        f = np.maximum(force, reference)
        g = equilibrium_gap(contact, weights, f)
        soft = (g - equilibrium_gap(contact, weights, 1.01 * f)) / (0.01 * f)
        target = g + soft * f
        prediction = predictor.solve_again(system, target, soft, correct=False)
    held = target - soft * prediction.force[:, 0]
    if floor > 0.0 and np.any(held < floor * contact.dhat):
        target, soft = np.maximum(held, floor * contact.dhat), np.zeros(m)
        prediction = predictor.solve_again(system, target, correct=False)
    return predictor.correct(system), target, soft


def _refined(system, predictor, prediction, body_energies, gap, soft=None):
    """The prediction after up to REFINE passes (``ContactPredictor.refine``): the correction
    is linear on the kept factor's matrix, the elasticity is not; each pass costs a gradient,
    a back-solve and the contact problem. Stops when the free point moves less than
    REFINE_TOLERANCE of the step's largest motion. Returns (prediction, passes)."""
    if prediction.rows.n_pairs == 0:
        return prediction, 0
    held = system.elimination.dofs

    def gradient(x):
        g = system.evaluate(x, 1, False, body_energies, contact=False).gradient.copy()
        g[held] = 0.0
        return g

    size = float(np.max(np.abs(system.difference(prediction.x, prediction.x_free)), initial=0.0))
    passes = 0
    for passes in range(1, REFINE + 1):  # noqa: B007 (returned)
        prediction, moved = predictor.refine(system, gradient, gap, soft)
        if moved <= REFINE_TOLERANCE * max(size, 1e-300):
            break
    else:  # the kept factor's matrix is too far from the step's: Newton's next step
        predictor.refresh = True
        predictor.own_factor["stale"] = True
    return prediction, passes


def _carried(system, predictor, t: float) -> np.ndarray | None:
    """The last step's contact forces for this step's free motion (``ContactPredictor.carry``),
    where every body's configuration is its DOFs (FEM: a dead load on positions), else None."""
    force = predictor.carried_force(t)
    # not after a step whose refinement ran out: its forces are a poor linearisation's
    if force is None or len(force) != system.n_dofs or predictor.refresh:
        return None
    same = all(
        (c.stop - c.start) == (d.stop - d.start)
        for c, d in zip(system.config_slices, system.tangent_slices, strict=True)
    )
    return force if same else None


def _predict_and_certify(
    system, predictor, solver, state, x_free, y0, y1, t1, body_energies, report, carried=None
):
    """(prediction, its configuration with prescribed values, the certificate or "") for the
    free motion x_free: detect, gaps linearised again at the first prediction, the barrier's
    gaps, the refinement passes, certification; the detection again from the corrected
    positions (REDETECT times) when it fails."""
    contact, clock = system.contact, predictor.clock
    gap = INTERACTIVE_GAP * contact.dhat
    also = None
    for redetections in range(1 + REDETECT):  # noqa: B007 (reported)
        prediction = predictor.predict(
            system, solver, state.x, x_free, y0, y1, gap, also, body_energies, carried=carried
        )
        for _ in range(RELINEARIZE):  # the gaps linearised again where the step ends
            at = prediction.x  # (corrected by _barrier_gaps: one back-solve less)
            prediction = predictor.predict(
                system, solver, state.x, x_free, y0, y1, gap, also, body_energies, at, False,
                carried,
            )  # fmt: skip
        prediction, target, soft = _barrier_gaps(contact, predictor, system, prediction, MIN_GAP)
        prediction, refinements = _refined(
            system, predictor, prediction, body_energies, target, soft
        )
        x = system.apply_prescribed(prediction.x, t1)
        start = time.perf_counter()
        certified = certify(contact, state.x, x, y0, y1)
        clock["certify"] += time.perf_counter() - start
        report.update(redetections=redetections, refinements=refinements)
        if certified:
            break
        also = x  # pairs the correction made: detect them too
    return prediction, x, certified


def certify(contact, x0: np.ndarray, x: np.ndarray, y0, y1) -> str:
    """How the bodies get from x0 to x, the obstacles from y0 to y1, without crossing a
    surface ("" if not shown): along one straight move, or in two legs, the bodies first with
    the obstacles where they were, then the obstacles (the proof ``time/steps.py`` accepts for
    a Newton start; a stroke's straight move can cross where the legs do not: the surface under a
    sliding probe moves along a line that cuts the probe's arc). Each move is free when
    additive CCD (conservative: it never reports a later contact than the true one) finds no
    contact in it, or else when tight-inclusion CCD proves it free (with its iterations
    bounded, undecided counts as not free: between surfaces sliding 50 um apart it was
    undecided where additive CCD found the move free). Else (3D): the end free of intersection
    (ipctk's exact test) and every pair of the sweep on the side it started on
    (``rows.sides_kept``), which rules out a surface tunnelled through."""

    def free(a, b, ya, yb) -> bool:
        return contact.max_step(a, b, ya, yb) >= 1.0 or contact.start_free(a, b, ya, yb)

    # one broad phase for the straight move's CCD, the sides test and the calibration's
    # collisions at x (``contact/barrier/candidates.py``)
    V0, V1 = contact.vertices(x0, obstacle=y0), contact.vertices(x, obstacle=y1)
    if contact.candidates.margin is not None:
        contact.candidates.hold_sweep(V0, V1)
    if free(x0, x, y0, y1):
        return "straight move"
    if y0 is not None and y1 is not None and free(x0, x, y0, y0) and free(x, x, y0, y1):
        return "two legs"
    # a large step near a curved surface: the straight move of a point pushed round a probe
    # is a chord through it, whatever the real motion; then the end must be free of
    # intersection (exact) with every surface on the side it started on (3D)
    if contact.dim == 3:
        from tissuesim.contact.predict.rows import sides_kept

        slack = SIDE_SLACK * contact.dhat
        if not contact._ipctk.has_intersections(contact.mesh, V1) and sides_kept(
            contact, V0, V1, slack
        ):
            return "end state and sides"
    return ""


def accurate_start(
    system, state, h, solver, options, dynamic, body_energies, t1, y0, y1
) -> tuple[np.ndarray | None, float | None]:
    """(a start for the barrier's Newton: the prediction with each pair at the barrier's
    equilibrium gap for its multiplier, None if the free motion fails; the gradient norm at
    the free motion's start, which Newton's relative tolerance is taken of: the start's own
    would hold a good start to a tighter tolerance the better it is)."""
    contact = system.contact
    predictor = _predictor(contact)
    start = time.perf_counter()
    # the free motion as the interactive mode's (the refinement passes below take the
    # elasticity's nonlinearity; Newton on the barrier then corrects what is left)
    free = (
        None
        if predictor.refresh
        else lagged_free_motion(system, state, h, solver, dynamic, body_energies, t1)
    )
    kind = "lagged"
    if free is None:
        kind = "newton"
        free = free_motion(
            system, state, h, solver, options, dynamic, body_energies, t1,
            {"iterations": FREE_ITERATIONS},
        )  # fmt: skip
        predictor.refresh = False
    x_free, record = free
    report = {
        "mode": "accurate",
        "free_motion": kind,
        "free_motion_s": time.perf_counter() - start,
        "free_iterations": record.iterations,
    }
    contact.prediction_report = report
    if not (record.converged or record.budget_stop):
        report["outcome"] = f"no prediction: free motion failed ({record.reason})"
        return None, None
    predictor.clock.clear()
    predictor.columns = 0
    predictor.smoothing = 0.5 * contact.settings.eps_v * h
    target = INTERACTIVE_GAP * contact.dhat
    prediction = predictor.predict(
        system, solver, state.x, x_free, y0, y1, target, energies=body_energies
    )
    for _ in range(RELINEARIZE):  # the gaps linearised again where the step ends
        prediction = predictor.predict(
            system, solver, state.x, x_free, y0, y1, target, None, body_energies,
            prediction.x, False,
        )  # fmt: skip
    prediction, gap, soft = _barrier_gaps(contact, predictor, system, prediction, ACCURATE_MIN_GAP)
    prediction, _ = _refined(system, predictor, prediction, body_energies, gap, soft)
    report.update(
        _figures(prediction),
        columns_solved=predictor.columns,
        **{f"{k}_s": v for k, v in predictor.clock.items()},
    )
    report["outcome"] = "start"
    return system.apply_prescribed(prediction.x, t1), record.gradient_norms[0]


def barrier_pull(contact, d: np.ndarray) -> np.ndarray:
    """The barrier's force per unit weight at distance d (N / m^2: weights are areas), ipctk's
    physical barrier (contact/model.py): kappa 2 d |b'(d^2)| / dhat^3 with
    b(s) = -(s - dhat^2)^2 ln(s / dhat^2), for 0 < d < dhat."""
    dhat = contact.dhat
    s_hat, s = dhat * dhat, d * d
    db = -2.0 * (s - s_hat) * np.log(s / s_hat) - (s - s_hat) ** 2 / s
    return contact.kappa * 2.0 * d * np.abs(db) / dhat**3


def equilibrium_gap(contact, weights: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Per pair, the distance d in (0, dhat) at which the barrier's force w ``barrier_pull(d)``
    equals ``force`` (N); dhat where the force is zero. By bisection on log d (the pull falls
    monotonically from infinity to 0)."""
    dhat = contact.dhat
    weights = np.maximum(weights, 1e-300)

    def pull(d):
        return weights * barrier_pull(contact, d)

    lo = np.full(len(force), 1e-9 * dhat)
    hi = np.full(len(force), dhat)
    for _ in range(32):  # log(dhat / lo) / 2^32: 5e-9 of d
        mid = np.sqrt(lo * hi)
        above = pull(mid) > force
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    return np.where(force > 0.0, np.sqrt(lo * hi), dhat)


def _figures(prediction) -> dict:
    return {
        "pairs": prediction.rows.n_pairs,
        "sweeps": prediction.sweeps,
        "contact_solve_converged": prediction.converged,
    }
