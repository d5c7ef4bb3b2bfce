"""How a penalty pair's gradient moves with the state through its current-area weights (FEBio's
sliding-elastic weighs each point by its facet's current area, lagged to the converged state:
``PenaltyPair.update``), for the sensitivities of a run (identification/sensitivity.py).

The pair's gradient is sum_i w_i f_i(x), f_i the force of point i per unit weight (its
traction t_i times the gap's gradient over the sampled and target facets' DOFs) and
w_i = W_i |x_r x x_s| at the point (W_i its reference quadrature weight). Where the weights
follow the state, d(gradient)/dx gains sum_i f_i (dw_i/dx)^T, with
d|a x b|/dx_k = H_r,k (b x n) + H_s,k (n x a), n = (a x b) / |a x b| (a = x_r, b = x_s): a
sparse, unsymmetric matrix on the points' stencils.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from tissuesim.contact.penalty.faces import shape_derivatives

__all__ = ["area_coupling"]


def area_coupling(pair, positions: list[np.ndarray], dofs: list[np.ndarray], n: int):
    """sum_i f_i (dw_i/dx)^T (n, n) of a pair with current-area weights at body positions
    ``positions`` (DOFs ``dofs``), or None where its weights do not follow the state."""
    if getattr(pair, "area", "reference") != "current" or pair.tied or pair.sticky:
        return None  # (a rigid wall weighs its nodes by fixed areas)
    rows, cols, vals = [], [], []
    for p in pair.passes:
        found = pair._search(p, positions)
        pts, facet = found[:2]
        if len(pts) == 0:
            continue
        parts = pair._gaps(p, positions, found, 1)
        t = pair.traction(p, pts, parts[0])
        on = pair.pressed(t)
        if not on.any():
            continue
        pts, facet, t = pts[on], facet[on], t[on]
        sf, tf = p.sampled.facets, p.target.facets
        sampled = sf.nodes[p.points.facet[pts]]
        stencil = np.concatenate(
            [dofs[p.sampled.body][sampled], dofs[p.target.body][tf.nodes[facet]]], axis=1
        ).reshape(len(pts), -1)
        force = t[:, None] * parts[3].reshape(len(on), -1)[on]  # per unit weight
        at = p.points.jacobian_rs[pts]
        Hr, Hs, *_ = shape_derivatives(at[:, 0], at[:, 1], sf.kind[p.points.facet[pts]],
                                       sf.nodes.shape[1])  # fmt: skip
        X = positions[p.sampled.body][sampled]
        a = np.einsum("na,nad->nd", Hr, X)
        b = np.einsum("na,nad->nd", Hs, X)
        c = np.cross(a, b)
        normal = c / np.linalg.norm(c, axis=1, keepdims=True)
        dJ = (Hr[:, :, None] * np.cross(b, normal)[:, None, :]
              + Hs[:, :, None] * np.cross(normal, a)[:, None, :])  # fmt: skip
        dw = (p.points.weight[pts][:, None, None] * dJ).reshape(len(pts), -1)
        wdofs = dofs[p.sampled.body][sampled].reshape(len(pts), -1)
        rows.append(np.repeat(stencil, wdofs.shape[1], axis=1).ravel())
        cols.append(np.tile(wdofs, (1, stencil.shape[1])).ravel())
        vals.append((force[:, :, None] * dw[:, None, :]).ravel())
    if not vals:
        return None
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    )
