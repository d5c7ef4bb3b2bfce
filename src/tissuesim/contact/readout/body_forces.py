"""The contact force one body receives from another, as a force sensor between them would
read it: "A.contact.B" (N, 3-vector) is the force on body A from body B, and with friction its
parts "A.contact.B.normal" (the barrier's) and "A.contact.B.friction" (the lagged friction's).

Obstacles' forces are the barrier gradient summed over their own vertices (obstacles never
touch each other). Two bodies can also touch themselves and a third, so each enabled pair
(A, B) gets its own collision set, built with a filter that keeps only vertex pairs between A
and B: the force on A from B is minus the gradient of that set's barrier (and of its friction,
lagged where the step lagged it) summed over A's vertices; B's from A is its opposite (each
collision's gradient sums to zero over its stencil). One collision build per pair per step:
about a candidate build's cost, only when two bodies can touch.
"""

from __future__ import annotations

import numpy as np

from tissuesim.contact.cut.sliver_points import weigh_points

__all__ = ["body_contact_forces"]


def body_contact_forces(model, V: np.ndarray, lag=None) -> dict[str, np.ndarray]:
    """Per enabled pair of bodies of the ContactModel ``model`` at collision vertices V: the
    force each receives from the other. ``lag`` (V_lag, V_start, FrictionPotential): the
    step's friction lag (None: frictionless)."""
    pairs = model.table.body_pairs()
    if not pairs:
        return {}
    ipctk, mesh, names, dim = model._ipctk, model.mesh, model.table.names, model.dim
    kept = mesh.can_collide
    out: dict[str, np.ndarray] = {}
    try:
        for i, j in pairs:
            mesh.can_collide = model.table.pair_filter(ipctk, model.group, i, j)
            normal = _gradient(model, V, _collisions(model, V))
            friction = np.zeros_like(normal)
            if lag is not None:
                V_lag, V_start, potential = lag
                tangential = model.tangential_collisions(V_lag, _collisions(model, V_lag))
                if len(tangential):
                    U = np.asfortranarray(V - V_start)
                    friction = potential.gradient(tangential, mesh, U).reshape(-1, dim)
            for a, b in ((i, j), (j, i)):
                rows = model.group == a
                n, f = -normal[rows].sum(axis=0), -friction[rows].sum(axis=0)
                key = f"{names[a]}.contact.{names[b]}"
                out[key] = n + f
                if model.has_friction:
                    out[f"{key}.normal"], out[f"{key}.friction"] = n, f
    finally:
        mesh.can_collide = kept
    return out


def _collisions(model, V: np.ndarray):
    col = model._ipctk.NormalCollisions()
    col.use_area_weighting = True
    col.build(model.mesh, V, model.dhat, broad_phase=model.broad_phase)
    if model.point_areas is not None:
        weigh_points(col, model.point_areas)
    return col


def _gradient(model, V: np.ndarray, col) -> np.ndarray:
    if len(col) == 0:
        return np.zeros_like(V)
    return model.barrier.gradient(col, model.mesh, V).reshape(-1, model.dim)
