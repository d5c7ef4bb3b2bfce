"""Penalty (and augmented-Lagrangian) contact between two facet surfaces, as FEBio enforces it:
one more energy in the incremental potential, with no barrier and no CCD (surfaces may
interpenetrate by what the penalty allows: FEBio's semantics, for FEBio's models).

Points sampled on the primary surface (``faces.py``: Gauss points, or the nodes for FEBio's
node-on-facet) are projected onto the secondary surface (``projection.py``); a point whose
projection lies on a facet (within ``search_tolerance`` in natural coordinates; the closest such
facet) has the gap g (> 0: penetration). With the point's weight W (rule weight x area
Jacobian, of the reference surface, or of the current surface lagged: FEBio's sliding-elastic
integrates over the current one) and penalty eps, its energy is

    W / (2 eps) <L + eps g>^2,     <a> = max(a, 0),

(``tension``: W / (2 eps) (L + eps g)^2, no bracket: a point whose projection lies on a facet
stays in contact as the surfaces pull apart, its traction tensile, as FEBio's sliding-elastic
with ``tension = 1``), whose gradient is FEBio's contact force W <L + eps g> dg/dy
(``FEFacet2FacetSliding::LoadVector``); the multiplier L is 0 for a penalty method and is
updated as FEBio's augmented Lagrangian does (``Augment``: L <- <L + eps g> until the
multipliers' norm changes by less than ``tolerance`` and the rms penetration is under
``gap_tolerance``, between ``min_augmentations`` and ``max_augmentations`` per step).
``two_pass``: the secondary surface's points are projected onto the primary too (a second,
symmetric energy). The Hessian is exact (``projection.py``). ``friction``: Coulomb friction by
FEBio's return map, one more energy per point with its pressure and normal lagged
(``friction.py``); ``keep_last_augmentation``: the augmentation that finds the multipliers
converged is kept for the next step (FEBio's sliding-elastic). ``special_cases``: a point on no
facet is projected onto an interior edge or a node of the other surface, FEBio's
``ProjectSpecial`` (``special_cases.py``). Tied and sticky passes: ``tied.py``."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from tissuesim.contact.penalty import friction as coulomb
from tissuesim.contact.penalty.faces import (
    Facets,
    SamplePoints,
    area_jacobians,
    sample_points,
)
from tissuesim.contact.penalty.projection import gap_derivatives, outside, project
from tissuesim.contact.penalty.special_cases import (
    Special,
    Topology,
    contact_gaps,
    in_order,
    nearest_feature,
    special_contacts,
)
from tissuesim.contact.penalty.tied import stick, tied_gaps, tied_terms

__all__ = ["PenaltyContact", "PenaltySide", "PenaltyPass"]

#: facets tried per point (the nearest by centroid)
CANDIDATES = 8
#: points farther than this many facet sizes (centre to corner) from every facet centre of
#: the other surface are out of contact (FEBio's search radius)
SEARCH_RADIUS = 2.0
#: how far outside a facet (natural coordinates) a projection is still on it, with special
#: cases (round-off)
STRICT = 1e-12
#: relative change of a lagged current-area weight below which it has settled
AREA_SETTLED = 1e-9


@dataclass(frozen=True)
class PenaltySide:
    """One surface: its body's index in the system, its facets (body vertex indices), and the
    per-facet penalty scale (FEBio's auto penalty, 1 otherwise)."""

    body: int
    facets: Facets
    scale: np.ndarray


@dataclass(eq=False)
class PenaltyPass:
    """Points of ``sampled`` projected onto ``target``; state: multipliers and weights."""

    sampled: PenaltySide
    target: PenaltySide
    points: SamplePoints
    weights: np.ndarray  # W per point (reference, or the lagged current one)
    multipliers: np.ndarray  # L per point (Pa); tied and sticky: (points, 3)
    tie: tuple | None = None  # tied / sticky: (points held, their facets, (r, s))
    friction: coulomb.FrictionState | None = None  # with a friction coefficient
    _last: tuple | None = None  # (positions, contacts) of the last search (_search)
    topology: Topology | None = None  # the target's edges, with special_cases


@dataclass(eq=False)
class PenaltyContact:
    """A contact pair (module docstring). ``penalty``: eps (Pa/m), times each primary
    facet's ``scale``."""

    name: str
    primary: PenaltySide
    secondary: PenaltySide
    penalty: float
    rule: str = "gauss"  # "gauss" or "nodal" (FEBio's node-on-facet)
    area: str = "reference"  # or "current" (lagged; FEBio's sliding-elastic)
    two_pass: bool = False
    augmented: bool = False
    tolerance: float = 0.0  # relative change of the multipliers' norm (0: not checked)
    gap_tolerance: float = 0.0  # rms penetration (m; 0: not checked)
    min_augmentations: int = 0
    max_augmentations: int = 10
    search_tolerance: float = 0.01
    # tied (FEBio's tied-elastic, tied-node-on-facet, tied-facet-on-facet): each point is held
    # to the place on the secondary surface it projects to at rest, by the vector gap d = q - x:
    # energy W / (2 eps) |L + eps d|^2, L a vector multiplier
    tied: bool = False
    # sticky (FEBio's sticky): a point is tied where it projects once it comes within
    # ``snap_tolerance`` of the secondary surface (or behind it), checked at converged
    # solutions; it lets go when its normal traction exceeds ``max_traction`` (0: never)
    sticky: bool = False
    snap_tolerance: float = 0.0
    max_traction: float = 0.0
    # Coulomb friction (friction.py): coefficient mu and the tangential penalty eps_t (Pa/m;
    # 0: the normal one, as FEBio's sliding-elastic; node-on-facet gives its fric_penalty)
    friction: float = 0.0
    friction_penalty: float = 0.0
    friction_anchor: str = "step"  # friction.ANCHORS
    # FEBio's sliding-elastic keeps the multipliers of the augmentation that finds them
    # converged (its Augment updates before it checks); facet-on-facet and node-on-facet do not
    keep_last_augmentation: bool = False
    # FEBio's HandleSpecialCases(true) (special_cases.py): a point projecting onto no facet
    # is projected onto an interior edge or a node of the secondary surface
    special_cases: bool = False
    # FEBio's sliding-elastic ``tension``: the traction L + eps g unbracketed (pulls too)
    tension: bool = False
    passes: list = field(default_factory=list)
    augmentations: int = 0  # in this step's solve

    def setup(self, rest: list[np.ndarray]) -> None:
        """The passes' points and reference weights, from every body's rest positions."""
        sides = [(self.primary, self.secondary)]
        if self.two_pass:
            sides.append((self.secondary, self.primary))
        self.passes = []
        for sampled, target in sides:
            points = sample_points(sampled.facets, self.rule)
            w = points.weight * area_jacobians(rest[sampled.body], sampled.facets, points)
            p = PenaltyPass(sampled, target, points, w, np.zeros(len(w)))
            if self.special_cases:
                p.topology = Topology.of(target.facets)
            if self.tied:  # where each point sits on the secondary surface at rest, kept
                p.tie = self._find_contacts(p, rest)[:3]
            if self.tied or self.sticky:
                p.multipliers = np.zeros((len(w), 3))
            if self.sticky:  # nothing stuck yet
                p.tie = (np.zeros(0, int), np.zeros(0, int), np.zeros((0, 2)))
            if self.friction > 0:
                p.friction = coulomb.FrictionState.empty(len(w))
                if self.friction_anchor == "contact":  # FEBio's node-on-facet slip
                    p.friction.rest = np.asarray(rest[target.body], dtype=float)
            self.passes.append(p)

    # -- geometry --------------------------------------------------------------------------
    def _contacts(self, p: PenaltyPass, positions: list[np.ndarray]):
        """(points with a facet, their facet, (r, s), their positions) of pass p at body
        positions."""
        return self._search(p, positions)[:4]

    def _search(self, p: PenaltyPass, positions: list[np.ndarray]):
        """``_contacts`` and which of them are special (special_cases.Special); the last
        answer again for the same positions (Newton asks for a point's Hessian after its line
        search asked for its gradient)."""
        here = (positions[p.sampled.body], positions[p.target.body])
        last = p._last
        if last is not None and all(
            np.array_equal(a, b) for a, b in zip(last[0], here, strict=True)
        ):
            return last[1]
        out = self._find_contacts(p, positions)
        p._last = ((here[0].copy(), here[1].copy()), out)
        return out

    def _find_contacts(self, p: PenaltyPass, positions: list[np.ndarray]):
        xs = positions[p.sampled.body][p.sampled.facets.nodes[p.points.facet]]
        x = np.einsum("na,nad->nd", p.points.H, xs)
        tf = p.target.facets
        X_all = positions[p.target.body][tf.nodes]
        centroids = X_all.mean(axis=1)
        # points farther from every facet centre than SEARCH_RADIUS facet sizes touch nothing
        size = float(np.max(np.linalg.norm(X_all - centroids[:, None], axis=2)))
        k = min(CANDIDATES, len(centroids))
        tree = cKDTree(centroids)
        d0, _ = tree.query(x, k=1)
        near_rows = np.flatnonzero(d0 <= SEARCH_RADIUS * size)
        if len(near_rows) == 0:
            return np.zeros(0, int), np.zeros(0, int), np.zeros((0, 2)), x[:0], Special.none()
        _, near = tree.query(x[near_rows], k=k)
        near = near.reshape(len(near_rows), k)
        flat = near.ravel()
        xr = np.repeat(x[near_rows], k, axis=0)
        rs = project(xr, X_all[flat], tf.kind[flat])
        excess = outside(rs, tf.kind[flat])
        g, _, _ = gap_derivatives(xr, None, X_all[flat], rs, tf.kind[flat], 0)
        # the closest facet whose projection is on it, within the search tolerance (extending
        # the nearest facet over a convex edge took co13 from 8e-9 to 1.2e-3); with special
        # cases strictly on it, else an edge or node, else within the tolerance (special_cases)
        excess = excess.reshape(len(near_rows), k)
        g = np.abs(g).reshape(excess.shape)
        rows = np.arange(len(near_rows))

        def closest(on, among):
            dist = np.where(on[among], g[among], np.inf)
            best = np.argmin(dist, axis=1)
            found = np.isfinite(dist[np.arange(len(among)), best])
            hit = among[found]
            return found, hit * k + best[found], hit

        special = Special.none()
        if p.topology is None:
            found, pick, hit = closest(excess <= self.search_tolerance, rows)
            return near_rows[hit], flat[pick], rs[pick], x[near_rows[hit]], special
        found, pick, hit = closest(excess <= STRICT, rows)
        pts, facet, rs_out = near_rows[hit], flat[pick], rs[pick]
        miss = rows[~found]
        if len(miss):  # FEBio's ProjectSpecial
            which, f, r, slots, lam = special_contacts(x[near_rows[miss]],
                                                       positions[p.target.body], tf,
                                                       p.topology)  # fmt: skip
            cand = (miss[which][:, None] * k + np.arange(k)).ravel()
            keep = nearest_feature(x[near_rows[miss[which]]], X_all[f], r, tf.kind[f],
                                   X_all[flat[cand]], rs[cand], tf.kind[flat[cand]])  # fmt: skip
            which, f, r, slots, lam = which[keep], f[keep], r[keep], slots[keep], lam[keep]
            special = Special(len(pts) + np.arange(len(which)), slots, lam)
            pts = np.concatenate([pts, near_rows[miss[which]]])
            facet, rs_out = np.concatenate([facet, f]), np.vstack([rs_out, r])
            miss = np.setdiff1d(miss, miss[which])
        if len(miss):  # the rim: within the search tolerance
            _, pick, hit = closest(excess <= self.search_tolerance, miss)
            pts = np.concatenate([pts, near_rows[hit]])
            facet, rs_out = np.concatenate([facet, flat[pick]]), np.vstack([rs_out, rs[pick]])
        pts, facet, rs_out, special = in_order(pts, facet, rs_out, special)
        return pts, facet, rs_out, x[pts], special

    def _gaps(self, p: PenaltyPass, positions: list[np.ndarray], found, order: int = 0):
        """gap_derivatives' list for the contacts ``found`` (``_search``) of pass p."""
        pts, facet, rs, x, special = found
        X = positions[p.target.body][p.target.facets.nodes[facet]]
        kind = p.target.facets.kind[facet]
        return contact_gaps(x, p.points.H[pts], X, rs, kind, special, order)

    def _eps(self, p: PenaltyPass) -> np.ndarray:
        return self.penalty * p.sampled.scale[p.points.facet]

    def traction(self, p: PenaltyPass, pts: np.ndarray, g: np.ndarray) -> np.ndarray:
        """The normal traction of pass p's points pts at gaps g: <L + eps g>, or L + eps g
        in ``tension``."""
        t = p.multipliers[pts] + self._eps(p)[pts] * g
        return t if self.tension else np.maximum(t, 0.0)

    def pressed(self, t: np.ndarray) -> np.ndarray:
        """Which tractions t (``traction``) act: the positive ones, any in tension."""
        return t != 0 if self.tension else t > 0

    def _eps_t(self, p: PenaltyPass) -> np.ndarray:
        if self.friction_penalty > 0:
            return np.full(len(p.weights), self.friction_penalty)
        return self._eps(p)

    # -- energy ---------------------------------------------------------------------------
    def evaluate(self, positions: list[np.ndarray], dofs: list[np.ndarray], n: int, order: int,
                 project_psd: bool = False):  # fmt: skip
        """(value, gradient (n,) or None, sparse Hessian or None) at body positions
        ``positions[j]`` (vertices, 3) whose DOFs are ``dofs[j]`` (vertices, 3) in the system."""
        value = 0.0
        grad = np.zeros(n) if order >= 1 else None
        rows, cols, vals = [], [], []
        for p in self.passes:
            if self.tied or self.sticky:
                value += tied_terms(self, p, positions, dofs, order, grad, rows, cols, vals)
                continue
            if p.friction is not None:
                value += coulomb.friction_terms(p.friction, p, positions, dofs,
                                                self._eps_t(p), self.friction, order, grad,
                                                rows, cols, vals)  # fmt: skip
            found = self._search(p, positions)
            pts, facet = found[:2]
            if len(pts) == 0:
                continue
            tf, sf = p.target.facets, p.sampled.facets
            parts = self._gaps(p, positions, found, min(order, 2))
            g = parts[0]
            eps = self._eps(p)[pts]
            t = self.traction(p, pts, g)
            W = p.weights[pts]
            value += float(np.sum(W * t * t / (2 * eps)))
            if order < 1:
                continue
            on = self.pressed(t)
            stencil = np.concatenate(
                [
                    dofs[p.sampled.body][sf.nodes[p.points.facet[pts]]],
                    dofs[p.target.body][tf.nodes[facet]],
                ],
                axis=1,
            ).reshape(len(pts), -1)
            width = stencil.shape[1]  # 3 x (the sampled facet's nodes + the target's)
            dg = parts[3].reshape(len(pts), width)
            np.add.at(grad, stencil[on], (W * t)[on, None] * dg[on])
            if order >= 2 and on.any():
                dg_on = dg[on]
                h = (W * eps)[on, None, None] * dg_on[:, :, None] * dg_on[:, None, :]
                h += (W * t)[on, None, None] * parts[4][on]
                if project_psd:
                    lam, V = np.linalg.eigh(h)
                    h = np.einsum("nij,nj,nkj->nik", V, np.maximum(lam, 0.0), V)
                s = stencil[on]
                rows.append(np.repeat(s, width, axis=1).ravel())
                cols.append(np.tile(s, (1, width)).ravel())
                vals.append(h.ravel())
        hess = None
        if order >= 2:
            hess = sp.csr_matrix(
                (
                    np.concatenate(vals) if vals else np.zeros(0),
                    (
                        np.concatenate(rows) if rows else np.zeros(0, int),
                        np.concatenate(cols) if cols else np.zeros(0, int),
                    ),
                ),
                shape=(n, n),
            )
        return value, grad, hess

    def forces(self, positions: list[np.ndarray]) -> tuple[np.ndarray, float]:
        """(the force the secondary surface puts on the primary, normal and friction (N, 3),
        the contact area's sum of point weights in contact (m^2)); with two passes, both
        passes' forces add (as FEBio's two-pass load vectors do)."""
        total, area = np.zeros(3), 0.0
        for k, p in enumerate(self.passes):
            if self.tied or self.sticky:
                pts, _, d = tied_gaps(p, positions)
                t = p.multipliers[pts] + self._eps(p)[pts][:, None] * d
                f = np.sum(p.weights[pts][:, None] * t, axis=0)
                total += f if k == 0 else -f
                area += float(np.sum(p.weights[pts]))
                continue
            found = self._search(p, positions)
            pts = found[0]
            if len(pts) == 0:
                continue
            g, nu, _ = self._gaps(p, positions, found)
            t = self.traction(p, pts, g)
            f = np.sum((p.weights[pts] * t)[:, None] * nu, axis=0)
            if p.friction is not None:
                f += coulomb.force(p.friction, p, positions, self._eps_t(p), self.friction)
            total += f if k == 0 else -f
            area += float(np.sum(p.weights[pts][self.pressed(t)]))
        return total, area

    # -- the lagged terms: multipliers and current-area weights -------------------------------
    def begin_step(self, positions: list[np.ndarray] | None = None) -> None:
        """A step starts from ``positions`` (the last converged ones): no augmentation yet,
        friction anchored where the points project."""
        self.augmentations = 0
        if positions is None:
            return
        for p in self.passes:
            if p.friction is not None:
                coulomb.anchor(p.friction, p, self._contacts(p, positions), positions,
                               self._eps(p), p.multipliers, self.friction_anchor)  # fmt: skip

    def update(self, positions: list[np.ndarray]) -> bool:
        """At a converged solution: re-lag current-area weights and do FEBio's augmentation;
        whether anything changed (then Newton solves again)."""
        changed = False
        if self.area == "current":
            for p in self.passes:
                sf = p.sampled.facets
                w = p.points.weight * area_jacobians(positions[p.sampled.body], sf, p.points)
                if np.max(np.abs(w - p.weights) / np.maximum(p.weights, 1e-300)) > AREA_SETTLED:
                    changed = True
                p.weights = w
        if self.sticky:
            changed = stick(self, positions) or changed
        lagged = False
        for p in self.passes:
            if p.friction is not None:
                contacts = self._contacts(p, positions)
                lagged = coulomb.lag(p.friction, p, contacts, positions, self._eps(p),
                                     p.multipliers, self._eps_t(p)) or lagged  # fmt: skip
        if lagged:  # the friction's pressures settle before the multipliers are augmented
            return True
        if not self.augmented:
            return changed
        old, new, gaps = 0.0, 0.0, []
        updates = []
        for p in self.passes:
            if self.tied or self.sticky:
                pts, _, d = tied_gaps(p, positions)
                L1 = p.multipliers.copy()
                L1[pts] += self._eps(p)[pts][:, None] * d
                old += float(np.sum(p.multipliers**2))
                new += float(np.sum(L1**2))
                gaps.append(np.linalg.norm(d, axis=1))
                updates.append(L1)
                continue
            g = np.zeros(len(p.multipliers))
            found = self._search(p, positions)
            if len(found[0]):
                g[found[0]] = self._gaps(p, positions, found)[0]
            L1 = self.traction(p, np.arange(len(g)), g)
            old += float(p.multipliers @ p.multipliers)
            new += float(L1 @ L1)
            gaps.append(g[g > 0])
            if p.friction is not None:  # FEBio's norm holds the tangential multipliers too
                o, nw, Lt = coulomb.augment(p.friction, p, positions, self._eps_t(p),
                                            self.friction)  # fmt: skip
                old, new = old + o, new + nw
                L1 = (L1, Lt)
            updates.append(L1)
        old, new = np.sqrt(old), np.sqrt(new)
        lnorm = abs(new - old) / new if new != 0 else abs(new - old)
        positive = np.concatenate(gaps)
        gnorm = float(np.sqrt(np.mean(positive**2))) if len(positive) else 0.0
        converged = not (self.tolerance > 0 and lnorm > self.tolerance)
        converged &= not (self.gap_tolerance > 0 and gnorm > self.gap_tolerance)
        if self.augmentations < self.min_augmentations:
            converged = False
        if self.augmentations >= self.max_augmentations:
            converged = True
        if not converged or self.keep_last_augmentation:
            for p, L1 in zip(self.passes, updates, strict=True):
                if isinstance(L1, tuple):
                    L1, p.friction.traction = L1
                p.multipliers = L1
        if not converged:
            self.augmentations += 1
            changed = True
        return changed
