"""Assembled energy, gradient and Hessian against central finite differences, on a small
mesh, for every material, in 2D and 3D; Hessian symmetry; the scatter pattern itself."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.backend import numba_available
from tissuesim.energies.mass import Inertia
from tissuesim.materials import MATERIALS
from tissuesim.model import Model

#: the soft-tissue laws take their own (FEBio) parameters; the others (E, nu)
SOFT_TISSUE_PARAMETERS = {
    "trans_iso_veronda_westmann": dict(
        c1=200.0, c2=1.5, c3=10.0, c4=5.0, c5=300.0, lam_max=1.1, k=3e3
    ),
    "coupled_trans_iso_mooney_rivlin": dict(
        c1=150.0, c3=10.0, c4=5.0, c5=300.0, lam_max=1.1, k=3e3
    ),
    "tc_nonlinear_orthotropic": dict(
        c1=150.0, beta=[3.0, 3.0, 4.0], ksi=[300.0, 200.0, 100.0], k=3e3
    ),
    "orthotropic_elastic": dict(
        E1=1000.0, E2=2000.0, E3=3000.0, G12=600.0, G23=400.0, G31=500.0, v12=0.3, v23=0.2, v31=0.25
    ),
    "fung_orthotropic": dict(
        E1=1000.0,
        E2=2000.0,
        E3=3000.0,
        G12=600.0,
        G23=400.0,
        G31=500.0,
        v12=0.3,
        v23=0.2,
        v31=0.25,
        c=1500.0,
        k=3e3,
    ),
    "fung_ortho_compressible": dict(
        E1=1000.0,
        E2=2000.0,
        E3=3000.0,
        G12=600.0,
        G23=400.0,
        G31=500.0,
        v12=0.3,
        v23=0.2,
        v31=0.25,
        c=1500.0,
        k=3e3,
    ),
    "holmes_mow": dict(E=1000.0, v=0.3, beta=0.5),
    "uncoupled_holmes_mow": dict(mu=300.0, beta=2.0, k=3e3),
    "arruda_boyce_unconstrained": dict(ksi=300.0, N=4.0, kappa=1500.0),
    "isotropic_hencky": dict(E=1000.0, v=0.3),
    "mooney_rivlin": dict(c1=150.0, c2=40.0, k=3000.0),
    "coupled_mooney_rivlin": dict(c1=150.0, c2=40.0, k=3000.0),
    "ogden": dict(c=[300.0, -40.0], m=[4.0, -2.0], k=3000.0),
    "ogden_unconstrained": dict(c=[300.0, -40.0], m=[4.0, -2.0], cp=3000.0),
    "yeoh": dict(c1=150.0, c2=30.0, c3=5.0, k=3000.0),
    "coupled_yeoh": dict(c1=150.0, c2=30.0, c3=5.0, k=3000.0),
    "veronda_westmann": dict(c1=200.0, c2=1.5, k=3000.0),
    "coupled_veronda_westmann": dict(c1=200.0, c2=1.5, k=3000.0),
    "arruda_boyce": dict(mu=300.0, N=4.0, k=3000.0),
    "coupled_arruda_boyce": dict(mu=300.0, N=4.0, k=3000.0),
    "holzapfel_gasser_ogden": dict(c=150.0, k1=200.0, k2=2.0, kappa=0.1, gamma=30.0, k=3000.0),
    "hgo_unconstrained": dict(c=150.0, k1=200.0, k2=2.0, kappa=0.1, gamma=30.0, k=3000.0),
    "trans_iso_mooney_rivlin": dict(c1=150.0, c3=10.0, c4=5.0, c5=300.0, lam_max=1.1, k=3e3),
    # FEBio's fibre laws alone (a mixture's components): beta = 3 keeps the Hessian continuous
    # where the fibre goes slack
    "fiber_exp_pow": dict(ksi=500.0, alpha=2.0, beta=3.0, mu=50.0),
    "fiber_exp_pow_uncoupled": dict(ksi=500.0, alpha=2.0, beta=3.0, mu=50.0),
    "fiber_pow_linear": dict(E=1000.0, lam0=1.1, beta=3.0),
    "fiber_pow_linear_uncoupled": dict(E=1000.0, lam0=1.1, beta=3.0),
    "fiber_exp_linear": dict(c3=10.0, c4=5.0, c5=300.0, lam_max=1.1),
    "fiber_exp_linear_uncoupled": dict(c3=10.0, c4=5.0, c5=300.0, lam_max=1.1),
}


def make_law(name):
    if name in SOFT_TISSUE_PARAMETERS:
        return MATERIALS[name](**SOFT_TISSUE_PARAMETERS[name])
    return MATERIALS[name](youngs_modulus=1000.0, poisson_ratio=0.3)


def perturbed_positions(mesh, scale=0.15, seed=0):
    rng = np.random.default_rng(seed)
    return (mesh.points + scale * 0.3 * rng.standard_normal(mesh.points.shape)).ravel()


def fd_gradient(f, x, eps=1e-6):
    g = np.zeros_like(x)
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = eps
        g[i] = (f(x + e) - f(x - e)) / (2 * eps)
    return g


BACKENDS = [
    "numpy",
    pytest.param(
        "numba", marks=pytest.mark.skipif(not numba_available(), reason="numba not installed")
    ),
]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_gradient_and_hessian_match_finite_differences(small_mesh, name, backend):
    material = make_law(name)
    model = Model(small_mesh, material, density=2.0, backend=backend)
    x = perturbed_positions(small_mesh, 0.1)
    x_pred = x + 0.01
    energies = (Inertia(model.mass, x_pred, 0.05),)

    def value(y):
        return model.evaluate(y, 0, False, energies).value

    acc = model.evaluate(x, 2, False, energies)
    g_fd = fd_gradient(value, x)
    scale = np.abs(acc.gradient).max()
    np.testing.assert_allclose(acc.gradient, g_fd, atol=1e-6 * scale)

    H = model.pattern.matrix(acc.hessian).toarray()
    H_fd = np.stack(
        [
            fd_gradient(lambda y, i=i: model.evaluate(y, 1, False, energies).gradient[i], x)
            for i in range(x.size)
        ]
    )
    np.testing.assert_allclose(H, H_fd, atol=1e-6 * np.abs(H).max())
    np.testing.assert_allclose(H, H.T, atol=1e-10 * np.abs(H).max())


def test_projected_hessian_is_positive_semidefinite(small_mesh):
    model = Model(
        small_mesh, MATERIALS["course_neo_hookean"](youngs_modulus=1e3, poisson_ratio=0.3), 1.0
    )
    rng = np.random.default_rng(3)
    x = (small_mesh.points + 0.4 * rng.standard_normal(small_mesh.points.shape)).ravel()
    exact = model.pattern.matrix(model.evaluate(x, 2, False).hessian).toarray()
    projected = model.pattern.matrix(model.evaluate(x, 2, True).hessian).toarray()
    assert np.linalg.eigvalsh(exact).min() < -1e-6  # the test point is really indefinite
    assert np.linalg.eigvalsh(projected).min() > -1e-9 * np.abs(projected).max()


def test_pattern_scatter_equals_coo_assembly():
    rng = np.random.default_rng(1)
    stencil = rng.integers(0, 12, size=(7, 4))
    stencil = np.array([rng.permutation(12)[:4] for _ in range(7)])
    pattern = SparsityPattern.from_stencils(12, [stencil])
    blocks = rng.standard_normal((7, 4, 4))
    data = np.zeros(pattern.nnz)
    pattern.accumulate(data, 0, blocks)
    rows = np.repeat(stencil, 4, axis=1).ravel()
    cols = np.tile(stencil, (1, 4)).ravel()
    reference = sp.coo_matrix((blocks.ravel(), (rows, cols)), shape=(12, 12)).toarray()
    np.testing.assert_allclose(pattern.matrix(data).toarray(), reference)
    assert np.all(
        pattern.matrix(np.arange(pattern.nnz, dtype=float)).diagonal() == pattern.diagonal
    )
