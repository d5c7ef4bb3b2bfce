"""Linear wedges (6-node prisms): shape functions and FEBio's rule, exact volumes and masses,
tractions on their quadrilateral and triangular faces, patch tests on distorted meshes, and
energy, gradient and Hessian against finite differences on both backends."""

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.backend import numba_available
from tissuesim.energies.loads import BodyForce, Gravity, Traction, traction_nodal_forces
from tissuesim.materials.registry import make_material
from tissuesim.mesh import describe_mesh
from tissuesim.mesh.cells import wedge
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.queries.select import boundary_vertices
from tissuesim.model import Model

LAWS = ("neo_hookean", "course_neo_hookean", "fixed_corotated", "linear", "stvk")
#: FEBio's FEPenta6G6 (FECore/FEElementTraits.cpp): r, s, t and weight of its 6 points
FEBIO_G6 = [
    (1 / 6, 1 / 6, -1 / 3**0.5, 1 / 6), (2 / 3, 1 / 6, -1 / 3**0.5, 1 / 6),
    (1 / 6, 2 / 3, -1 / 3**0.5, 1 / 6), (1 / 6, 1 / 6, 1 / 3**0.5, 1 / 6),
    (2 / 3, 1 / 6, 1 / 3**0.5, 1 / 6), (1 / 6, 2 / 3, 1 / 3**0.5, 1 / 6),
]  # fmt: skip


def distorted(mesh, amount=0.15, seed=3):
    """The mesh with its interior nodes moved randomly (warped, non-prismatic wedges)."""
    p = mesh.points.copy()
    inner = np.setdiff1d(np.arange(mesh.n_points), boundary_vertices(mesh))
    h = np.ptp(p, axis=0) / 4.0
    p[inner] += amount * h * np.random.default_rng(seed).uniform(-1, 1, (inner.size, 3))
    return validate_mesh(p, mesh.cells, source="distorted", facet_sets=dict(mesh.facet_sets))


MESHES = {
    "wedge": lambda: ts.box(divisions=(2, 1, 1), element="wedge"),
    "wedge_distorted": lambda: distorted(ts.box(divisions=(3, 3, 3), element="wedge")),
}


def model(mesh, law="neo_hookean", backend="numpy", formulation="displacement", nu=0.3, **kw):
    mat = make_material(law, youngs_modulus=1e3, poisson_ratio=nu)
    return Model(
        mesh, mat, np.full(mesh.n_cells, 2.0), backend=backend, formulation=formulation, **kw
    )


def test_shape_functions_partition_of_unity_nodes_and_gradients():
    rng = np.random.default_rng(1)
    rs = rng.uniform(0, 0.5, (7, 2))
    xi = np.column_stack([rs, rng.uniform(-1, 1, 7)])
    N, dN = wedge.shape_functions(xi)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(N @ wedge.NODES, xi, atol=1e-14)  # reproduces r, s, t
    np.testing.assert_allclose(dN.sum(axis=1), 0.0, atol=1e-14)
    np.testing.assert_allclose(wedge.shape_functions(wedge.NODES)[0], np.eye(6), atol=1e-15)
    eps = 1e-7
    for j in range(3):
        e = np.zeros(3)
        e[j] = eps
        fd = (wedge.shape_functions(xi + e)[0] - wedge.shape_functions(xi - e)[0]) / (2 * eps)
        np.testing.assert_allclose(dN[:, :, j], fd, atol=1e-9)


def test_stiffness_rule_is_febios_and_both_rules_are_exact():
    p, w = wedge.stiffness_rule()
    np.testing.assert_allclose(np.column_stack([p, w]), FEBIO_G6, atol=1e-15)

    def exact(a, b, c):  # int over the reference wedge of r^a s^b t^c
        from math import factorial

        tri = factorial(a) * factorial(b) / factorial(a + b + 2)
        return tri * (0.0 if c % 2 else 2.0 / (c + 1))

    for (a, b, c), rule in [((2, 0, 3), wedge.stiffness_rule()), ((1, 2, 5), wedge.mass_rule())]:
        p, w = rule
        assert w @ (p[:, 0] ** a * p[:, 1] ** b * p[:, 2] ** c) == pytest.approx(
            exact(a, b, c), abs=1e-15
        )
        assert w @ (p[:, 0] * p[:, 1] * p[:, 2] ** 2) == pytest.approx(exact(1, 1, 2), rel=1e-13)


def test_volume_of_a_right_and_a_tapered_wedge_is_exact():
    """A right prism over the triangle with legs a, b (V = a b h / 2) and a frustum whose top
    triangle is the bottom one scaled by k about its centroid (V = h/3 (A1 + A2 + sqrt(A1 A2))),
    integrated by the stiffness rule, the mass rule and ``describe_mesh``."""
    a, b, h, k = 0.3, 0.2, 0.5, 0.6
    base = np.array([[0, 0, 0], [a, 0, 0], [0, b, 0]])
    right = np.concatenate([base, base + [0, 0, h]])
    centre = base.mean(axis=0)
    top = centre + k * (base - centre) + [0.05, -0.02, h]  # scaled and shifted: planar sides
    frustum = np.concatenate([base, top])
    A1 = a * b / 2
    for points, volume in ((right, A1 * h), (frustum, h / 3 * (A1 + k * k * A1 + k * A1))):
        mesh = validate_mesh(points, [np.arange(6)], source="one wedge")
        md = model(mesh)
        assert md.kinematics.weights.sum() == pytest.approx(volume, rel=1e-14)
        assert md.mass.row_sums.sum() / 3 == pytest.approx(2.0 * volume, rel=1e-14)
        assert describe_mesh(mesh)["total_volume"] == pytest.approx(volume, rel=1e-14)
        x = mesh.simplices
        assert np.linalg.det(points[x][:, 1:] - points[x][:, :1]).sum() / 6 == pytest.approx(
            volume, rel=1e-14
        )


@pytest.mark.parametrize("name", MESHES)
def test_patch_test_constant_strain_is_exact(name):
    """A linear field gives the same F at every point of every (distorted) wedge, the weights
    sum to the unit cube's volume, and a homogeneous stretch leaves no interior force."""
    mesh = MESHES[name]()
    A = np.eye(3) + 0.1 * np.arange(9).reshape(3, 3) / 9
    x = (mesh.points @ A.T + 0.3).ravel()
    inner = np.setdiff1d(np.arange(mesh.n_points), boundary_vertices(mesh))
    for law in LAWS:
        md = model(mesh, law)
        F = md.kinematics.deformation_gradients(x)
        np.testing.assert_allclose(F, np.broadcast_to(A, F.shape), atol=1e-13)
        assert md.kinematics.weights.sum() == pytest.approx(1.0, rel=1e-12)
        g = md.evaluate(x, 1, False).gradient.reshape(-1, 3)
        scale = np.abs(g).max()
        assert np.abs(g[inner]).max(initial=0.0) <= 1e-11 * scale
        assert np.abs(g.sum(axis=0)).max() <= 1e-11 * scale
        stress = md.material.evaluate(F, 1).stress
        np.testing.assert_allclose(stress, np.broadcast_to(stress[0], stress.shape), atol=1e-10)


@pytest.mark.parametrize("law", ["neo_hookean", "stvk", "fixed_corotated"])
@pytest.mark.parametrize("formulation", ["displacement", "mean_dilatation"])
def test_energy_gradient_hessian_match_finite_differences(law, formulation):
    mesh = MESHES["wedge_distorted"]()
    md = model(mesh, law, formulation=formulation, nu=0.45)
    rng = np.random.default_rng(7)
    x = mesh.points.ravel() + 0.02 * rng.standard_normal(mesh.points.size)
    acc = md.evaluate(x, 2, False)
    H = md.pattern.matrix(acc.hessian)
    dx = rng.standard_normal(x.size)
    eps = 1e-6
    e_plus, e_minus = md.evaluate(x + eps * dx, 1, False), md.evaluate(x - eps * dx, 1, False)
    assert (e_plus.value - e_minus.value) / (2 * eps) == pytest.approx(acc.gradient @ dx, rel=1e-6)
    fd_H = (e_plus.gradient - e_minus.gradient) / (2 * eps)
    np.testing.assert_allclose(fd_H, H @ dx, rtol=0, atol=1e-6 * np.abs(H @ dx).max())
    assert abs(H - H.T).max() <= 1e-12 * abs(H).max()


@pytest.mark.skipif(not numba_available(), reason="numba not installed")
def test_fused_numba_loop_equals_numpy():
    mesh = MESHES["wedge_distorted"]()
    x = mesh.points.ravel() + 0.02 * np.random.default_rng(2).standard_normal(mesh.points.size)
    a = model(mesh, "neo_hookean", "numpy").evaluate(x, 2, False)
    fused = model(mesh, "neo_hookean", "numba")
    assert fused.elastic.fused
    b = fused.evaluate(x, 2, False)
    assert b.value == pytest.approx(a.value, rel=1e-12)
    np.testing.assert_allclose(b.gradient, a.gradient, atol=1e-11 * abs(a.gradient).max())
    np.testing.assert_allclose(b.hessian, a.hessian, atol=1e-11 * abs(a.hessian).max())
    np.testing.assert_allclose(fused.elastic.jacobians(x), model(mesh).elastic.jacobians(x))


@pytest.mark.parametrize("name", MESHES)
def test_mass_consistent_lumped_gravity_and_body_force(name):
    mesh = MESHES[name]()
    md = model(mesh)  # density 2 on the unit cube
    M = md.mass.matrix()
    ones = np.zeros(mesh.points.size)
    ones[0::3] = 1.0
    assert ones @ M @ ones == pytest.approx(2.0, rel=1e-12)
    xx = np.zeros(mesh.points.size)
    xx[0::3] = mesh.points[:, 0]  # x is linear on every wedge: int rho x^2 exact
    assert xx @ M @ xx == pytest.approx(2.0 / 3.0, rel=1e-12)
    assert np.all(np.linalg.eigvalsh(M.toarray()) > 0)
    # lumped: the row sums, positive; they keep the mass centre (first moments) exactly
    lumped = md.mass.lumped.reshape(-1, 3)[:, 0]
    assert lumped.min() > 0
    np.testing.assert_allclose(md.mass.lumped, md.mass.row_sums, rtol=1e-12)
    np.testing.assert_allclose(lumped @ mesh.points, 2.0 * np.array([0.5, 0.5, 0.5]), rtol=1e-12)
    diagonal = Model(mesh, md.material, md.density, "lumped", backend="numpy").mass.matrix()
    np.testing.assert_allclose(diagonal.diagonal(), md.mass.lumped)
    f = Gravity(np.array([0.0, 0.0, -9.81])).nodal_forces(md, 0.0)
    assert f[:, 2].sum() == pytest.approx(-9.81 * 2.0, rel=1e-12)
    b = BodyForce(lambda X, t: np.column_stack([X[:, 0], 0 * X[:, 0], 0 * X[:, 0]]))
    fb = b.nodal_forces(md, 0.0)
    assert fb[:, 0].sum() == pytest.approx(0.5, rel=1e-12)
    assert (fb[:, 0] * mesh.points[:, 0]).sum() == pytest.approx(1.0 / 3.0, rel=1e-12)


@pytest.mark.parametrize("name", MESHES)
def test_tractions_on_quadrilaterals_and_triangles(name):
    """A traction linear along the face: its force and moment exact on the side quads
    (bilinear, the hexahedra's rule) and on the top triangles (linear); a uniform one puts
    A / 3 on each corner of a triangle, as the linear triangle's consistent load."""
    mesh = MESHES[name]()
    md = model(mesh)
    side = ts.select.facets_on_plane(mesh, 0, 1.0)
    top = ts.select.facets_on_plane(mesh, 2, 1.0)
    assert not wedge.is_triangle(side).any() and wedge.is_triangle(top).all()
    for facets, along in ((side, 1), (top, 0)):
        h = Traction(facets, lambda X, t, a=along: np.outer(5.0 * X[:, a], [0, 1, 0]))
        f = h.nodal_forces(md, 0.0)
        assert f[:, 1].sum() == pytest.approx(5.0 / 2.0, rel=1e-12)
        assert (f[:, 1] * mesh.points[:, along]).sum() == pytest.approx(5.0 / 3.0, rel=1e-12)
    uniform = Traction(top, lambda X, t: np.broadcast_to([0.0, 0.0, -3.0], X.shape))
    per_vertex = np.broadcast_to([0.0, 0.0, -3.0], (len(top), 3, 3))
    expected = traction_nodal_forces(mesh.points, top[:, :3], per_vertex)
    np.testing.assert_allclose(uniform.nodal_forces(md, 0.0), expected, atol=1e-14)
    # the collapsed quads' normals are the triangles': outward
    x = mesh.points[top]
    n = np.cross(x[:, 1] - x[:, 0], x[:, 3] - x[:, 0])
    assert (n[:, 2] > 0).all()
