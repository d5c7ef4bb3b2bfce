"""A follower pressure on an open surface (or on quadrilaterals), lagged as IPC lags friction.

The follower load of a pressure p on facets oriented outward is f_a = -G_a(x) at node a, with

    G_a(x) = p int_f N_a (x_,xi x x_,eta) dxi deta,

the nodal share of p times the area-weighted normal of the deformed facet (N_a the facet's
shape functions: linear on triangles, where G_a = p/6 (x_b - x_a) x (x_c - x_a) for each corner,
one third of p times the area vector; bilinear on the quadrilateral faces of hexahedra,
integrated exactly by 2 x 2 Gauss points, FEBio's consistent pressure load; the quad8 faces of
hexahedra20 on 3 x 3, FEBio's FEQuad8G9). On an open
surface G has no potential (its derivative K_ab = dG_a/dx_b is not symmetric), so a step
freezes it at a lag configuration x_lag and minimises with the dead load

    W_lag(x) = G(x_lag) . x

(inner Newton solves stay those of a dead load: exact Hessian, quadratic convergence), re-lags
at the point it converges to (Newton's ``relag``, also at its loosely converged points) and
repeats until the applied load differs from the follower load there by at most the tolerance
relative to its size (``PressureLags``; the steps use Newton's ``gradient_tolerance``, 1e-8 by
default: the load is then as accurate as the balance Newton stops at). At that fixed point the
force is the follower force.

``SYMMETRIC_STIFFNESS`` adds 1/2 (x - x_lag)^T S (x - x_lag), S = sym K(x_lag), which leaves
the fixed point unchanged (value and gradient vanish at x = x_lag) and turns the error map of
a re-lag from K_int^-1 K into (K_int + S)^-1 skew K. Measured (re-lags per step to 1e-8, Newton
iterations in all): it helps a cantilever bending under its top face a little (hexahedra,
p = 1e-3 E, 4 steps: 22 re-lags and 53 iterations against 29 and 62), but slows a block
compressed through its top face (per step 9 and 13-15 re-lags against 6 and 8): there the face
moves down as a whole, and S turns that into forces along the face at its rim that the
follower load does not have. So it is off, and the dead lag keeps the inner Hessian positive
definite where the elasticity is.

Derivatives: K_ab = p sum_q w_q N_a (N_b,eta [x_,xi]_x - N_b,xi [x_,eta]_x) ([v]_x w = v x w);
on triangles dG_a/dx_j = p/6 [x_k - x_i]_x for every a, (j, i, k) a cyclic order of the corners.
Without a lag (``lag`` None: the energies report, explicit steps) the load is frozen where it
is evaluated: the value is G(x) . x, the potential -f . x of the load frozen there (as a dead
load's is), and the gradient G(x), the follower load.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tissuesim.energies.accumulator import Accumulator

__all__ = ["LaggedPressureEnergy", "PressureLags", "facet_loads", "facet_stiffness", "MAX_RELAGS"]

#: whether W_lag carries S, the symmetric part of the load stiffness (off: see the docstring)
SYMMETRIC_STIFFNESS = False
#: the most re-lags of one solve (each costs a few Newton iterations from a converged point)
MAX_RELAGS = 30

_G = 1.0 / np.sqrt(3.0)
_QUAD_SIGNS = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
_QUAD_POINTS = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])


def _rule(m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(N (q, m), dN/dxi (q, m), dN/deta (q, m), weights (q,)) of a facet with m nodes."""
    if m == 3:  # linear triangle on (0,0) (1,0) (0,1): the centroid is exact (G is linear)
        N = np.full((1, 3), 1.0 / 3.0)
        return N, np.array([[-1.0, 1.0, 0.0]]), np.array([[-1.0, 0.0, 1.0]]), np.array([0.5])
    if m == 8:  # a hexahedron20's quad8 face: FEBio's FEQuad8G9, 3 x 3 Gauss points
        from tissuesim.mesh.cells import tensor_quadratic as tq
        from tissuesim.mesh.cells.tensor import gauss_rule

        points, w = gauss_rule(2, 3)
        N, dN = tq.shape_functions("quad8", points)
        return N, dN[:, :, 0], dN[:, :, 1], w
    s, t = _QUAD_SIGNS[:, 0], _QUAD_SIGNS[:, 1]
    xi, eta = _QUAD_POINTS[:, :1], _QUAD_POINTS[:, 1:]
    N = (1 + s * xi) * (1 + t * eta) / 4.0
    return N, s * (1 + t * eta) / 4.0, t * (1 + s * xi) / 4.0, np.ones(4)


def _tangents(X: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple]:
    """x_,xi and x_,eta (k, q, 3) at the rule's points of facets X (k, m, 3), and the rule."""
    rule = _rule(X.shape[1])
    _, dxi, deta, _ = rule
    return np.einsum("qa,kai->kqi", dxi, X), np.einsum("qa,kai->kqi", deta, X), rule


def facet_loads(X: np.ndarray, p: float) -> np.ndarray:
    """G (k, m, 3): p int N_a (x_,xi x x_,eta) per node of each facet X (k, m, 3), m = 3, 4, 8;
    minus the follower force of pressure p on the facets (outward-oriented)."""
    a, b, (N, _, _, w) = _tangents(X)
    return p * np.einsum("q,qa,kqi->kai", w, N, np.cross(a, b))


def facet_stiffness(X: np.ndarray, p: float) -> np.ndarray:
    """K (k, m, 3, m, 3) = dG_a/dx_b of ``facet_loads`` (not symmetric)."""
    a, b, (N, dxi, deta, w) = _tangents(X)
    cross = np.einsum("qb,kqij->kqbij", deta, _cross_matrix(a)) - np.einsum(
        "qb,kqij->kqbij", dxi, _cross_matrix(b)
    )
    return p * np.einsum("q,qa,kqbij->kaibj", w, N, cross)


def _cross_matrix(v: np.ndarray) -> np.ndarray:
    """[v]_x (..., 3, 3): [v]_x w = v x w."""
    out = np.zeros((*v.shape, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


@dataclass(eq=False)
class LaggedPressureEnergy:
    """W_lag at one pressure p for the facets of ``load`` (energies/pressure.FollowerPressure);
    see the module docstring. ``stiffness``: add S (default ``SYMMETRIC_STIFFNESS``)."""

    load: object
    p: float
    lag: np.ndarray | None = None  # the body's positions (n * 3,) the load is frozen at
    stiffness: bool = field(default_factory=lambda: SYMMETRIC_STIFFNESS)
    relags: int = 0  # re-lags that changed the load
    _frozen: tuple | None = field(default=None, repr=False)

    def set_lag(self, x: np.ndarray) -> None:
        """Freeze the load at x (a copy)."""
        self.lag = np.array(x, dtype=float)
        self._frozen = None

    def _at(self, x_lag: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """(G (k, m, 3), S (k, 3m, 3m) or None) at x_lag."""
        X = x_lag.reshape(-1, 3)[self.load.facets]
        G = facet_loads(X, self.p)
        if not self.stiffness:
            return G, None
        k, m = X.shape[:2]
        K = facet_stiffness(X, self.p).reshape(k, 3 * m, 3 * m)
        return G, 0.5 * (K + np.swapaxes(K, 1, 2))

    def _frozen_terms(self, x: np.ndarray):
        if self.lag is None:
            return (*self._at(x), x)
        if self._frozen is None:
            self._frozen = (*self._at(self.lag), self.lag)
        return self._frozen

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        f = self.load.facets
        G, S, x_lag = self._frozen_terms(x)
        X = x.reshape(-1, 3)[f]
        k, m = f.shape
        d = (X - x_lag.reshape(-1, 3)[f]).reshape(k, 3 * m)
        value = float(np.einsum("kai,kai->", G, X))
        g = G.reshape(k, 3 * m)
        if S is not None:
            Sd = np.einsum("kij,kj->ki", S, d)
            value += 0.5 * float(np.einsum("ki,ki->", d, Sd))
            g = g + Sd
        acc.add_value(self.load.name, value)
        if acc.order >= 1:
            acc.gradient += np.bincount(
                (f[:, :, None] * 3 + np.arange(3)).ravel(), weights=g.ravel(),
                minlength=acc.gradient.size,
            )  # fmt: skip
        # S is indefinite: a projected (PSD) Hessian leaves it out (the step stays a descent)
        if acc.order >= 2 and S is not None and not acc.project:
            acc.hessian += np.bincount(
                self.load.positions(acc.pattern).ravel(), weights=S.ravel(),
                minlength=acc.hessian.size,
            )  # fmt: skip

    def nodal(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(the applied load's gradient dW_lag/dx, G(x) the follower one), both (n * 3,)."""
        acc = _GradientOnly(x.size)
        self.accumulate(x, acc)
        f = self.load.facets
        follower = np.bincount(
            (f[:, :, None] * 3 + np.arange(3)).ravel(),
            weights=facet_loads(x.reshape(-1, 3)[f], self.p).ravel(),
            minlength=x.size,
        )
        return acc.gradient, follower

    def mismatch(self, x: np.ndarray) -> float:
        """|applied - follower| / |follower| at x (nodal vectors; 0 when both vanish)."""
        applied, follower = self.nodal(x)
        size = float(np.linalg.norm(follower))
        gap = float(np.linalg.norm(applied - follower))
        return gap / size if size > 0.0 else gap

    def relag(self, x: np.ndarray, tolerance: float) -> bool:
        """Re-lag at x unless the applied load is the follower load there to ``tolerance``
        (relative); whether it re-lagged."""
        if self.lag is not None and self.mismatch(x) <= tolerance:
            return False
        self.set_lag(x)
        self.relags += 1
        return True


class _GradientOnly:
    """An order-1 accumulator without a pattern (for ``nodal``)."""

    order, project = 1, False

    def __init__(self, n: int) -> None:
        self.gradient = np.zeros(n)

    def add_value(self, name: str, value: float) -> None:
        pass


class PressureLags:
    """The lagged pressures of one step's energies over a system's configuration: ``start``
    freezes them at the start point, ``relag`` (Newton's) re-lags those not settled, and
    ``unsettled`` names one that is not at the end (the step must not be accepted)."""

    def __init__(self, items: list[tuple[slice, LaggedPressureEnergy]], tolerance: float):
        self.items, self.tolerance = items, tolerance

    @classmethod
    def of(cls, slices, energies, tolerance: float) -> PressureLags | None:
        """From per-body energy lists (body j's configuration at ``slices[j]``); None when
        no energy is a lagged pressure."""
        items = [
            (slices[j], e)
            for j, body in enumerate(energies)
            for e in body
            if isinstance(e, LaggedPressureEnergy)
        ]
        return cls(items, tolerance) if items else None

    @property
    def relags(self) -> int:
        """The re-lags that changed a load, over every lagged pressure."""
        return sum(e.relags for _, e in self.items)

    def start(self, c: np.ndarray) -> None:
        for s, e in self.items:
            e.set_lag(c[s])

    def relag(self, c: np.ndarray) -> bool:
        changed = False
        for s, e in self.items:
            changed = e.relag(c[s], self.tolerance) or changed
        return changed

    def unsettled(self, c: np.ndarray, relags: int) -> str | None:
        """A one-line reason when a load at c is not yet its follower load, else None."""
        for s, e in self.items:
            gap = e.mismatch(c[s])
            if gap > self.tolerance:
                return (
                    f"the follower pressure {e.load.name!r} did not settle in {relags} re-lags "
                    f"(its load still moves {gap:.2g} of itself, tolerance {self.tolerance:.2g})"
                )
        return None
