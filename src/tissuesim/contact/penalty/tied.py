"""The tied and sticky passes of a penalty pair (``pair.py``): FEBio's tied contacts hold each
point where it projects at rest by the vector gap d = q - x, energy W / (2 eps) |L + eps d|^2
(its Hessian constant); sticky ties a point once it comes within the snap distance and lets go
past ``max_traction`` (``stick``, at converged solutions)."""

from __future__ import annotations

import numpy as np

from tissuesim.contact.penalty.faces import shape
from tissuesim.contact.penalty.projection import gap_derivatives

__all__ = ["stick", "tied_gaps", "tied_terms"]


def tied_gaps(p, positions: list[np.ndarray]):
    """(points, stencil weights w (n, k + m), vector gaps d = q - x (n, 3)) of a tied
    pass (k, m: the sampled and target facets' node widths)."""
    pts, facet, rs = p.tie
    sf, tf = p.sampled.facets, p.target.facets
    Hs = p.points.H[pts]
    x = np.einsum("na,nad->nd", Hs, positions[p.sampled.body][sf.nodes[p.points.facet[pts]]])
    Hm = shape(rs[:, 0], rs[:, 1], tf.kind[facet], tf.nodes.shape[1])
    q = np.einsum("na,nad->nd", Hm, positions[p.target.body][tf.nodes[facet]])
    return pts, np.concatenate([-Hs, Hm], axis=1), q - x


def tied_terms(pair, p, positions, dofs, order, grad, rows, cols, vals) -> float:
    """A tied pass: its energy, and its gradient and (constant) Hessian added in place."""
    pts, w, d = tied_gaps(p, positions)
    if len(pts) == 0:
        return 0.0
    eps = pair._eps(p)[pts]
    W = p.weights[pts]
    t = p.multipliers[pts] + eps[:, None] * d
    value = float(np.sum(W * np.sum(t * t, axis=1) / (2 * eps)))
    if order < 1:
        return value
    _, facet, _ = p.tie
    stencil = np.concatenate(
        [
            dofs[p.sampled.body][p.sampled.facets.nodes[p.points.facet[pts]]],
            dofs[p.target.body][p.target.facets.nodes[facet]],
        ],
        axis=1,
    ).reshape(len(pts), -1)
    width = stencil.shape[1]
    g = (w[:, :, None] * (W[:, None] * t)[:, None, :]).reshape(len(pts), width)
    np.add.at(grad, stencil, g)
    if order >= 2:
        ww = (W * eps)[:, None, None] * w[:, :, None] * w[:, None, :]  # (n, k+m, k+m)
        h = np.einsum("nab,ij->naibj", ww, np.eye(3)).reshape(len(pts), width, width)
        rows.append(np.repeat(stencil, width, axis=1).ravel())
        cols.append(np.tile(stencil, (1, width)).ravel())
        vals.append(h.ravel())
    return value


def stick(pair, positions: list[np.ndarray]) -> bool:
    """Sticky: free points within the snap distance stick where they project; stuck ones
    whose normal traction passes ``max_traction`` let go. Whether any changed."""
    changed = False
    for p in pair.passes:
        held, facet, rs = p.tie
        let_go = np.zeros(0, int)  # not stuck again at once (FEBio: at its next update)
        if pair.max_traction > 0 and len(held):
            _, _, d = tied_gaps(p, positions)
            X = positions[p.target.body][p.target.facets.nodes[facet]]
            nodes = p.sampled.facets.nodes[p.points.facet[held]]
            x = np.einsum("na,nad->nd", p.points.H[held], positions[p.sampled.body][nodes])
            _, nu, _ = gap_derivatives(x, None, X, rs, p.target.facets.kind[facet], 0)
            t = p.multipliers[held] + pair._eps(p)[held][:, None] * d
            keep = np.einsum("nd,nd->n", t, nu) >= -pair.max_traction  # pulled off: let go
            if not keep.all():
                p.multipliers[held[~keep]] = 0.0
                let_go = held[~keep]
                held, facet, rs = held[keep], facet[keep], rs[keep]
                changed = True
        found = pair._search(p, positions)
        pts, f, r, _ = found[:4]
        free = ~np.isin(pts, held) & ~np.isin(pts, let_go)
        if free.any():
            g = pair._gaps(p, positions, found)[0][free]
            new = g > -pair.snap_tolerance
            if new.any():
                sel = np.flatnonzero(free)[new]
                held = np.concatenate([held, pts[sel]])
                facet = np.concatenate([facet, f[sel]])
                rs = np.vstack([rs, r[sel]])
                changed = True
        p.tie = (held, facet, rs)
    return changed
