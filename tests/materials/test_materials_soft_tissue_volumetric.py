"""The soft-tissue laws' volumetric part (k/2 (ln J)^2, cp/2 (J - 1)^2) for the mean-dilatation
formulation: it is exactly the k-dependent part of the energy, and the mean-dilatation energy's
gradient and Hessian match finite differences on tetrahedra."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.errors import MaterialError
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


UNCOUPLED = ["mooney_rivlin", "ogden", "yeoh", "veronda_westmann", "arruda_boyce"]
#: FEBio's pressure_model -> U(J) / k, by hand
BULK = {
    "default": lambda J: 0.5 * np.log(J) ** 2,
    "NIKE3D": lambda J: 0.25 * (J**2 - 2 * np.log(J) - 1),
    "Abaqus": lambda J: 0.5 * (J - 1) ** 2,
    "Abaqus (GOH)": lambda J: 0.5 * ((J**2 - 1) / 2 - np.log(J)),
}


@pytest.mark.parametrize("name", UNCOUPLED)
@pytest.mark.parametrize("model", sorted(BULK))
def test_febio_pressure_models(name, model):
    k = 4000.0
    base = make_material(name, **PARAMS[name], k=k)
    law = make_material(name, **PARAMS[name], k=k, pressure_model=model)
    rng = np.random.default_rng(8)
    F = np.eye(3) + 0.3 * rng.standard_normal((12, 3, 3))
    F = F[np.linalg.det(F) > 0.3]
    J = np.linalg.det(F)
    # only the bulk term changes
    expected = base.energy_density(F) + k * (BULK[model](J) - BULK["default"](J))
    np.testing.assert_allclose(law.energy_density(F), expected, rtol=1e-11)
    # consistent derivatives, the same small-strain moduli, stress-free at rest
    res = law.evaluate(F, 2)
    h = 1e-6
    for i, j in ((0, 0), (1, 2), (2, 1)):
        E = np.zeros((3, 3))
        E[i, j] = h
        fd = (law.energy_density(F + E) - law.energy_density(F - E)) / (2 * h)
        np.testing.assert_allclose(res.stress[:, i, j], fd, rtol=1e-6, atol=1e-6 * k)
        fd = (law.stress(F + E) - law.stress(F - E)) / (2 * h)
        np.testing.assert_allclose(res.tangent[:, :, :, i, j], fd, rtol=1e-6, atol=1e-6 * k)
    assert (law.mu, law.lam) == pytest.approx((base.mu, base.lam), rel=1e-14)
    assert np.abs(law.stress(np.eye(3)[None])).max() < 1e-12 * k
    # by its integer too, the parameters give it back, and mean dilatation averages that term
    same = make_material(name, **law.parameters())
    np.testing.assert_allclose(same.energy_density(F), law.energy_density(F), rtol=1e-15)
    index = ["default", "NIKE3D", "Abaqus", "Abaqus (GOH)"].index(model)
    by_int = make_material(name, **PARAMS[name], k=k, pressure_model=index)
    np.testing.assert_allclose(by_int.energy_density(F), law.energy_density(F), rtol=1e-15)
    part = volumetric_part(law)
    U = part.energy(J, 0)[0]
    np.testing.assert_allclose(U, k * BULK[model](J), rtol=1e-12, atol=1e-12 * k)


def test_pressure_model_errors():
    with pytest.raises(MaterialError, match="pressure_model must be one of"):
        make_material("mooney_rivlin", c1=1.0, k=10.0, pressure_model="abaqus-ish")
    with pytest.raises(MaterialError, match="pressure_model must be one of"):
        make_material("ogden", c=[1.0], m=[2.0], k=10.0, pressure_model=4)
    with pytest.raises(MaterialError, match="coupled_yeoh has no pressure_model"):
        make_material("coupled_yeoh", c1=1.0, k=10.0, pressure_model="Abaqus")
    with pytest.raises(MaterialError, match="unknown parameter 'pressure_model'"):
        make_material("coupled_mooney_rivlin", c1=1.0, k=10.0, pressure_model="Abaqus")


# FEBio's Holmes-Mow laws (issue 42), whose volumetric parts test_materials_febio_laws.py
# checks (the coupled one has none: U = 0)
PARAMS.update(
    holmes_mow=dict(E=1000.0, v=0.3, beta=0.5), uncoupled_holmes_mow=dict(mu=300.0, beta=2.0)
)

# FEBio's Arruda-Boyce unconstrained (issue 42): its bulk term kappa/2 (J^2 - 1 - 2 ln J)
PARAMS["arruda_boyce_unconstrained"] = dict(ksi=300.0, N=4.0)

# FEBio's isotropic Hencky (issue 42): its bulk term lam/2 (ln J)^2
PARAMS["isotropic_hencky"] = dict(E=1000.0, v=0.3)
