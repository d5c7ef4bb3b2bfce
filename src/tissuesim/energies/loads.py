"""Dead loads: gravity, body forces and Neumann tractions as nodal forces f, energy -f . x.

Tractions h (force per unit rest length in 2D, per unit rest area in 3D) are given at the
vertices of boundary facets and interpolated linearly, so (notes, eq. 6b)
    f^a = sum_b (int_facet N^a N^b) h^b,  int N^a N^b = A (1 + delta_ab) / (d (d + 1))
for a facet of measure A with d vertices. Body forces b (force per unit rest volume) are
integrated the same way over the elements with the unit-density consistent mass matrix.
Quad faces of hexahedra interpolate h bilinearly (``quad_traction_nodal_forces``), those of
quadratic hexahedra with their quad8 / quad9 shape functions.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError
from tissuesim.mesh.queries.boundary import facet_measures

__all__ = [
    "ExternalForce",
    "Gravity",
    "BodyForce",
    "Traction",
    "NodalForces",
    "traction_nodal_forces",
    "as_field",
]


@dataclass(frozen=True, eq=False)
class ExternalForce:
    """Potential of a dead load: E(x) = -f . x, gradient -f, no Hessian."""

    force: np.ndarray  # (n_dofs,) N

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        acc.add_value("external", -float(self.force @ x))
        if acc.order >= 1:
            acc.gradient -= self.force


def traction_nodal_forces(
    points: np.ndarray, facets: np.ndarray, traction_at_vertices: np.ndarray
) -> np.ndarray:
    """Nodal forces (n, d) of a traction given per facet vertex (k, d, d) [facet, vertex, comp]."""
    n, d = points.shape
    area = facet_measures(points, facets)  # (k,)
    ref = (np.ones((d, d)) + np.eye(d)) / (d * (d + 1))
    local = area[:, None, None] * np.einsum("ab,kbi->kai", ref, traction_at_vertices)
    out = np.zeros((n, d))
    for i in range(d):  # d components, not a loop over facets
        out[:, i] = np.bincount(facets.ravel(), weights=local[:, :, i].ravel(), minlength=n)
    return out


def quadratic_traction_nodal_forces(
    points: np.ndarray, facets: np.ndarray, traction_at_nodes: np.ndarray
) -> np.ndarray:
    """Nodal forces (n, d) of a traction on quadratic facets (k, 3 or 6), given at the facet's
    nodes (k, nf, d) and interpolated quadratically: f^a = int N^a N^b dA h^b, by a degree-5
    rule on the (possibly curved) facet, dA = |dX/dxi| (2D) or |dX/dxi_1 x dX/dxi_2| (3D)."""
    from tissuesim.mesh.cells.reference import facet_quadrature, shape_functions

    n, d = points.shape
    xi, w = facet_quadrature(d, 5)
    N, dN = shape_functions(d - 1, 2, xi)  # (q, nf), (q, nf, d-1)
    T = np.einsum("kai,qaj->kqij", points[facets], dN)  # (k, q, d, d-1) tangents
    if d == 2:
        dA = np.linalg.norm(T[..., 0], axis=-1)
    else:
        dA = np.linalg.norm(np.cross(T[..., 0], T[..., 1]), axis=-1)
    hq = np.einsum("qb,kbi->kqi", N, traction_at_nodes)  # traction at the points
    local = np.einsum("q,kq,qa,kqi->kai", w, dA, N, hq)
    out = np.zeros((n, d))
    for i in range(d):  # d components, not a loop over facets
        out[:, i] = np.bincount(facets.ravel(), weights=local[:, :, i].ravel(), minlength=n)
    return out


def quad_traction_nodal_forces(
    points: np.ndarray, faces: np.ndarray, traction_at_nodes: np.ndarray
) -> np.ndarray:
    """Nodal forces (n, 3) of a traction on quad faces (k, 4) of hexahedra, given at the faces'
    nodes (k, 4, 3) and interpolated bilinearly: f^a = int N^a N^b dA h^b with
    dA = |dX/dxi_1 x dX/dxi_2| dxi, by 3 x 3 Gauss points (exact on a flat parallelogram, where
    dA is constant and N^a N^b of degree 2 per variable). Faces of quadratic hexahedra
    (k, 8) / (k, 9) (``tensor_quadratic.local_facets`` order) interpolate it with the quad8 /
    quad9 shape functions, by the same rule (N^a N^b of degree 4 per variable: still exact on
    a flat parallelogram)."""
    from tissuesim.mesh.cells.tensor import gauss_rule, shape_functions

    n = points.shape[0]
    xi, w = gauss_rule(2, 3)
    if faces.shape[1] == 4:
        N, dN = shape_functions(2, xi)  # (q, 4), (q, 4, 2)
    else:
        from tissuesim.mesh.cells import tensor_quadratic as tq

        N, dN = tq.shape_functions(tq.CELL_TYPES[2, faces.shape[1]], xi)
    T = np.einsum("kai,qaj->kqij", points[faces], dN)  # (k, q, 3, 2) tangents
    dA = np.linalg.norm(np.cross(T[..., 0], T[..., 1]), axis=-1)
    hq = np.einsum("qb,kbi->kqi", N, traction_at_nodes)
    local = np.einsum("q,kq,qa,kqi->kai", w, dA, N, hq)
    out = np.zeros((n, 3))
    for i in range(3):  # 3 components, not a loop over faces
        out[:, i] = np.bincount(faces.ravel(), weights=local[:, :, i].ravel(), minlength=n)
    return out


ForceField = Callable[[np.ndarray, float], np.ndarray]


def as_field(value, what: str = "load", dim: int | None = None) -> ForceField:
    """A constant vector (finite, ``dim`` entries) or a callable (X (k, d), t) -> (k, d) as a
    callable (callables are checked where they are evaluated, ``Model.external_force``)."""
    if callable(value):
        return value
    from tissuesim.validate import vector

    v = vector(value, what, dim if dim is not None else (2, 3))

    def field(X: np.ndarray, t: float) -> np.ndarray:
        return np.broadcast_to(v, X.shape)

    return field


@dataclass(frozen=True, eq=False)
class Gravity:
    """Weight rho g per unit volume: nodal forces int rho N^a g, the consistent mass's row sums
    times g; with a lumped mass the lumped masses times g (the same for P1; for P2 the HRZ
    masses, so that a lumped body falls freely without deforming)."""

    acceleration: np.ndarray  # (d,) m/s^2

    def nodal_forces(self, model, t: float) -> np.ndarray:
        d = model.mesh.dim
        mass = model.mass.lumped if model.mass.kind == "lumped" else model.mass.row_sums
        return mass.reshape(-1, d) * np.asarray(self.acceleration, dtype=float)


@dataclass(frozen=True, eq=False)
class BodyForce:
    """Force per unit rest volume b(X, t), interpolated from the vertices (notes, eq. 9)."""

    force_density: ForceField

    def nodal_forces(self, model, t: float) -> np.ndarray:
        b = np.asarray(self.force_density(model.mesh.points, t), dtype=float)
        b = np.broadcast_to(b, model.mesh.points.shape).ravel()
        return model.unit_mass().dot(b).reshape(model.mesh.points.shape)


@dataclass(frozen=True, eq=False)
class Traction:
    """Neumann traction h(X, t) (N/m in 2D, Pa in 3D) on boundary facets (k, d) ((k, 4) quad
    faces of hexahedra, interpolated bilinearly)."""

    facets: np.ndarray
    traction: ForceField

    def nodal_forces(self, model, t: float) -> np.ndarray:
        mesh = model.mesh
        facets = self.facets
        if mesh.order == 2:
            from tissuesim.mesh.cells.quadratic import quadratic_facets

            facets = quadratic_facets(mesh, facets)
        X = mesh.points[facets]  # (k, nf, d) [facet, node, coord]
        h = np.asarray(self.traction(X.reshape(-1, X.shape[-1]), t), dtype=float)
        h = np.broadcast_to(h, (X.shape[0] * X.shape[1], X.shape[2])).reshape(X.shape)
        if mesh.order == 2 and mesh.dim == 3 and not mesh.simplicial:  # quad8 / quad9 faces
            return quad_traction_nodal_forces(mesh.points, facets, h)
        if mesh.order == 2:  # also the 3-node edges of quad8 / quad9 cells
            return quadratic_traction_nodal_forces(mesh.points, facets, h)
        if facets.shape[1] == 4 and mesh.dim == 3:  # quad faces of hexahedra
            return quad_traction_nodal_forces(mesh.points, facets, h)
        return traction_nodal_forces(mesh.points, facets, h)


@dataclass(frozen=True, eq=False)
class NodalForces:
    """Point forces (N) on vertices (k,): ``force(t)`` -> (k, d) or (d,) per vertex."""

    vertices: np.ndarray
    force: Callable[[float], np.ndarray]

    def nodal_forces(self, model, t: float) -> np.ndarray:
        f = np.broadcast_to(
            np.asarray(self.force(t), dtype=float), (self.vertices.size, model.mesh.dim)
        )
        if not np.all(np.isfinite(f)):
            raise InputError(f"a nodal force is not finite at t = {t:g} s")
        out = np.zeros(model.mesh.points.shape)
        np.add.at(out, self.vertices, f)
        return out
