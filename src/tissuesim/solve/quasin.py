"""FEBio's nonlinear solver, ``FESolidSolver2::Quasin``, as an option of a step's solve
(``NewtonOptions(method="febio")``): a FEBio model run to FEBio's own stopping point.

tissuesim's Newton (``solve/newton.py``) converges each step tightly; FEBio stops a step as
soon as its norms say so, and in undamped vibration (FEBio's ms01, ms02, dy02) the steps'
leftovers add up to 1e-3 of the solution (benchmarks/febio_quasin.py). This module runs FEBio's
loop on tissuesim's own residual R = -gradient of Phi and stiffness K = its Hessian:

    start: K reformed and factored (each step, ``reform_each_time_step``), R_0 = R(x_n) with
        the prescribed DOFs not moved yet plus FEBio's m_Fd = -K_fp du_p (``prescribed_from``)
    loop:  u = (BFGS-updated K)^-1 R_0 (``BFGSSolver::SolveEquations``; Broyden's or the plain
        factor's for the other qn_methods), line search s (``FELineSearch``, Bonet & Wood),
        x += s u, R_1 = R(x);
        converged when |s u|^2 <= dtol^2 |U|^2 (U the step's increment), |s u . R_1| <=
        etol |u_0 . R_0|, |R_1|^2 <= rtol |R_0|^2 (rtol > 0), s >= lsmin and (diverge_reform)
        the energy norm not above its largest; or |R_1|^2 < min_residual;
        else reform when s < lsmin or the energy norm grows, or a BFGS update (at most
        max_ups - 1 between reformations, none past condition number cmax); at most max_refs
        reformations a step (the step fails past them, as in FEBio).
    at a converged point ``relag`` (FEBio's augmentations: contact, joints): if it changed
        something, R_0 = R(x) and the loop goes on with the same updates and norms.

``iterations`` counts FEBio's equilibrium iterations. With ``reform_each_time_step`` false the
factor, the updates and m_Fd are kept from the last step (``_MEMORY``, per linear solver), as
FEBio keeps them. Linear solves are direct (the simulation's direct solver, a private
instance; SuperLU where the matrix is not positive definite): FEBio's factor is exact.
"""

from __future__ import annotations

import logging
import weakref
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tissuesim.errors import InputError
from tissuesim.solve.febio_settings import FebioSettings
from tissuesim.solve.linear import (
    CholmodSolver,
    LinearSolver,
    NotPositiveDefiniteError,
    PardisoSolver,
    SuperLUSolver,
    has_cholmod,
    has_pardiso,
)
from tissuesim.solve.newton import NewtonResult, _budget_spent

_LOG = logging.getLogger(__name__)

__all__ = ["FebioSettings", "minimize_febio", "follow_pressures"]


@dataclass(eq=False)
class _Memory:
    """What FEBio keeps between steps: the factor, the quasi-Newton updates, m_Fd."""

    solve: object = None  # b -> K_ff^-1 b of the last reformation
    n_free: int = -1
    updates: list = field(default_factory=list)  # BFGS (v, w) or Broyden (r, d, rho)
    nups: int = 0
    fd: np.ndarray | None = None
    q: np.ndarray | None = None  # Broyden's last q
    new_step: bool = True


#: FEBio's memory between steps, per linear solver of a simulation (one run)
_MEMORY: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def follow_pressures(pressures) -> None:
    """Lagged follower pressures (energies/pressure_lag.py's ``PressureLags``, or None) made
    FEBio's: the load at x in every residual and its symmetrised stiffness there (FEBio's
    ``symmetric_stiffness``), instead of a dead load re-lagged to a fixed point (which would
    take the step past FEBio's stopping point). Returns None: nothing is left to re-lag."""
    for _, energy in getattr(pressures, "items", ()):
        energy.lag, energy._frozen, energy.stiffness = None, None, True


class _Failed(Exception):
    """The step fails as FEBio's does (the caller halves or cuts back)."""


def _direct_factor(solver: LinearSolver, A: sp.csr_matrix):
    """b -> A^-1 b with a private direct solver, as FEBio factors its stiffness: the
    simulation's own where it is direct, else PARDISO or CHOLMOD where installed (the "auto"
    choice of an iterative solver for a large model, mi39's 73k DOFs, would otherwise fall
    to SuperLU: 67 s a factorisation against PARDISO's seconds); where the Cholesky refuses
    an indefinite matrix, PARDISO's LU (FEBio's PARDISO factors it), then SuperLU."""
    direct = getattr(solver, "direct", solver)
    if A.shape[0] == 0:
        return lambda b: b.copy()
    if not np.all(np.isfinite(A.data)):  # an inverted element's stiffness: the step fails
        raise _Failed("febio: the stiffness matrix is not finite (an inverted element?)")
    kinds = (PardisoSolver, CholmodSolver, SuperLUSolver)
    if isinstance(direct, kinds):
        kind = type(direct)
    else:
        kind = PardisoSolver if has_pardiso() else CholmodSolver if has_cholmod() else None
    if kind is not None and kind is not SuperLUSolver:
        own = kind()
        try:
            own.factorize(A)
            return own.solve
        except (NotPositiveDefiniteError, RuntimeError):  # PARDISO's analysis may refuse it
            pass
    if kind is not SuperLUSolver and has_pardiso():
        try:
            return _PardisoLU(A)
        except Exception:  # noqa: BLE001 - pypardiso's own errors: SuperLU decides
            pass
    try:
        return spla.splu(A.tocsc()).solve
    except RuntimeError as exc:
        raise _Failed(f"the stiffness matrix is singular ({exc})") from None


class _PardisoLU:
    """b -> A^-1 b by PARDISO's LU (real unsymmetric, mtype 11): an indefinite stiffness,
    without SuperLU's fill. PARDISO's memory is released with the object (pypardiso keeps it
    until told: a factor per reformation filled 17 GB, sh29 and oi01 were killed)."""

    def __init__(self, A: sp.csr_matrix) -> None:
        import pypardiso

        self._A = sp.csr_matrix(A)
        self._A.sort_indices()
        lu = pypardiso.PyPardisoSolver(mtype=11)
        self._release = weakref.finalize(self, lu.free_memory, True)
        lu.factorize(self._A)
        self._lu = lu

    def __call__(self, b: np.ndarray) -> np.ndarray:
        return self._lu.solve(self._A, np.asarray(b, dtype=float))


def minimize_febio(
    evaluate,
    x0: np.ndarray,
    elimination,
    solver: LinearSolver,
    options,
    *,
    force_scale: float = 1.0,
    length_scale: float = 1.0,
    retract=None,
    max_step=None,
    path_free=None,
    relag=None,
    max_relags: int = 0,
    budget: dict | None = None,
    start=None,
    prescribed_from: np.ndarray | None = None,
    difference=None,
    **_ignored,
) -> tuple[np.ndarray, NewtonResult]:
    """FEBio's Quasin from x0 (prescribed DOFs at their t_{n+1} values), with ``minimize``'s
    arguments and record (module docstring); ``options.febio`` its settings.

    prescribed_from: the step's start (prescribed DOFs at their old values): FEBio's first
    stiffness and residual are taken there, the prescribed increment entering as m_Fd;
    ``difference(c1, c0)``: the tangent step between two configurations (rigid bodies'
    prescribed rotations enter m_Fd through it).
    Tolerances of ``minimize`` (gradient, force and step) and its contact arguments other
    than ``relag`` are not used; the barrier's CCD (``max_step``, ``path_free``) is refused."""
    if max_step is not None or path_free is not None:
        raise InputError(
            "newton method 'febio' does not run with the barrier contact's CCD: use 'newton'"
        )
    s_: FebioSettings = options.febio or FebioSettings()
    result = NewtonResult()
    retract = retract or (lambda x, dx: x + dx)
    memory = _MEMORY.setdefault(solver, _Memory())
    try:
        x, acc = _quasin(evaluate, x0, elimination, solver, s_, retract, relag, max_relags,
                         budget, start, prescribed_from, memory, result, difference)  # fmt: skip
    except _Failed as exc:
        _MEMORY[solver] = _Memory()  # FEBio's Rewind: reform at the retried step's start
        result.converged, result.reason = False, str(exc)
        return x0.copy(), result
    result.energy_terms = dict(acc.terms)
    result.gradient = acc.gradient
    return x, result


def _quasin(evaluate, x0, elimination, solver, s_, retract, relag, max_relags, budget, start,
            prescribed_from, memory, result, difference=None):  # fmt: skip
    x = x0.copy()
    dofs = np.asarray(elimination.dofs)
    shifted = (
        prescribed_from is not None
        and prescribed_from.shape == x0.shape
        and (dofs.size == 0 or int(dofs.max()) < x0.size)
        and bool(np.any(prescribed_from[dofs] != x0[dofs]))
    )
    xs = x0.copy()  # the step's start: the prescribed DOFs where they were
    du_p = None
    if shifted and difference is not None:
        increment = difference(x0, prescribed_from)
        if increment.size != x0.size:
            # rigid or frame DOFs (rotations): the prescribed increment in the tangent space.
            # As FEBio, the first stiffness and residual are the step's start (nothing
            # prescribed moved: the last step's leftovers under the new loads) and the
            # increment enters as m_Fd = -K_fp du_p; where no deformable DOF is coupled to a
            # prescribed rigid body yet (co37's first step: its contact not closed) that first
            # iteration is nothing, the Update puts the body in place and FEBio reforms as
            # diverging (its log's two reformations)
            xs, du_p = prescribed_from, increment
    if shifted and du_p is None:
        xs[dofs] = prescribed_from[dofs]
    maxups = s_.max_updates
    nref = 0

    def stiffness(acc) -> sp.csr_matrix:
        K = acc.pattern.matrix(acc.hessian)
        if acc.extra_hessian is not None:
            K = K + sp.csr_matrix(acc.extra_hessian)
        return K.tocsr()

    def reform(acc, fd_from=None) -> None:
        nonlocal nref
        if nref >= s_.max_refs:
            raise _Failed(f"febio: {s_.max_refs} stiffness reformations (max_refs) in the step")
        K = stiffness(acc)
        Kff = K[free][:, free]
        memory.solve = _direct_factor(solver, Kff.tocsr())
        memory.n_free = nf
        memory.updates, memory.nups = [], 0
        memory.fd = np.zeros(nf)
        if fd_from is not None:  # m_Fd = -K_fp du_p (FESolidLinearSystem at the step's start)
            memory.fd = -(K[free][:, ~free] @ fd_from[~free])
        nref += 1

    def residual(acc) -> np.ndarray:
        # an inverted element: FEBio's negative jacobian fails the step (retried smaller)
        if not np.isfinite(acc.value):
            raise _Failed("febio: an inverted element (negative jacobian) in the iterate")
        R = -acc.gradient[free]
        if not np.all(np.isfinite(R)):
            raise _Failed("febio: NaN in the residual (an inverted element?)")
        return R

    # QNInit: the stiffness (reformed each step, or after a failure) and the first residual,
    # at the step's start with the prescribed DOFs where they were
    breform = s_.reform_each_time_step or maxups == 0 or memory.solve is None
    start_acc = evaluate(xs, 2, False) if breform or start is None or shifted else start
    n = start_acc.gradient.size
    if shifted and n != x0.size and du_p is None:  # rigid DOFs, no difference: from x0
        shifted, xs = False, x0
        start_acc = evaluate(x0, 2, False)
    free = np.ones(n, dtype=bool)
    free[dofs] = False
    nf = int(free.sum())
    if memory.n_free != nf:
        breform = True
        if start_acc.order < 2:
            start_acc = evaluate(xs, 2, False)
    memory.new_step = True
    if breform:
        reform(start_acc, (du_p if du_p is not None else x0 - xs) if shifted else None)
    R0 = residual(start_acc) + memory.fd
    acc = start_acc  # the accumulator at x (x0's gradient once the prescribed move)
    result.gradient_norms.append(float(np.linalg.norm(R0)))
    result.energies.append(start_acc.value)
    U = np.zeros(nf)
    niter = 0
    normEi = normEm = normRi = 0.0
    ui_full = np.zeros(n)

    def at(step: float, ui):
        ui_full[free] = step * ui
        y = retract(x, ui_full)
        a = evaluate(y, 1, False)
        return y, a, residual(a)

    while True:
        ui = _solve_qn(s_, memory, R0)
        step, y, acc1, R1 = _line_search(s_, ui, R0, at)
        if niter == 0:
            normRi, normEi = float(R0 @ R0), abs(float(ui @ R0))
            normEm = normEi
        du = step * ui
        x, acc = y, acc1
        U += du
        normR1, normu, normU, normE1 = float(R1 @ R1), float(du @ du), float(U @ U), abs(du @ R1)
        niter += 1
        result.iterations = niter
        result.step_lengths.append(step)
        result.step_norms.append(float(np.max(np.abs(du), initial=0.0)))
        result.gradient_norms.append(float(np.sqrt(normR1)))
        result.energies.append(acc.value)
        result.projected.append(False)
        result.contact_projected.append(False)
        if _LOG.isEnabledFor(logging.DEBUG):  # FEBio's log of the iteration's norms
            _LOG.debug("iteration %d: s %.3g, R %.3e, u %.3e, U %.3e, E %.3e (Ei %.3e, Em %.3e)",
                       niter, step, normR1, normu, normU, normE1, normEi, normEm)  # fmt: skip
        conv = not (
            (s_.rtol > 0 and normR1 > s_.rtol * normRi)
            or (s_.dtol > 0 and normu > s_.dtol**2 * normU)
            or (s_.etol > 0 and normE1 > s_.etol * normEi)
            or (s_.lstol > 0 and step < s_.lsmin)
            or (s_.diverge_reform and normE1 > normEm)
        )
        if not conv and normR1 < s_.min_residual:
            conv = True  # FEBio: "no force acting on the system"
        if not conv and s_.max_residual > 0 and normR1 >= s_.max_residual:
            raise _Failed(f"febio: the residual passed max_residual ({s_.max_residual:g})")
        if conv:
            if relag is None or result.relags >= max_relags:
                break
            result.relags += 1
            if not relag(x):  # the augmentations have converged too
                break
            nref = 0  # FEBio's DoAugmentations: a new residual, the same updates and norms
            acc = evaluate(x, 2 if maxups == 0 or s_.reform_augment else 1, False)
            if maxups == 0 or s_.reform_augment:
                reform(acc)
            R0 = residual(acc)
            result.gradient_norms[-1] = float(np.linalg.norm(acc.gradient[free]))
            result.energies[-1] = acc.value
            memory.new_step = True
        else:
            force_reform = s_.lstol > 0 and step < s_.lsmin
            if not force_reform and s_.diverge_reform and normE1 > normEm:
                normEm = normEi = normE1  # diverging: reform
                normRi = normR1
                force_reform = True
            if force_reform or not _update(s_, memory, step, ui, R0, R1):
                reform(evaluate(x, 2, False))
            R0 = R1
        if _budget_spent(budget, niter):
            result.budget_stop = True
            result.reason = "stopped by the step's budget before converging"
            return x, acc
    result.converged, result.reason = True, "febio norms"
    return x, acc


def _solve_qn(s_: FebioSettings, memory: _Memory, R: np.ndarray) -> np.ndarray:
    """The search direction: BFGSSolver's / FEBroydenStrategy's SolveEquations."""
    if s_.qn_method == "Broyden" and memory.nups > 0:
        updates = memory.updates
        if memory.new_step:  # FEBio's m_bnewStep: q from the factor and all but the last
            q = memory.solve(R)
            for r, d, rho in updates[:-1]:
                q = q + (rho * (d @ q)) * (d - r)
            memory.q = q
        memory.new_step = False
        r, d, rho = updates[-1]
        q = memory.q
        return q + (rho * (d @ q)) * (d - r)
    memory.new_step = False
    if s_.qn_method == "Broyden" or not memory.updates:
        return memory.solve(R)
    tmp = R.copy()
    for v, w in reversed(memory.updates):
        tmp += v * (w @ tmp)
    ui = memory.solve(tmp)
    for v, w in memory.updates:
        ui += w * (v @ ui)
    return ui


def _update(s_: FebioSettings, memory: _Memory, step, ui, R0, R1) -> bool:
    """A quasi-Newton update (``BFGSSolver::Update``, ``FEBroydenStrategy::Update``); False:
    reform instead (max_ups reached, full Newton, or BFGS's condition number above cmax)."""
    maxups = s_.max_updates
    if maxups == 0 or memory.nups >= maxups - 1:
        return False
    if s_.qn_method == "Broyden":
        q = memory.solve(R1)
        for r, d, rho in memory.updates:
            q = q + (rho * (d @ q)) * (d - r)
        r, d = q - ui, -step * ui
        memory.updates.append((r, d, 1.0 / float(d @ r)))
        memory.q = q
    else:
        D, G, H = step * ui, R0 - R1, R0 * step
        dg, dh = float(D @ G), float(D @ H)
        c = np.sqrt(abs(dg / dh))
        if not c <= s_.cmax:
            return False
        memory.updates.append((-H * c - G, D / dg))
    memory.nups += 1
    return True


def _line_search(s_: FebioSettings, ui, R0, at):
    """``FELineSearch::DoLineSearch`` from s = 1: (s, the point, its accumulator, R)."""
    if s_.lstol <= 0.0:
        return (1.0, *at(1.0, ui))
    step, r0 = 1.0, float(ui @ R0)
    smin, rmin, n = step, abs(r0), 0
    tried = {}
    while True:
        tried[step] = y, a, R1 = at(step, ui)
        if step < s_.lsmin:  # NIKE3D's rule, as FEBio: s = 0.5 and hope for the best
            return (0.5, *at(0.5, ui))
        r1 = float(ui @ R1)
        if n == 0 or abs(r1) < rmin:
            smin, rmin = step, abs(r1)
        r = 0.0 if abs(r1) < 1e-17 else abs(r1 / r0)
        if r <= s_.lstol:
            return step, y, a, R1
        a_ = r0 / r1
        A, B = 1.0 + a_ * (step - 1.0), a_ * step * step
        D = B * B - 4.0 * A * B
        if D >= 0:
            step = (B + np.sqrt(D)) / (2.0 * A)
            if step < 0:
                step = (B - np.sqrt(D)) / (2.0 * A)
            if step < 0:
                step = 0.0
        else:
            step = 0.5 * B / A
        n += 1
        if n >= s_.lsiter:
            return (smin, *tried[smin])
