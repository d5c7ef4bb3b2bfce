"""Moving obstacles inside the Newton solve, as IPC does for kinematic objects.

An obstacle held at its prescribed place for the whole solve would start each step inside the
barrier (or through the surface) as soon as it moves further per step than the barrier gap;
the step would then have to be halved until it does not (16 substeps per step were measured).
Instead the obstacles' vertex coordinates y become unknowns next to the system's, starting
where they are, and are pulled to their targets y1 (their places at t_{n+1}) by an augmented
Lagrangian

    Phi_aug(x, y) = Phi(x) + B(x, y) + kappa_p / 2 |y - y1|^2 - lambda . (y - y1),

so one Newton solve moves the obstacles and pushes the bodies out of their way together, every
line search limited by CCD over both. After each solve lambda <- lambda - kappa_p (y - y1); the
solves repeat (at most MAX_UPDATES) until every obstacle vertex is within TOLERANCE x dhat of
its target. kappa_p is chosen large against the bodies' stiffness (PENALTY x force scale /
length scale per vertex), so the first solve already lands close.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.constraints.dirichlet import Elimination
from tissuesim.energies.accumulator import Accumulator
from tissuesim.solve.newton import minimize

__all__ = ["solve_with_moving_obstacles", "MAX_UPDATES", "TOLERANCE"]

MAX_UPDATES = 6
TOLERANCE = 0.01  # of dhat: how close every obstacle vertex must end to its target
PENALTY = 1e4


def _structure(system, contact) -> tuple[SparsityPattern, Elimination]:
    """The augmented pattern (the system's, then a diagonal for the obstacles' coordinates)
    and its elimination, built once per system and prescribed set (kept on the contact
    model), not every step."""
    key = (id(system.pattern), id(system.elimination))
    cached = contact.augmented_cache.get("structure")
    if cached is not None and cached[0] == key:
        return cached[1]
    n, k = system.n_dofs, contact.n_obstacle
    base = system.pattern
    keys = base.keys()
    rows = np.concatenate([keys // n, n + np.arange(k)])
    cols = np.concatenate([keys % n, n + np.arange(k)])
    pattern = SparsityPattern.from_entries(n + k, rows, cols)
    # rows of the system come first with the same columns: its data is a prefix
    assert np.array_equal(pattern.indices[: base.nnz], base.indices)
    structure = (pattern, Elimination.build(pattern, system.elimination.dofs))
    contact.augmented_cache["structure"] = (key, structure)
    return structure


class _Augmented:
    """The system with the obstacles' coordinates appended: pattern, elimination, energy."""

    def __init__(self, system, contact, energies) -> None:
        self.system, self.contact, self.energies = system, contact, energies
        self.n_config = system.n_config
        self.pattern, self.elimination = _structure(system, contact)
        self.penalty = PENALTY * system.force_scale / system.length_scale
        self.target = np.zeros(contact.n_obstacle)
        self.multiplier = np.zeros(contact.n_obstacle)

    def split(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return z[: self.n_config], z[self.n_config :]

    def evaluate(self, z: np.ndarray, order: int, project: bool) -> Accumulator:
        c, y = self.split(z)
        part = self.system.evaluate(c, order, project, self.energies, contact=False)
        acc = Accumulator(self.pattern, order, project)
        for term, value in part.terms.items():
            acc.add_value(term, value)
        r = y - self.target
        acc.add_value("obstacle_penalty", 0.5 * self.penalty * float(r @ r))
        acc.add_value("obstacle_multiplier", -float(self.multiplier @ r))
        value, grad, hess = self.contact.evaluate_augmented(c, y, order, bool(project))
        acc.add_value("contact", value)
        n = self.system.n_dofs
        if order >= 1:
            acc.gradient[:n] = part.gradient
            acc.gradient[n:] = self.penalty * r - self.multiplier
            if grad is not None:
                acc.gradient += grad
        if order >= 2:
            acc.hessian[: part.hessian.size] = part.hessian
            acc.hessian[self.pattern.diagonal[n:]] += self.penalty
            acc.extra_hessian = hess
        return acc

    def retract(self, z: np.ndarray, dz: np.ndarray) -> np.ndarray:
        n = self.system.n_dofs
        c, y = self.split(z)
        return np.concatenate([self.system.retract(c, dz[:n]), y + dz[n:]])

    def max_step(self, z0: np.ndarray, z1: np.ndarray) -> float:
        c0, y0 = self.split(z0)
        c1, y1 = self.split(z1)
        return self.contact.max_step(c0, c1, y0, y1)

    def path_free(self, z0: np.ndarray, z1: np.ndarray) -> bool:
        c0, y0 = self.split(z0)
        c1, y1 = self.split(z1)
        return self.contact.path_free(c0, c1, y0, y1)


def _solver_for(problem: _Augmented, contact, solver, options):
    """A linear solver for the augmented size (kept on the contact model across steps): the
    system's AMG solver carries near-null-space modes of the system's size."""
    from tissuesim.solve.linear import make_linear_solver

    cached = contact.augmented_cache.get("solver")
    if cached is None or cached[0] != problem.pattern.n:
        made, _ = make_linear_solver(options.linear_solver, problem.pattern.n, 3, None)
        contact.augmented_cache["solver"] = cached = (problem.pattern.n, made)
    return cached[1]


def solve_with_moving_obstacles(
    system, c0, t0, t1, energies, solver, options, y0=None, budget=None, relag=None, max_relags=0
):
    """Newton over the bodies and the obstacles (see the module docstring); returns (c1, the
    obstacles' final coordinates, NewtonResult of the last solve, all results). ``relag(c, y)``
    re-lags friction inside the solves (``minimize``'s relag), ``max_relags`` times in all."""
    contact = system.contact
    problem = _Augmented(system, contact, energies)
    solver = _solver_for(problem, contact, solver, options)
    problem.target = contact.obstacle_positions(t1)
    y = contact.obstacle_state if y0 is None else y0
    if y is None:
        y = contact.obstacle_positions(t0)
    z = np.concatenate([c0, y])
    results = []
    relags_left = max_relags
    for _ in range(MAX_UPDATES):
        z, record = minimize(
            problem.evaluate,
            z,
            problem.elimination,
            solver,
            options,
            force_scale=system.force_scale,
            length_scale=system.length_scale,
            retract=problem.retract,
            max_step=problem.max_step,
            reference_rows=slice(0, system.n_dofs),
            path_free=None if contact.linear else problem.path_free,
            contact_projection=True,
            physical_default=True,
            budget=budget,
            relag=None if relag is None else (lambda z: relag(*problem.split(z))),
            max_relags=relags_left,
        )
        relags_left -= record.relags
        results.append(record)
        if not record.converged or record.budget_stop:
            break
        c, y = problem.split(z)
        lag = np.abs(y - problem.target).max(initial=0.0)
        if lag <= TOLERANCE * contact.dhat:
            break
        problem.multiplier = problem.multiplier - problem.penalty * (y - problem.target)
    c, y = problem.split(z)
    record = results[-1]
    if record.gradient is not None:
        record = replace(record, gradient=record.gradient[: system.n_dofs])
    return c, y, record, results
