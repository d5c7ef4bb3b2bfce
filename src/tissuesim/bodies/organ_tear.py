"""A FEM body that tears (``Simulation.set_tearing(stress=..., body=...)``, scene ``[tearing]``
with ``body``): by the machinery of a cut (``Simulation.cut_body``, virtual nodes), along a
crack that grows, normal to the largest principal stress, through the elements that exceed
the strength.

After every step, each element's largest principal Cauchy stress sigma_1 (or largest principal
stretch, with ``stretch``) and its direction are computed where the body is. The first time
one exceeds the threshold, the crack's plane is set: through the centroid of the element that
exceeds it most, normal to its principal direction (the crack opens against that stress). Then
every step the crack takes the elements its plane crosses that exceed the threshold: the crack
polygon is the convex hull, in that plane, of their sections and of the crack so far, and the
body is cut along it (a named cut that goes on). The rule is deterministic (no random
nucleation) and the crack is planar (one plane per body). Its size per step, and so the load at
which a body tears, depends on the mesh as every local strength criterion on a stress field
does: the guide reports it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.virtual_nodes import PlanarCut

__all__ = ["BodyTearing"]


@dataclass
class BodyTearing:
    """Tearing of FEM body ``body`` where the largest principal Cauchy stress exceeds
    ``stress`` (Pa), or the largest principal stretch exceeds ``stretch``; one of the two."""

    body: str
    stress: float | None = None
    stretch: float | None = None
    name: str = "tear"
    point: np.ndarray | None = field(default=None, init=False)
    normal: np.ndarray | None = field(default=None, init=False)
    corners: np.ndarray | None = field(default=None, init=False)  # the crack polygon so far

    def __post_init__(self) -> None:
        given = [v for v in (self.stress, self.stretch) if v is not None]
        if len(given) != 1:
            raise InputError(
                f"tearing of body {self.body!r}: give stress (Pa, the strength: the largest "
                "principal Cauchy stress it bears) or stretch (the largest principal stretch), "
                "one of the two"
            )
        value = float(given[0])
        low = 0.0 if self.stress is not None else 1.0
        if not np.isfinite(value) or value <= low:
            what = "stress must be > 0 Pa" if self.stress is not None else "stretch must be > 1"
            raise InputError(f"tearing of body {self.body!r}: {what}, not {value:g}")

    @property
    def threshold(self) -> float:
        return float(self.stress if self.stress is not None else self.stretch)

    def measure(self, body, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(per element of the body's current mesh: its largest principal stress or stretch,
        the principal direction (m, 3)) where the body is (configuration c)."""
        if self.stress is not None:
            sigma = body.cell_fields(c)["cauchy_stress"]
            w, v = np.linalg.eigh(0.5 * (sigma + np.swapaxes(sigma, 1, 2)))
            return w[:, -1], v[:, :, -1]
        F = body.model.kinematics.deformation_gradients(c)
        F = body.model.kinematics.cell_average(F)
        w, v = np.linalg.eigh(F @ np.swapaxes(F, 1, 2))  # left Cauchy-Green: spatial axes
        return np.sqrt(np.maximum(w[:, -1], 0.0)), v[:, :, -1]

    def grow(self, body, c: np.ndarray) -> PlanarCut | None:
        """The crack after this step (None while nothing exceeds the threshold), from the body's
        configuration c (its current mesh)."""
        value, direction = self.measure(body, c)
        over = value >= self.threshold
        if not over.any():
            return None
        mesh = body.mesh
        x = c.reshape(-1, mesh.dim)
        x = np.column_stack([x, np.zeros(len(x))]) if mesh.dim == 2 else x
        X = x[mesh.cells]  # (m, k, 3) where each element's vertices are
        if self.point is None:
            worst = int(np.argmax(value / self.threshold))
            self.point = X[worst].mean(axis=0)
            n = direction[worst]
            n = np.concatenate([n, [0.0]]) if n.size == 2 else n
            self.normal = n / np.linalg.norm(n)
        d = (X - self.point) @ self.normal
        crossed = over & (d.max(axis=1) > 0.0) & (d.min(axis=1) < 0.0)
        if not crossed.any():
            return None
        k = mesh.cells.shape[1]
        i, j = np.triu_indices(k, 1)
        di, dj = d[crossed][:, i], d[crossed][:, j]
        hit = di * dj < 0.0
        t = np.where(hit, di / np.where(hit, di - dj, 1.0), 0.0)
        P = X[crossed][:, i] + t[..., None] * (X[crossed][:, j] - X[crossed][:, i])
        points = P[hit]
        if mesh.dim == 2:  # a 2D body's crack is a line: the cut's polygon spans it in z
            span = np.array([0.0, 0.0, float(np.ptp(x, axis=0).max())])
            points = np.concatenate([points + span, points - span])
        if self.corners is not None:
            points = np.concatenate([points, self.corners])
        crack = PlanarCut.hull(points, self.point.copy(), self.normal.copy())
        if crack is not None:
            self.corners = crack.polygon
        return crack
