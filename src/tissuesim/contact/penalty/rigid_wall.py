"""A rigid wall as FEBio enforces it (``FERigidWallInterface``): the nodes of a body's facet
surface pressed out of a plane by a penalty, optionally an augmented Lagrangian; one more
energy in the incremental potential (no barrier, no CCD: nodes may cross the plane by what the
penalty allows).

The plane is n . x = d (n a unit normal; the surface is on the side n points to), moved along n
by ``offset(t)``. Node m's gap (> 0: penetration) and its energy are

    g_m = offset(t) - (n . x_m - d),      W_m / (2 eps) <L_m + eps g_m>^2,

W_m the node's area: the sum over its facets of FEBio's nodal rule (FE_QUAD4NI, FE_TRI3NI:
weights 1 and 1/6 at the corners) times the reference area Jacobian there (FEBio's
``LoadVector``: detJ w[n] from r0). The gradient -W_m <L_m + eps g_m> n is FEBio's nodal force
with its sign, and the Hessian W_m eps H(L_m + eps g_m) n n^T is FEBio's stiffness (exact: the
gap is linear in x). The multiplier L is 0 for a penalty and is updated at converged solutions
as FEBio's ``Augment`` does: L1 = <L + eps g>; while |(|L1| - |L|) / |L1|| >= ``tolerance`` the
multipliers become L1 and Newton solves again (at most ``max_augmentations`` times a step; FEBio
has no cap). Multipliers are kept from step to step, as FEBio's m_Lm.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from tissuesim.contact.penalty.faces import Facets, area_jacobians, sample_points

__all__ = ["RigidWall", "node_areas"]

#: a multipliers' norm at or under this counts as none (FEBio's 1e-10 in ``Augment``)
NO_FORCE = 1e-10


def node_areas(rest: np.ndarray, facets: Facets) -> tuple[np.ndarray, np.ndarray]:
    """(the surface's vertices (k,), their areas W (k,)): FEBio's nodal rule on each facet,
    at rest, summed per vertex."""
    points = sample_points(facets, "nodal")
    w = points.weight * area_jacobians(rest, facets, points)
    node = np.argmax(points.H, axis=1)  # the nodal rule's points are the facets' nodes
    vertex = facets.nodes[points.facet, node]
    nodes, index = np.unique(vertex, return_inverse=True)
    return nodes, np.bincount(index, w, minlength=len(nodes))


@dataclass(eq=False)
class RigidWall:
    """The wall of the module docstring on body ``body`` (its index in the system):
    ``nodes`` its vertices, ``areas`` their W, ``normal`` a unit vector, ``distance`` d,
    ``offset(t)`` the plane's move along the normal, ``penalty`` (Pa/m) times ``scale(t)``
    eps (FEBio's penalty on a load curve); ``clock()`` the time the offset and the scale are
    taken at (the system's load time: the step's end)."""

    name: str
    body: int
    nodes: np.ndarray
    areas: np.ndarray
    normal: np.ndarray
    distance: float
    penalty: float
    offset: Callable[[float], float] = lambda t: 0.0
    clock: Callable[[], float] = lambda: 0.0
    augmented: bool = False
    tolerance: float = 0.0
    max_augmentations: int = 10
    multipliers: np.ndarray = field(default=None)  # type: ignore[assignment]
    augmentations: int = 0  # in this step's solve
    friction: float = 0.0  # none (FEBio's rigid wall is frictionless): as a penalty pair's
    scale: Callable[[float], float] = lambda t: 1.0

    def __post_init__(self) -> None:
        self.normal = np.asarray(self.normal, float)
        if self.multipliers is None:
            self.multipliers = np.zeros(len(self.nodes))

    @property
    def passes(self) -> list:  # a penalty pair's state for carry_penalty_state: none here
        return []

    def eps(self) -> float:
        """The penalty now (Pa/m)."""
        return self.penalty * float(self.scale(self.clock()))

    def gaps(self, x: np.ndarray) -> np.ndarray:
        """g per wall node at the body's positions x (vertices, 3); > 0: behind the plane."""
        return float(self.offset(self.clock())) - (x[self.nodes] @ self.normal - self.distance)

    def _pressures(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        g = self.gaps(x)
        return g, np.maximum(self.multipliers + self.eps() * g, 0.0)

    def evaluate(self, positions: list[np.ndarray], dofs: list[np.ndarray], n: int, order: int,
                 project_psd: bool = False):  # fmt: skip
        """(value, gradient (n,) or None, sparse Hessian or None), as a penalty pair's
        (``pair.py``); the Hessian is PSD already (``project_psd`` changes nothing)."""
        g, t = self._pressures(positions[self.body])
        eps = self.eps()
        if eps > 0:
            value = float(np.sum(self.areas * t * t) / (2 * eps))
        else:  # a penalty curve at 0: the limit W <L> g, up to a constant (the multipliers')
            value = float(np.sum(self.areas * t * g))
        grad = hess = None
        if order >= 1:
            d = dofs[self.body][self.nodes]  # (k, 3)
            grad = np.zeros(n)
            np.add.at(grad, d, -(self.areas * t)[:, None] * self.normal)
        if order >= 2:
            on = t > 0
            k = self.areas[on] * eps
            block = k[:, None, None] * np.outer(self.normal, self.normal)  # (k, 3, 3)
            d = dofs[self.body][self.nodes[on]]
            hess = sp.csr_matrix(
                (block.ravel(), (np.repeat(d, 3, axis=1).ravel(), np.tile(d, (1, 3)).ravel())),
                shape=(n, n),
            )
        return value, grad, hess

    def forces(self, positions: list[np.ndarray]) -> tuple[np.ndarray, float]:
        """(the force the wall puts on the body (3,), the area of the nodes it presses)."""
        _, t = self._pressures(positions[self.body])
        return float(np.sum(self.areas * t)) * self.normal, float(np.sum(self.areas[t > 0]))

    def begin_step(self, positions: list[np.ndarray] | None = None) -> None:
        """A new step's solve (``positions``: the last converged ones, unused: no friction)."""
        self.augmentations = 0

    def update(self, positions: list[np.ndarray]) -> bool:
        """FEBio's ``Augment`` at a converged solution; whether the multipliers changed (then
        Newton solves again)."""
        if not self.augmented or self.augmentations >= self.max_augmentations:
            return False
        _, L1 = self._pressures(positions[self.body])
        old, new = float(np.linalg.norm(self.multipliers)), float(np.linalg.norm(L1))
        change = abs((new - old) / new) if new > NO_FORCE else 0.0
        if change < self.tolerance or (change == 0.0 and self.tolerance == 0.0):
            return False
        self.multipliers = L1
        self.augmentations += 1
        return True
