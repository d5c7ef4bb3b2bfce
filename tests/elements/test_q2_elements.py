"""Quadratic quadrilaterals and hexahedra (quad8, quad9, hexahedron20, hexahedron27): shape
functions and node order, patch tests on distorted meshes, derivatives against finite
differences, mass, tractions, the simplex split, VTU files and Newton's convergence."""

import os

import numpy as np
import pytest

from tissuesim.backend import numba_available
from tissuesim.materials.registry import make_material
from tissuesim.mesh import box, rectangle
from tissuesim.mesh.cells import tensor_quadratic as tq
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.queries.select import boundary_vertices
from tissuesim.model import Model

KINDS = ("quad8", "quad9", "hexahedron20", "hexahedron27")
ELEMENT = {"quad8": "quad8", "quad9": "quad9", "hexahedron20": "hex20", "hexahedron27": "hex27"}


def mesh_of(kind, divisions=None, distort=0.0, seed=3):
    """A unit square / cube of ``kind`` cells, interior nodes moved by ``distort`` cells."""
    if kind.startswith("quad"):
        mesh = rectangle(divisions=divisions or (2, 2), element=ELEMENT[kind])
    else:
        mesh = box(divisions=divisions or (2, 2, 1), element=ELEMENT[kind])
    if not distort:
        return mesh
    p = mesh.points.copy()
    inner = np.setdiff1d(np.arange(mesh.n_points), boundary_vertices(mesh))
    assert inner.size
    h = 1.0 / (2.0 * np.max(divisions or 2))
    rng = np.random.default_rng(seed)
    p[inner] += distort * h * rng.uniform(-1, 1, (inner.size, mesh.dim))
    return validate_mesh(p, mesh.cells, source="distorted", facet_sets=dict(mesh.facet_sets))


def model(mesh, law="neo_hookean", formulation="displacement", nu=0.3, **kw):
    mat = make_material(law, youngs_modulus=1e3, poisson_ratio=nu)
    return Model(
        mesh, mat, np.full(mesh.n_cells, 2.0), backend="numpy", formulation=formulation, **kw
    )


@pytest.mark.parametrize("kind", KINDS)
def test_shape_functions_unity_nodes_derivatives_and_vtk_order(kind):
    X = tq.NODES[kind]
    d = X.shape[1]
    N, _ = tq.shape_functions(kind, X)
    np.testing.assert_allclose(N, np.eye(len(X)), atol=1e-14)  # Kronecker at the nodes
    xi = np.random.default_rng(1).uniform(-1, 1, (6, d))
    N, dN = tq.shape_functions(kind, xi)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(N @ X, xi, atol=1e-14)  # reproduces linear fields
    np.testing.assert_allclose(N @ X**2, xi**2, atol=1e-14)  # and x^2 per axis
    eps = 1e-6
    for j in range(d):
        e = np.eye(d)[j] * eps
        fd = (tq.shape_functions(kind, xi + e)[0] - tq.shape_functions(kind, xi - e)[0]) / (2 * eps)
        np.testing.assert_allclose(dN[:, :, j], fd, atol=1e-9)
    vtk = pytest.importorskip("vtk")
    cls = {
        "quad8": vtk.vtkQuadraticQuad,
        "quad9": vtk.vtkBiQuadraticQuad,
        "hexahedron20": vtk.vtkQuadraticHexahedron,
        "hexahedron27": vtk.vtkTriQuadraticHexahedron,
    }[kind]()
    pc = cls.GetParametricCoords()
    ref = 2.0 * np.array([pc[i] for i in range(3 * len(X))]).reshape(-1, 3)[:, :d] - 1.0
    np.testing.assert_array_equal(ref, X)  # VTK's node order
    assert cls.GetCellType() == {"quad8": 23, "quad9": 28, "hexahedron20": 25}.get(kind, 29)


@pytest.mark.parametrize("kind", KINDS)
def test_patch_test_linear_field_is_exact_on_distorted_cells(kind):
    mesh = mesh_of(kind, distort=0.3)
    d = mesh.dim
    A = np.eye(d) + 0.1 * np.arange(d * d).reshape(d, d) / d**2
    x = (mesh.points @ A.T + 0.3).ravel()
    for law in ("neo_hookean", "stvk"):
        md = model(mesh, law)
        F = md.kinematics.deformation_gradients(x)
        np.testing.assert_allclose(F, np.broadcast_to(A, F.shape), atol=1e-12)
        assert md.kinematics.weights.sum() == pytest.approx(1.0, rel=1e-12)
        g = md.evaluate(x, 1, False).gradient.reshape(-1, d)
        inner = np.setdiff1d(np.arange(mesh.n_points), boundary_vertices(mesh))
        scale = np.abs(g).max()
        assert np.abs(g[inner]).max() <= 1e-11 * scale
        assert np.abs(g.sum(axis=0)).max() <= 1e-11 * scale


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("formulation", ["displacement", "mean_dilatation"])
def test_energy_gradient_hessian_match_finite_differences(kind, formulation):
    mesh = mesh_of(kind, distort=0.3)
    md = model(mesh, "neo_hookean", formulation=formulation, nu=0.45)
    rng = np.random.default_rng(7)
    x = mesh.points.ravel() + 0.02 * rng.standard_normal(mesh.points.size)
    acc = md.evaluate(x, 2, False)
    H = md.pattern.matrix(acc.hessian)
    dx = rng.standard_normal(x.size)
    eps = 1e-6
    e_plus = md.evaluate(x + eps * dx, 1, False)
    e_minus = md.evaluate(x - eps * dx, 1, False)
    assert (e_plus.value - e_minus.value) / (2 * eps) == pytest.approx(acc.gradient @ dx, rel=1e-6)
    fd_H = (e_plus.gradient - e_minus.gradient) / (2 * eps)
    np.testing.assert_allclose(fd_H, H @ dx, rtol=0, atol=1e-6 * np.abs(H @ dx).max())
    assert abs(H - H.T).max() <= 1e-12 * abs(H).max()


@pytest.mark.parametrize("kind", KINDS)
def test_mass_integrates_volume_and_quadratics_lumped_is_positive(kind):
    mesh = mesh_of(kind, distort=0.2)
    md = model(mesh)
    d = mesh.dim
    M = md.mass.matrix()
    ones = np.zeros(mesh.points.size)
    ones[0::d] = 1.0
    assert ones @ M @ ones == pytest.approx(2.0, rel=1e-12)  # density 2, unit volume
    # boundary nodes stay put, so x is exactly the cells' quadratic geometry field there;
    # on the undistorted mesh int x^2 dV = 1/3 exactly
    md0 = model(mesh_of(kind))
    xx = np.zeros(mesh.points.size)
    xx[0::d] = md0.mesh.points[:, 0] ** 2
    xd = np.zeros(mesh.points.size)
    xd[0::d] = md0.mesh.points[:, 0]
    M0 = md0.mass.matrix()
    assert xd @ M0 @ xd == pytest.approx(2.0 / 3.0, rel=1e-12)
    assert xx @ M0 @ ones == pytest.approx(2.0 / 3.0, rel=1e-12)  # int x^2 dV, x^2 in the space
    assert np.all(np.linalg.eigvalsh(M.toarray()) > 0)
    # lumped: HRZ, positive everywhere, the same total; the serendipity row sums are not
    assert md.mass.lumped.min() > 0
    assert md.mass.lumped.sum() == pytest.approx(md.mass.row_sums.sum(), rel=1e-12)
    lumped = Model(mesh, md.material, md.density, "lumped", backend="numpy")
    np.testing.assert_allclose(lumped.mass.matrix().diagonal(), md.mass.lumped)
    if kind in ("quad8", "hexahedron20"):
        one = model(mesh_of(kind, divisions=(1,) * d))
        corners = one.mass.row_sums.reshape(-1, d)[one.mesh.cells[0, : 2**d], 0]
        # quad8: -A/12 per corner; hexahedron20: -V/8 (times the density 2)
        np.testing.assert_allclose(corners, -2.0 / (12 if d == 2 else 8), rtol=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_traction_integrates_force_and_moment(kind):
    from tissuesim.energies.loads import Traction
    from tissuesim.mesh.queries.select import facets_on_plane

    mesh = mesh_of(kind, distort=0.3)
    md = model(mesh)
    facets = facets_on_plane(mesh, 0, 1.0)
    assert facets.shape[1] == 2 ** (mesh.dim - 1)

    def quadratic(X, time):
        out = np.zeros_like(X)
        out[:, 1] = 5.0 * X[:, 1] ** 2  # quadratic along the face: interpolated exactly
        return out

    f = Traction(facets, quadratic).nodal_forces(md, 0.0)
    assert f[:, 1].sum() == pytest.approx(5.0 / 3.0, rel=1e-12)
    assert (f[:, 1] * mesh.points[:, 1]).sum() == pytest.approx(5.0 / 4.0, rel=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_split_fills_the_cells_and_shows_each_face_on_the_boundary(kind):
    from tissuesim.contact.pairs import contact_facets
    from tissuesim.mesh.queries.boundary import boundary_facets, facet_normals

    mesh = mesh_of(kind, divisions=(2, 1, 2)[: 2 if kind.startswith("quad") else 3], distort=0.2)
    d = mesh.dim
    s = mesh.simplices
    X = mesh.points[s]
    vol = np.linalg.det(np.swapaxes(X[:, 1:] - X[:, :1], 1, 2)) / (2.0 if d == 2 else 6.0)
    assert vol.min() >= -1e-15
    md = model(mesh)
    assert vol.sum() == pytest.approx(md.kinematics.weights.sum(), rel=0.05)  # curved cells
    bt = boundary_facets(s)
    per_face = {"quad8": 2, "quad9": 2, "hexahedron20": 6, "hexahedron27": 8}[kind]
    n_faces = sum(len(v) for k, v in mesh.facet_sets.items() if k.endswith(("min", "max")))
    assert len(bt) == per_face * n_faces
    # a facet set as a contact surface: the same simplices, outward, every node on it
    tri = contact_facets("b", mesh, "xmax")
    assert len(tri) == per_face * len(mesh.facet_sets["xmax"])
    assert (facet_normals(mesh.points, tri)[:, 0] > 0).all()
    on = np.flatnonzero(np.abs(mesh.points[:, 0] - 1.0) < 1e-12)
    np.testing.assert_array_equal(np.unique(tri), on)


@pytest.mark.parametrize("kind", KINDS)
def test_vtu_round_trip_keeps_cells_and_type(kind, tmp_path):
    import meshio

    from tissuesim.mesh.io import read_mesh, write_mesh

    mesh = mesh_of(kind, distort=0.2)
    path = tmp_path / "m.vtu"
    write_mesh(mesh, path)
    raw = meshio.read(path)
    assert [b.type for b in raw.cells] == [kind]
    back = read_mesh(path)
    assert back.cell_type == kind
    np.testing.assert_array_equal(back.cells, mesh.cells)
    np.testing.assert_allclose(back.points, mesh.points, rtol=0, atol=1e-15)


def test_mirrored_and_inconsistent_cells():
    mesh = mesh_of("hexahedron20", divisions=(1, 1, 1))
    mirrored = mesh.cells[:, tq.reorient("hexahedron20")]
    with pytest.warns(UserWarning, match="reoriented 1"):
        fixed = validate_mesh(mesh.points, mirrored, source="m")
    np.testing.assert_array_equal(fixed.cells, mesh.cells)
    two = mesh_of("quad8", divisions=(2, 1))
    cells = two.cells.copy()
    cells[1, 7] = 0 if cells[1, 7] != 0 else 1  # a midside node the neighbour does not share
    pts = two.points
    with pytest.raises(Exception, match="share the corners of a facet|inverted|repeats"):
        validate_mesh(pts, cells, source="m")


def test_newton_converges_quadratically_on_hexahedra27():
    import tissuesim as ts
    from tissuesim.solve.newton import NewtonOptions

    mesh = box(upper=(4.0, 1.0, 1.0), divisions=(2, 1, 1), element="hex27")
    mat = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    opts = NewtonOptions(gradient_tolerance=1e-13, absolute_tolerance=1e-16)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0, newton=opts)
    sim.add_body("b", mesh, mat)
    sim.fix(mesh.point_sets["xmin"], body="b")
    sim.add_traction(mesh.facet_sets["xmax"], [0.0, 0.0, -300.0], body="b")
    record = sim.step()
    r = np.array(record.residual_norms[0])
    r = r / r[0]
    assert record.converged and len(r) >= 4
    # the last steps: r_{k+1} <= C r_k^2 with C of order one (linear would be r_{k+1} ~ c r_k)
    # (above 1e-6: below it the next residual is round-off, ~1e-13)
    tail = [(a, b) for a, b in zip(r[:-1], r[1:], strict=True) if 1e-6 < a < 5e-2]
    assert len(tail) >= 2, r
    for a, b in tail:
        assert b <= 50.0 * a**2, r


@pytest.mark.skipif(
    not numba_available() or not os.environ.get("TISSUESIM_COMPILE_TESTS"),
    reason="compiles 4 Numba loops (about 40 s each); set TISSUESIM_COMPILE_TESTS=1",
)
@pytest.mark.parametrize("kind", KINDS)
def test_fused_numba_equals_numpy(kind):
    mesh = mesh_of(kind, distort=0.2)
    x = mesh.points.ravel() + 0.02 * np.random.default_rng(2).standard_normal(mesh.points.size)
    a = model(mesh).evaluate(x, 2, False)
    mat = make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    fused = Model(mesh, mat, np.full(mesh.n_cells, 2.0), backend="numba")
    assert fused.elastic.fused
    b = fused.evaluate(x, 2, False)
    assert b.value == pytest.approx(a.value, rel=1e-12)
    np.testing.assert_allclose(b.gradient, a.gradient, atol=1e-11 * abs(a.gradient).max())
    np.testing.assert_allclose(b.hessian, a.hessian, atol=1e-11 * abs(a.hessian).max())
