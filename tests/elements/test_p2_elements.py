"""P2 triangles and tetrahedra: kinematics, derivatives, both backends, mass, loads."""

import numpy as np
import pytest

from tissuesim.backend import numba_available
from tissuesim.materials.registry import make_material
from tissuesim.mesh import box, ellipsoid, rectangle
from tissuesim.mesh.checks import validate_mesh
from tissuesim.model import Model

LAWS = ("neo_hookean", "course_neo_hookean", "fixed_corotated", "linear", "stvk")


def curved(mesh, amount=0.05):
    """The mesh with its interior midside nodes moved off their edges (curved elements)."""
    from tissuesim.mesh.queries.select import boundary_vertices

    p = mesh.points.copy()
    d = mesh.dim
    mids = np.setdiff1d(np.unique(mesh.cells[:, d + 1 :]), boundary_vertices(mesh))
    rng = np.random.default_rng(3)
    h = np.linalg.norm(np.ptp(p, axis=0)) / 10
    p[mids] += amount * h * rng.standard_normal((mids.size, d))
    return validate_mesh(p, mesh.cells, source="curved")


MESHES = {
    "tri6": lambda: rectangle(divisions=(3, 2), order=2),
    "tri6_curved": lambda: curved(rectangle(divisions=(3, 3), order=2)),
    "tet10": lambda: box(divisions=(2, 1, 1), order=2),
    "tet10_curved": lambda: curved(box(divisions=(2, 2, 2), order=2)),
}


def model(mesh, law="neo_hookean", backend="numpy", formulation="displacement", nu=0.3):
    mat = make_material(law, youngs_modulus=1e3, poisson_ratio=nu)
    return Model(mesh, mat, np.full(mesh.n_cells, 2.0), backend=backend, formulation=formulation)


@pytest.mark.parametrize("name", MESHES)
def test_p2_reproduces_quadratic_fields_exactly(name):
    mesh = MESHES[name]()
    md = model(mesh)
    K = md.kinematics
    X = mesh.points
    d = mesh.dim
    A = np.eye(d) + 0.1 * np.arange(d * d).reshape(d, d) / d**2
    Q = 0.05 * np.ones((d, d, d))
    x = X @ A.T + np.einsum("ijk,nj,nk->ni", Q, X, X)
    F = K.deformation_gradients(x.ravel())
    # exact gradient at the quadrature points: A + 2 Q X (Q symmetric in j, k)
    from tissuesim.mesh.cells.reference import quadrature, shape_functions

    xi, _ = quadrature(d, 2)
    N, _ = shape_functions(d, 2, xi)
    Xq = np.einsum("qa,mai->mqi", N, X[mesh.cells]).reshape(-1, d)
    exact = A[None] + 2.0 * np.einsum("ijk,qk->qij", Q, Xq)
    if "curved" in name:
        # a curved element's map is quadratic: the field is no longer quadratic in xi; only
        # linear fields stay exact
        x = X @ A.T
        exact = np.broadcast_to(A, F.shape)
        F = K.deformation_gradients(x.ravel())
    np.testing.assert_allclose(F, exact, atol=1e-12)
    # the weights sum to the measure of the domain (det J of a curved tetrahedron is cubic in
    # xi, beyond the degree-2 rule: close, not exact)
    rel = 1e-5 if name == "tet10_curved" else 1e-12
    assert K.weights.sum() == pytest.approx(np.prod(np.ptp(X, axis=0)), rel=rel)


@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("formulation", ["displacement", "mean_dilatation"])
def test_p2_energy_gradient_hessian_match_finite_differences(name, law, formulation):
    mesh = MESHES[name]()
    md = model(mesh, law, formulation=formulation, nu=0.45)
    rng = np.random.default_rng(7)
    x = mesh.points.ravel() + 0.02 * rng.standard_normal(mesh.points.size)
    acc = md.evaluate(x, 2, False)
    H = md.pattern.matrix(acc.hessian)
    dx = rng.standard_normal(x.size)
    eps = 1e-6
    e_plus = md.evaluate(x + eps * dx, 1, False)
    e_minus = md.evaluate(x - eps * dx, 1, False)
    fd_g = (e_plus.value - e_minus.value) / (2 * eps)
    assert fd_g == pytest.approx(acc.gradient @ dx, rel=1e-6)
    fd_H = (e_plus.gradient - e_minus.gradient) / (2 * eps)
    np.testing.assert_allclose(fd_H, H @ dx, rtol=0, atol=1e-6 * np.abs(H @ dx).max())
    assert abs(H - H.T).max() <= 1e-12 * abs(H).max()


@pytest.mark.skipif(not numba_available(), reason="numba not installed")
@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("law", LAWS)
def test_p2_fused_numba_equals_numpy(name, law):
    mesh = MESHES[name]()
    rng = np.random.default_rng(2)
    x = mesh.points.ravel() + 0.02 * rng.standard_normal(mesh.points.size)
    a = model(mesh, law, "numpy").evaluate(x, 2, False)
    from tissuesim.materials.isotropic.point_kernels import LAW_IDS

    fused = model(mesh, law, "numba")
    assert fused.elastic.fused == (law in LAW_IDS)  # fixed_corotated has no point kernel
    b = fused.evaluate(x, 2, False)
    assert b.value == pytest.approx(a.value, rel=1e-12)
    np.testing.assert_allclose(b.gradient, a.gradient, atol=1e-11 * abs(a.gradient).max())
    np.testing.assert_allclose(b.hessian, a.hessian, atol=1e-11 * abs(a.hessian).max())


@pytest.mark.parametrize("name", MESHES)
def test_p2_mass_consistent_lumped_and_gravity(name):
    mesh = MESHES[name]()
    md = model(mesh)
    d = mesh.dim
    volume = np.prod(np.ptp(mesh.points, axis=0))  # boundary nodes stay on the box
    M = md.mass.matrix()
    ones = np.zeros(mesh.points.size)
    ones[0::d] = 1.0
    assert ones @ M @ ones == pytest.approx(2.0 * volume, rel=1e-12)  # density 2
    # M integrates products of P2 fields exactly: int x * x dV on straight elements
    xx = np.zeros(mesh.points.size)
    xx[0::d] = mesh.points[:, 0]
    if "curved" not in name:
        lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
        exact = 2.0 * (hi[0] ** 3 - lo[0] ** 3) / 3 * np.prod((hi - lo)[1:])
        assert xx @ M @ xx == pytest.approx(exact, rel=1e-12)
    # consistent row sums: some corners negative (tet10) or zero (tri6); HRZ all positive
    assert md.mass.lumped.min() > 0
    assert md.mass.lumped.sum() == pytest.approx(d * 2.0 * volume, rel=1e-12)
    if d == 3:
        assert md.mass.row_sums.min() < 0
    lumped = model(mesh).__class__(mesh, md.material, md.density, "lumped", backend="numpy")
    np.testing.assert_allclose(lumped.mass.matrix().diagonal(), md.mass.lumped)
    # gravity: the weight, and its moment (the consistent row sums integrate N^a exactly)
    from tissuesim.energies.loads import Gravity

    g = np.zeros(d)
    g[-1] = -9.81
    f = Gravity(g).nodal_forces(md, 0.0)
    assert f[:, -1].sum() == pytest.approx(-9.81 * 2.0 * volume, rel=1e-12)


def test_p2_traction_integrates_force_and_moment():
    from tissuesim.energies.loads import Traction
    from tissuesim.mesh.queries.select import facets_on_plane

    for mesh in (rectangle(divisions=(3, 4), order=2), box(divisions=(2, 3, 2), order=2)):
        md = model(mesh)
        d = mesh.dim
        facets = facets_on_plane(mesh, 0, 1.0)
        t = np.zeros(d)
        t[1] = 5.0

        def linear(X, time):
            out = np.zeros_like(X)
            out[:, 1] = 5.0 * X[:, 1] ** 2  # quadratic along the face: integrated exactly
            return out

        f = Traction(facets, linear).nodal_forces(md, 0.0)
        area = 1.0  # the face x = 1 of the unit square / cube
        assert f[:, 1].sum() == pytest.approx(5.0 / 3.0 * area, rel=1e-12)
        moment = (f[:, 1] * mesh.points[:, 1]).sum()
        assert moment == pytest.approx(5.0 / 4.0 * area, rel=1e-12)


def test_curved_ellipsoid_volume_is_close_to_exact():
    e1, e2 = ellipsoid(divisions=6), ellipsoid(divisions=6, order=2)
    exact = 4.0 / 3.0 * np.pi
    v1 = model(e1).kinematics.weights.sum()
    v2 = model(e2).kinematics.weights.sum()
    assert abs(v2 / exact - 1) < 1e-3 < abs(v1 / exact - 1)
