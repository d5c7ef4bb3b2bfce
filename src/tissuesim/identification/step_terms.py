"""The step's terms that the sensitivities add beyond its potential's Hessian
(``sensitivity.py``): where the step was solved with a term lagged to its own solution (a
fixed point), that term's derivative joins the step's matrix; where a term was set up at the
step's start, the parameter copies take it about the start moved along its own derivative.

- ``damping_from``: Rayleigh damping about the step's start (C(x_n) (x - x_n) / h);
- ``area_coupling``: FEBio's sliding-elastic current-area weights (the penalty pairs');
- ``lag_coupling``: a reactive viscoelastic law's bond recruitment lagged to FEBio's fixed
  point (``Model.lag_coupling``);
- ``follower_stiffness``: follower pressures on open surfaces, re-lagged until they settled.
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp

__all__ = ["area_coupling", "damping_from", "follower_stiffness", "lag_coupling"]


@contextmanager
def damping_from(sim, x_start: np.ndarray, h: float, step: float = 0.0, direction=None):
    """The Rayleigh damping of each damped FEM body of ``sim`` about the step's start
    ``x_start`` (configuration), moved by ``step`` along the tangent ``direction`` where one
    is given (as ``Model.begin_step`` sets it up), for the evaluations inside; the bodies' own
    terms after."""
    s = sim.system
    damped = [
        (j, sim.bodies[name].model)
        for j, name in enumerate(s.names)
        if sim.bodies[name].kind == "fem" and sim.bodies[name].model.damping is not None
    ]
    if not damped:
        yield
        return
    from tissuesim.energies.damping import RayleighDamping

    kept = [m._step_damping for _, m in damped]
    for j, m in damped:
        start = x_start[s.config_slices[j]]
        if direction is not None:  # a FEM body's configuration and tangent coincide
            start = start + step * direction[s.tangent_slices[j]]
        m._step_damping = RayleighDamping.at(m, start, h, *m.damping)
    try:
        yield
    finally:
        for (_, m), old in zip(damped, kept, strict=True):
            m._step_damping = old


def area_coupling(system, x: np.ndarray):
    """The penalty pairs' d(gradient)/dx through their current-area weights (None: none)."""
    from tissuesim.contact.penalty.area_coupling import area_coupling as pair_coupling

    if not system.penalty_contacts:
        return None
    positions, dofs = system.body_positions_and_dofs(x)
    total = None
    for pair in system.penalty_contacts:
        C = pair_coupling(pair, positions, dofs, system.n_dofs)
        if C is not None:
            total = C if total is None else total + C
    return total


def lag_coupling(system, x: np.ndarray):
    """The FEM bodies' d(gradient)/dx through their materials' lagged terms (a reactive
    viscoelastic law's recruitment, at its fixed point), in the system's DOFs (None: none)."""
    _, dofs = system.body_positions_and_dofs(x)
    total = None
    for j, body in enumerate(system.bodies):
        if not (hasattr(body, "lagged_materials") and body.lagged_materials()):
            continue
        C = body.lag_coupling(x[system.config_slices[j]])
        if C is None:
            continue
        C = C.tocoo()
        where = np.asarray(dofs[j]).ravel()
        C = sp.csr_matrix((C.data, (where[C.row], where[C.col])),
                          shape=(system.n_dofs, system.n_dofs))  # fmt: skip
        total = C if total is None else total + C
    return total


def follower_stiffness(s, x: np.ndarray):
    """d G / dx (sparse, n x n) of the step's lagged follower pressures on open surfaces
    (``energies/pressure_lag.py``): the step's solve balanced the follower load G(x) itself
    (re-lagged until it settled), so its derivative moves with x; None without one."""
    from tissuesim.energies.pressure_lag import LaggedPressureEnergy, facet_stiffness

    rows, cols, vals = [], [], []
    for j, energies in enumerate(s.last_step_energies or ()):
        offset = s.config_slices[j].start
        for e in energies:
            if not isinstance(e, LaggedPressureEnergy):
                continue
            f = e.load.facets
            k, m = f.shape
            xb = x[s.config_slices[j]].reshape(-1, 3)
            Kf = facet_stiffness(xb[f], e.p)  # (k, m, 3, m, 3)
            dof = offset + f[:, :, None] * 3 + np.arange(3)  # (k, m, 3)
            rows.append(np.broadcast_to(dof[:, :, :, None, None], Kf.shape).ravel())
            cols.append(np.broadcast_to(dof[:, None, None, :, :], Kf.shape).ravel())
            vals.append(Kf.ravel())
    if not rows:
        return None
    n = s.n_dofs
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, n))  # fmt: skip
