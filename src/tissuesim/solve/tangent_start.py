"""A start for Newton when the prescribed motion alone inverts elements: the linear response
of the free DOFs to the step's prescribed increment (FEBio's first iteration).

A step's Newton starts with the prescribed DOFs already at their t_{n+1} values and the free
ones where they were. When a support moves farther in one step than a thin element next to it
is thick (a shell 0.01 thick on a face pushed by 0.02), that start holds an inverted element:
its energy is infinite and Newton cannot begin. FEBio does not meet this: its first iteration
takes the prescribed increment du_p as a load, K_ff du_f = R_f - K_fp du_p at the step's start,
so the free DOFs next to the support move with it. Here the same linear step gives a start:

    x = x0 + du,   K_ff du_f = -(g_f(x_s) + K_fp du_p),   du_p = 0,

with x_s the step's start (prescribed DOFs at their old values), g and K the gradient and
Hessian of the step's potential there, and du_p = x0_p - x_s_p. It is tried only when x0's
energy is infinite (an answer that converged before is unchanged), and kept only when its
energy is finite.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from tissuesim.solve.linear import NotPositiveDefiniteError

__all__ = ["tangent_start"]


def tangent_start(evaluate, x0: np.ndarray, xs: np.ndarray, elimination, solver, retract):
    """The linear start (module docstring) from the step's start ``xs`` towards ``x0`` (the
    prescribed DOFs at their new values): ``retract(x0, du)``, du zero at the prescribed DOFs.
    None when the configuration is not a vector of DOFs (frames' rotations), xs has no finite
    energy, its stiffness cannot be factorised, or the linear start holds an inverted element
    too. Returns (x, its accumulator evaluated with the gradient)."""
    if xs.shape != x0.shape:
        return None
    acc = evaluate(xs, 2, False)
    if not np.isfinite(acc.value) or acc.gradient.shape != x0.shape:
        return None
    dofs = np.asarray(elimination.dofs)
    d = np.zeros_like(x0)
    d[dofs] = x0[dofs] - xs[dofs]
    K = acc.pattern.matrix(acc.hessian)
    extra = None
    if acc.extra_hessian is not None:
        extra = sp.csr_matrix(acc.extra_hessian)
        K = K + extra
    rhs = -(acc.gradient + K @ d)
    hessian = acc.hessian.copy()
    elimination.apply(hessian, rhs)  # prescribed rows: zero right-hand side
    A = acc.pattern.matrix(hessian)
    if extra is not None:
        A = A + elimination.eliminate_matrix(extra)
    try:
        solver.factorize(A.tocsr())
        du = solver.solve(rhs)
    except (NotPositiveDefiniteError, RuntimeError, ArithmeticError, ValueError):
        return None
    if not np.all(np.isfinite(du)):
        return None
    du[dofs] = 0.0
    x = retract(x0, du)
    start = evaluate(x, 1, False)
    if not np.isfinite(start.value):
        return None
    return x, start
