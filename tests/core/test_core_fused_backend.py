"""The fused Numba assembly against the batched NumPy reference: point kernels, assembled
energy, gradient and Hessian, inverted elements, and which evaluations take which path."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.backend import numba_available, resolve_backend
from tissuesim.materials import MATERIALS
from tissuesim.materials.isotropic.neo_hookean import NeoHookean
from tissuesim.mesh import box, rectangle
from tissuesim.model import Model

needs_numba = pytest.mark.skipif(not numba_available(), reason="numba not installed")
FUSED_LAWS = ["neo_hookean", "course_neo_hookean", "stvk", "linear"]


def deformed(mesh, scale, seed=0):
    rng = np.random.default_rng(seed)
    return (mesh.points + scale * rng.standard_normal(mesh.points.shape)).ravel()


@pytest.fixture(params=[2, 3], ids=["2d", "3d"])
def mesh(request):
    if request.param == 2:
        return rectangle(lower=(0, 0), upper=(1, 0.8), divisions=(9, 7))
    return box(lower=(0, 0, 0), upper=(1, 0.7, 0.5), divisions=(4, 3, 2))


@needs_numba
@pytest.mark.parametrize("name", FUSED_LAWS)
@pytest.mark.parametrize("dim", [2, 3])
def test_point_kernels_equal_numpy_laws(name, dim):
    from tissuesim.materials.isotropic.point_kernels import KERNELS

    material = MATERIALS[name](youngs_modulus=800.0, poisson_ratio=0.35)
    rng = np.random.default_rng(dim)
    F = np.eye(dim) + 0.3 * rng.standard_normal((40, dim, dim))
    F = F[np.linalg.det(F) > 0.05]  # the log law is undefined for J <= 0
    ref = material.evaluate(F, 2)
    for q in range(F.shape[0]):
        P, A, W = np.zeros((dim, dim)), np.zeros((dim,) * 4), np.empty((2, dim, dim))
        psi = KERNELS[name](F[q], material.mu, material.lam, 2, P, A, W)
        np.testing.assert_allclose(psi, ref.energy[q], rtol=1e-12, atol=1e-12 * material.mu)
        np.testing.assert_allclose(P, ref.stress[q], rtol=1e-12, atol=1e-12 * material.mu)
        np.testing.assert_allclose(A, ref.tangent[q], rtol=1e-12, atol=1e-12 * material.mu)


@needs_numba
@pytest.mark.parametrize("name", FUSED_LAWS)
def test_fused_assembly_equals_numpy_assembly(mesh, name):
    material = MATERIALS[name](youngs_modulus=1000.0, poisson_ratio=0.3)
    fused = Model(mesh, material, 1.0, backend="numba")
    reference = Model(mesh, material, 1.0, backend="numpy")
    assert fused.elastic.fused and not reference.elastic.fused
    x = deformed(mesh, 0.02)
    for order in (0, 1, 2):
        a, b = fused.evaluate(x, order, False), reference.evaluate(x, order, False)
        assert a.value == pytest.approx(b.value, rel=1e-12)
        if order >= 1:
            scale = np.abs(b.gradient).max()
            np.testing.assert_allclose(a.gradient, b.gradient, rtol=0, atol=1e-12 * scale)
        if order == 2:
            scale = np.abs(b.hessian).max()
            np.testing.assert_allclose(a.hessian, b.hessian, rtol=0, atol=1e-12 * scale)


@needs_numba
def test_fused_inverted_element_gives_infinite_energy(mesh):
    material = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.3)
    fused = Model(mesh, material, 1.0, backend="numba")
    reference = Model(mesh, material, 1.0, backend="numpy")
    x = mesh.points.copy()
    v = mesh.cells[0, 0]
    x[v] = x[mesh.cells[0]].mean(axis=0) * 2 - x[v]  # push a vertex through its element
    x = x.ravel()
    for order in (0, 1, 2):
        assert fused.evaluate(x, order, False).value == np.inf
        assert reference.evaluate(x, order, False).value == np.inf


@needs_numba
def test_projection_and_unkernelled_laws_take_the_numpy_path(mesh):
    corotated = Model(mesh, MATERIALS["fixed_corotated"](youngs_modulus=1e3, poisson_ratio=0.3),
                      1.0, backend="numba")  # fmt: skip
    assert not corotated.elastic.fused

    class Stiffer(NeoHookean):  # overrides the law: the stock kernel must not be used
        def evaluate(self, F, order=2):
            r = super().evaluate(F, order)
            return type(r)(*(None if v is None else 2 * v for v in (r.energy, r.stress, r.tangent)))

    custom = Model(mesh, Stiffer(youngs_modulus=1e3, poisson_ratio=0.3), 1.0, backend="numba")
    plain = Model(mesh, NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), 1.0, backend="numba")
    assert not custom.elastic.fused and plain.elastic.fused
    x = deformed(mesh, 0.02, seed=4)
    doubled = 2 * plain.evaluate(x, 0, False).value
    assert custom.evaluate(x, 0, False).value == pytest.approx(doubled)
    # project=True: the per-point PSD projection lives in the NumPy path
    a = plain.evaluate(x, 2, True)
    b = Model(mesh, plain.material, 1.0, backend="numpy").evaluate(x, 2, True)
    np.testing.assert_allclose(a.hessian, b.hessian, rtol=0, atol=1e-12 * np.abs(b.hessian).max())


def test_backend_resolution(monkeypatch):
    monkeypatch.delenv("TISSUESIM_BACKEND", raising=False)
    assert resolve_backend("numpy") == ("numpy", "requested")
    name, reason = resolve_backend("auto")
    assert name == ("numba" if numba_available() else "numpy") and reason.startswith("auto")
    monkeypatch.setenv("TISSUESIM_BACKEND", "numpy")
    assert resolve_backend("auto") == ("numpy", "TISSUESIM_BACKEND")
    monkeypatch.setenv("TISSUESIM_BACKEND", "fortran")
    with pytest.raises(ValueError, match="TISSUESIM_BACKEND"):
        resolve_backend("auto")
    with pytest.raises(ValueError, match="backend must be one of"):
        resolve_backend("gpu")
    monkeypatch.setattr("tissuesim.backend.numba_available", lambda: False)
    with pytest.raises(ValueError, match=r"tissuesim\[fast\]"):
        resolve_backend("numba")


@needs_numba
def test_auto_keeps_small_meshes_on_numpy(monkeypatch):
    """Numba's fixed cost per run (0.4-0.5 s) takes over 250 evaluations to repay on a small mesh
    (benchmarks/backend_threshold.py): "auto" takes NumPy there, Numba from the threshold."""
    from tissuesim.backend import SMALL_MESH_CELLS

    monkeypatch.delenv("TISSUESIM_BACKEND", raising=False)
    for dim, limit in SMALL_MESH_CELLS.items():
        name, reason = resolve_backend("auto", limit - 1, dim)
        assert name == "numpy" and "small mesh" in reason
        assert resolve_backend("auto", limit, dim)[0] == "numba"
        assert resolve_backend("numba", 1, dim) == ("numba", "requested")
    small = Model(
        rectangle((0, 0), (1, 1), (4, 4)), NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), 1.0
    )
    assert small.backend == "numpy"
    large = Model(
        rectangle((0, 0), (1, 1), (30, 30)), NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), 1.0
    )
    assert large.backend == "numba"
    monkeypatch.setenv("TISSUESIM_BACKEND", "numba")
    assert Model(
        rectangle((0, 0), (1, 1), (4, 4)), NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), 1.0
    ).backend == ("numba")


@needs_numba
def test_fused_jacobians_equal_numpy_determinants(mesh):
    material = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.3)
    fused = Model(mesh, material, 1.0, backend="numba")
    x = deformed(mesh, 0.05, seed=2)
    F = fused.kinematics.deformation_gradients(x)
    np.testing.assert_allclose(fused.elastic.jacobians(x), np.linalg.det(F), rtol=1e-12)
    reference = Model(mesh, material, 1.0, backend="numpy")
    np.testing.assert_allclose(reference.elastic.jacobians(x), np.linalg.det(F), rtol=1e-12)
