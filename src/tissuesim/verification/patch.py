"""Patch tests: a linear displacement field u = A X prescribed on a patch's boundary is
reproduced exactly inside it (a homogeneous F = I + A is in equilibrium for any law, and the
elements contain linear fields), on P1 and P2 tetrahedra and Q1 hexahedra, the P1 and Q1
patches with their interior node moved off the regular grid."""

from __future__ import annotations

import numpy as np

import tissuesim as ts
from tissuesim.solve.newton import NewtonOptions
from tissuesim.verification.result import Check

__all__ = ["checks", "patch_error"]

A = np.array([[0.10, 0.03, -0.02], [0.01, -0.05, 0.04], [-0.03, 0.02, 0.08]])
TOL = 1e-8


def _patch(kind: str) -> ts.Mesh:
    if kind == "P2 tetrahedra":
        return ts.box(divisions=(2, 2, 2), order=2)
    mesh = ts.box(divisions=(2, 2, 2), element="hex" if kind == "Q1 hexahedra" else "tet")
    points = mesh.points.copy()
    centre = np.flatnonzero(np.all(np.isclose(points, 0.5), axis=1))
    points[centre] += [0.07, -0.05, 0.04]  # an irregular patch
    return ts.Mesh(points, mesh.cells)


def patch_error(kind: str) -> float:
    """The largest error of the interior nodes against X + A X, relative to |A X|."""
    mesh = _patch(kind)
    law = ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3)
    newton = NewtonOptions(gradient_tolerance=1e-12, absolute_tolerance=1e-14)
    sim = ts.Simulation(mesh, law, integrator="quasistatic", time_step=1.0, newton=newton)
    boundary = ts.select.boundary_vertices(mesh)
    sim.add_dirichlet(boundary, lambda X, t: t * X @ A.T)
    sim.step()
    X = mesh.points
    x = sim.state.x.reshape(X.shape)
    inside = np.setdiff1d(np.arange(len(X)), boundary)
    exact = X + X @ A.T
    return float(np.abs(x[inside] - exact[inside]).max() / np.abs(X @ A.T).max())


def checks() -> list[Check]:
    """One check per element kind: the interior nodes' error (relative to the field, 1e-8)."""
    kinds = ("P1 tetrahedra", "P2 tetrahedra", "Q1 hexahedra")
    return [
        Check(f"patch test, {k}", "interior displacement error", 0.0, patch_error(k), TOL, True)
        for k in kinds
    ]
