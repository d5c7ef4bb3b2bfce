"""The soft-tissue laws' volumetric part (k/2 (ln J)^2, cp/2 (J - 1)^2) for the mean-dilatation
formulation: it is exactly the k-dependent part of the energy, and the mean-dilatation energy's
gradient and Hessian match finite differences on tetrahedra."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.materials import SOFT_TISSUE_LAWS, make_material
from tissuesim.materials.volumetric import VOLUMETRIC_LAWS, volumetric_part
from tissuesim.mesh import box, rectangle
from tissuesim.model import Model

PARAMS = {
    "mooney_rivlin": dict(c1=150.0, c2=40.0),
    "coupled_mooney_rivlin": dict(c1=150.0, c2=40.0),
    "ogden": dict(c=[300.0, -40.0], m=[4.0, -2.0]),
    "ogden_unconstrained": dict(c=[300.0, -40.0], m=[4.0, -2.0]),
    "yeoh": dict(c1=150.0, c2=30.0, c3=5.0),
    "coupled_yeoh": dict(c1=150.0, c2=30.0, c3=5.0),
    "veronda_westmann": dict(c1=200.0, c2=1.5),
    "coupled_veronda_westmann": dict(c1=200.0, c2=1.5),
    "arruda_boyce": dict(mu=300.0, N=4.0),
    "coupled_arruda_boyce": dict(mu=300.0, N=4.0),
}


def law(name, bulk):
    key = "cp" if name == "ogden_unconstrained" else "k"
    return make_material(name, **PARAMS[name], **{key: bulk})


def test_every_soft_tissue_law_has_a_volumetric_part():
    assert {cls.name for cls in SOFT_TISSUE_LAWS} == set(PARAMS) <= set(VOLUMETRIC_LAWS)


@pytest.mark.parametrize("name", sorted(PARAMS))
def test_the_volumetric_part_is_the_bulk_term(name):
    """psi(k1) - psi(k2) = U_k1(J) - U_k2(J): U holds every k-dependent term, psi - U none."""
    rng = np.random.default_rng(3)
    F = np.eye(3) + 0.3 * rng.standard_normal((20, 3, 3))
    F = F[np.linalg.det(F) > 0.3]
    a, b = law(name, 2000.0), law(name, 9000.0)
    Ua, Ub = volumetric_part(a), volumetric_part(b)
    assert Ua.lam == 2000.0 and Ub.lam == 9000.0
    theta = Ua.theta(F, 0)[0]
    diff = a.energy_density(F) - b.energy_density(F)
    expected = Ua.energy(theta, 0)[0] - Ub.energy(theta, 0)[0]
    np.testing.assert_allclose(diff, expected, rtol=1e-10, atol=1e-9)


@pytest.mark.parametrize("name", ["mooney_rivlin", "ogden", "coupled_yeoh", "ogden_unconstrained"])
@pytest.mark.parametrize("mesh", ["tri3", "tet4", "tet10"])
def test_mean_dilatation_energy_matches_finite_differences(name, mesh):
    mesh = {
        "tri3": lambda: rectangle(divisions=(3, 2)),
        "tet4": lambda: box(divisions=(2, 1, 1)),
        "tet10": lambda: box(divisions=(1, 1, 1), order=2),
    }[mesh]()
    md = Model(
        mesh, law(name, 5e4), np.ones(mesh.n_cells), backend="numpy", formulation="mean_dilatation"
    )
    rng = np.random.default_rng(11)
    x = mesh.points.ravel() + 0.03 * rng.standard_normal(mesh.points.size)
    acc = md.evaluate(x, 2, False)
    H = md.pattern.matrix(acc.hessian)
    dx = rng.standard_normal(x.size)
    eps = 1e-6
    plus, minus = md.evaluate(x + eps * dx, 1, False), md.evaluate(x - eps * dx, 1, False)
    assert (plus.value - minus.value) / (2 * eps) == pytest.approx(acc.gradient @ dx, rel=1e-6)
    fd_H = (plus.gradient - minus.gradient) / (2 * eps)
    np.testing.assert_allclose(fd_H, H @ dx, rtol=0, atol=1e-6 * np.abs(H @ dx).max())
