"""Q1 quadrilaterals and hexahedra: kinematics (patch tests on distorted meshes), derivatives
against finite differences on both backends, mass, body loads and tractions."""

import numpy as np
import pytest

from tissuesim.backend import numba_available
from tissuesim.materials.registry import make_material
from tissuesim.mesh import box, rectangle
from tissuesim.mesh.checks import validate_mesh
from tissuesim.model import Model

LAWS = ("neo_hookean", "course_neo_hookean", "fixed_corotated", "linear", "stvk")


def distorted(mesh, amount=0.15, seed=3):
    """The mesh with its interior nodes moved randomly (non-parallelogram cells)."""
    from tissuesim.mesh.queries.select import boundary_vertices

    p = mesh.points.copy()
    inner = np.setdiff1d(np.arange(mesh.n_points), boundary_vertices(mesh))
    h = np.ptp(p, axis=0) / np.array([4.0, 4.0, 4.0][: mesh.dim])
    rng = np.random.default_rng(seed)
    p[inner] += amount * h * rng.uniform(-1, 1, (inner.size, mesh.dim))
    return validate_mesh(p, mesh.cells, source="distorted", facet_sets=dict(mesh.facet_sets))


MESHES = {
    "quad": lambda: rectangle(divisions=(3, 2), element="quad"),
    "quad_distorted": lambda: distorted(rectangle(divisions=(4, 4), element="quad")),
    "hex": lambda: box(divisions=(2, 1, 1), element="hex"),
    "hex_distorted": lambda: distorted(box(divisions=(3, 3, 3), element="hex")),
}


def model(mesh, law="neo_hookean", backend="numpy", formulation="displacement", nu=0.3, **kw):
    mat = make_material(law, youngs_modulus=1e3, poisson_ratio=nu)
    return Model(
        mesh, mat, np.full(mesh.n_cells, 2.0), backend=backend, formulation=formulation, **kw
    )


@pytest.mark.parametrize("name", MESHES)
def test_q1_patch_test_constant_strain_is_exact(name):
    """A linear field gives the same F at every Gauss point of every (distorted) cell, the
    weights sum to the domain's measure, and the interior forces of a homogeneous stretch
    vanish (the patch test), for every law."""
    mesh = MESHES[name]()
    d = mesh.dim
    A = np.eye(d) + 0.1 * np.arange(d * d).reshape(d, d) / d**2
    x = (mesh.points @ A.T + 0.3).ravel()
    for law in LAWS:
        md = model(mesh, law)
        F = md.kinematics.deformation_gradients(x)
        np.testing.assert_allclose(F, np.broadcast_to(A, F.shape), atol=1e-13)
        assert md.kinematics.weights.sum() == pytest.approx(1.0, rel=1e-12)
        g = md.evaluate(x, 1, False).gradient.reshape(-1, d)
        from tissuesim.mesh.queries.select import boundary_vertices

        inner = np.setdiff1d(np.arange(mesh.n_points), boundary_vertices(mesh))
        scale = np.abs(g).max()
        assert np.abs(g[inner]).max(initial=0.0) <= 1e-11 * scale
        assert np.abs(g.sum(axis=0)).max() <= 1e-11 * scale  # in equilibrium as a whole


@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("formulation", ["displacement", "mean_dilatation"])
def test_q1_energy_gradient_hessian_match_finite_differences(name, law, formulation):
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
def test_q1_fused_numba_equals_numpy(name, law):
    mesh = MESHES[name]()
    rng = np.random.default_rng(2)
    x = mesh.points.ravel() + 0.02 * rng.standard_normal(mesh.points.size)
    a = model(mesh, law, "numpy").evaluate(x, 2, False)
    from tissuesim.materials.isotropic.point_kernels import LAW_IDS

    fused = model(mesh, law, "numba")
    assert fused.elastic.fused == (law in LAW_IDS)
    b = fused.evaluate(x, 2, False)
    assert b.value == pytest.approx(a.value, rel=1e-12)
    np.testing.assert_allclose(b.gradient, a.gradient, atol=1e-11 * abs(a.gradient).max())
    np.testing.assert_allclose(b.hessian, a.hessian, atol=1e-11 * abs(a.hessian).max())
    np.testing.assert_allclose(
        fused.elastic.jacobians(x), model(mesh, law).elastic.jacobians(x), rtol=1e-12
    )


@pytest.mark.parametrize("name", MESHES)
def test_q1_mass_consistent_lumped_gravity_and_body_force(name):
    mesh = MESHES[name]()
    md = model(mesh)
    d = mesh.dim
    volume = 1.0  # unit square / cube; boundary nodes stay on it
    M = md.mass.matrix()
    ones = np.zeros(mesh.points.size)
    ones[0::d] = 1.0
    assert ones @ M @ ones == pytest.approx(2.0 * volume, rel=1e-12)  # density 2
    # M integrates products of Q1 fields exactly: int x * x dV (x is a Q1 field here)
    xx = np.zeros(mesh.points.size)
    xx[0::d] = mesh.points[:, 0]
    assert xx @ M @ xx == pytest.approx(2.0 / 3.0, rel=1e-12)
    assert np.all(np.linalg.eigvalsh(M.toarray()) > 0)
    # lumped: the row sums, positive, the same total
    assert md.mass.lumped.min() > 0
    np.testing.assert_allclose(md.mass.lumped, md.mass.row_sums, rtol=1e-12)
    lumped = Model(mesh, md.material, md.density, "lumped", backend="numpy")
    np.testing.assert_allclose(lumped.mass.matrix().diagonal(), md.mass.lumped)
    assert lumped.mass.matrix().nnz == M.nnz  # same pattern, zeros off the diagonal
    from tissuesim.energies.loads import BodyForce, Gravity

    g = np.zeros(d)
    g[-1] = -9.81
    f = Gravity(g).nodal_forces(md, 0.0)
    assert f[:, -1].sum() == pytest.approx(-9.81 * 2.0 * volume, rel=1e-12)
    # a body force linear in x: total int b dV and its moment int b x dV, exact
    b = BodyForce(lambda X, t: np.column_stack([X[:, 0], *[0 * X[:, 0]] * (d - 1)]))
    fb = b.nodal_forces(md, 0.0)
    assert fb[:, 0].sum() == pytest.approx(0.5, rel=1e-12)
    assert (fb[:, 0] * mesh.points[:, 0]).sum() == pytest.approx(1.0 / 3.0, rel=1e-12)


@pytest.mark.parametrize("name", ["quad_distorted", "hex", "hex_distorted"])
def test_q1_traction_integrates_force_and_moment(name):
    from tissuesim.energies.loads import Traction
    from tissuesim.mesh.queries.select import facets_on_plane

    mesh = MESHES[name]()
    md = model(mesh)
    d = mesh.dim
    facets = facets_on_plane(mesh, 0, 1.0)
    assert facets.shape[1] == (4 if d == 3 else 2)

    def linear(X, time):
        out = np.zeros_like(X)
        out[:, 1] = 5.0 * X[:, 1]  # linear along the face: bilinear interpolation is exact
        return out

    f = Traction(facets, linear).nodal_forces(md, 0.0)
    assert f[:, 1].sum() == pytest.approx(5.0 / 2.0, rel=1e-12)
    moment = (f[:, 1] * mesh.points[:, 1]).sum()
    assert moment == pytest.approx(5.0 / 3.0, rel=1e-12)
    # outward normals of the selected faces
    from tissuesim.mesh.cells.tensor import split_faces

    if d == 3:
        tri = split_faces(facets)
        x = mesh.points[tri]
        n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
        assert (n[:, 0] > 0).all()


def test_q1_shape_functions_partition_of_unity_and_derivatives():
    from tissuesim.mesh.cells.tensor import SIGNS, gauss_rule, shape_functions

    for d in (2, 3):
        rng = np.random.default_rng(d)
        xi = rng.uniform(-1, 1, (5, d))
        N, dN = shape_functions(d, xi)
        np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-14)
        np.testing.assert_allclose(N @ SIGNS[d], xi, atol=1e-14)  # reproduces xi
        np.testing.assert_allclose(shape_functions(d, SIGNS[d])[0], np.eye(2**d), atol=1e-14)
        eps = 1e-7
        for j in range(d):
            e = np.zeros(d)
            e[j] = eps
            fd = (shape_functions(d, xi + e)[0] - shape_functions(d, xi - e)[0]) / (2 * eps)
            np.testing.assert_allclose(dN[:, :, j], fd, atol=1e-9)
        # the 2-point rule integrates degree 3 per variable exactly
        p, w = gauss_rule(d, 2)
        assert w @ (p[:, 0] ** 2 * p[:, -1] ** 2) == pytest.approx((2 / 3) ** 2 * 2 ** (d - 2))


@pytest.mark.parametrize("name", ["hex", "hex_distorted"])
def test_q1_mass_by_the_element_rule_is_febios_hex8_mass(name):
    """mass = "element_rule": the consistent mass integrated by the hex8's own 2 x 2 x 2 Gauss
    points (FEBio's): on parallelepipeds the exact mass, on distorted cells not (3 points per
    direction are exact there) but with the same row sums (gravity, the lumped mass)."""
    mesh = MESHES[name]()
    exact = model(mesh).mass
    febio = model(mesh, mass_kind="element_rule").mass
    A, B = exact.matrix().toarray(), febio.matrix().toarray()
    np.testing.assert_allclose(febio.row_sums, exact.row_sums, rtol=1e-12)
    if name == "hex":
        np.testing.assert_allclose(B, A, atol=1e-14 * np.abs(A).max())
    else:
        assert np.abs(B - A).max() > 1e-6 * np.abs(A).max()


def test_the_element_rules_mass_is_the_gauss_sum_written_out():
    """One distorted hex8: every entry of the element_rule mass is rho N_a N_b det J summed
    over the 2 x 2 x 2 Gauss points (weight 1), written out here."""
    corners = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                        [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)  # fmt: skip
    X = (corners + 1) / 2 + 0.12 * np.random.default_rng(5).standard_normal((8, 3))
    mesh = validate_mesh(X, np.arange(8)[None], source="one hex")
    B = model(mesh, mass_kind="element_rule").mass.matrix().toarray()
    M = np.zeros((8, 8))
    for q in corners / np.sqrt(3.0):
        N = np.prod(1 + corners * q, axis=1) / 8
        dN = np.stack([corners[:, k] * np.prod(np.delete(1 + corners * q, k, axis=1), axis=1)
                       for k in range(3)], axis=1) / 8  # fmt: skip
        M += 2.0 * np.outer(N, N) * np.linalg.det(X.T @ dN)
    np.testing.assert_allclose(B[0::3, 0::3], M, rtol=1e-12)
    np.testing.assert_allclose(B[1::3, 1::3], M, rtol=1e-12)
    exact = model(mesh).mass.matrix().toarray()
    assert np.abs(exact[0::3, 0::3] - M).max() > 1e-6 * np.abs(M).max()  # not the exact one
