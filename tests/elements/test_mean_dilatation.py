"""The mean-dilatation formulation: derivatives, patch test, stability, Newton, no locking."""

import numpy as np
import pytest

from tissuesim import Simulation
from tissuesim.errors import InputError
from tissuesim.materials.registry import make_material
from tissuesim.mesh import box, rectangle
from tissuesim.mesh.queries.select import boundary_vertices, facets_on_plane, vertices_on_plane
from tissuesim.model import Model
from tissuesim.solve.newton import NewtonOptions

LAWS = ("neo_hookean", "course_neo_hookean", "fixed_corotated", "linear", "stvk")
MESHES = {
    "tri3": lambda: rectangle(divisions=(3, 2)),
    "tri6": lambda: rectangle(divisions=(2, 2), order=2),
    "tet4": lambda: box(divisions=(2, 1, 1)),
    "tet10": lambda: box(divisions=(1, 1, 1), order=2),
}


def model(mesh, law="neo_hookean", formulation="mean_dilatation", nu=0.45):
    mat = make_material(law, youngs_modulus=1e3, poisson_ratio=nu)
    return Model(mesh, mat, np.ones(mesh.n_cells), backend="numpy", formulation=formulation)


@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("law", LAWS)
def test_energy_gradient_hessian_match_finite_differences(name, law):
    mesh = MESHES[name]()
    md = model(mesh, law)
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


@pytest.mark.parametrize("name", MESHES)
def test_it_differs_from_the_displacement_form_only_in_the_volumetric_term(name):
    mesh = MESHES[name]()
    rng = np.random.default_rng(5)
    x = mesh.points.ravel() + 0.03 * rng.standard_normal(mesh.points.size)
    # with lambda = 0 (nu = 0) the lambda term vanishes: both forms are the same energy
    a = model(mesh, nu=0.0).evaluate(x, 1, False)
    b = model(mesh, formulation="displacement", nu=0.0).evaluate(x, 1, False)
    assert a.value == pytest.approx(b.value, rel=1e-12)
    np.testing.assert_allclose(a.gradient, b.gradient, atol=1e-10 * abs(b.gradient).max())
    # with lambda > 0 they differ (averaging changes the energy of a non-uniform dilatation)
    c = model(mesh).evaluate(x, 0, False).value
    d = model(mesh, formulation="displacement").evaluate(x, 0, False).value
    assert abs(c - d) > 1e-6 * abs(d)


@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("formulation", ["displacement", "mean_dilatation"])
def test_patch_test_linear_field_is_reproduced(name, formulation):
    """Boundary vertices on x = A X; the free interior nodes must land on A X exactly."""
    mesh = {
        "tri3": lambda: rectangle(divisions=(4, 4)),
        "tri6": lambda: rectangle(divisions=(3, 3), order=2),
        "tet4": lambda: box(divisions=(3, 3, 3)),
        "tet10": lambda: box(divisions=(2, 2, 2), order=2),
    }[name]()  # meshes with interior nodes
    d = mesh.dim
    A = np.eye(d) + 0.05 * np.arange(d * d).reshape(d, d) / d**2
    sim = Simulation(
        integrator="quasistatic", time_step=1.0, newton=NewtonOptions(gradient_tolerance=1e-12)
    )
    mat = make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.49)
    body = sim.add_body("patch", mesh, mat, formulation=formulation)
    ids = boundary_vertices(mesh)
    X = mesh.points
    body.add_dirichlet(ids, lambda P, t: P @ (A - np.eye(d)).T)
    sim.step()
    np.testing.assert_allclose(sim.positions, X @ A.T, atol=1e-9)


@pytest.mark.parametrize("name", MESHES)
def test_no_spurious_zero_energy_modes(name):
    """The rest Hessian of a free body has exactly the rigid modes as its null space."""
    mesh = MESHES[name]()
    md = model(mesh, nu=0.49)
    H = md.pattern.matrix(md.evaluate(mesh.points.ravel(), 2, False).hessian).toarray()
    w = np.linalg.eigvalsh(H)
    d = mesh.dim
    rigid = d * (d + 1) // 2
    scale = w.max()
    assert np.all(w > -1e-10 * scale)
    assert np.sum(np.abs(w) < 1e-10 * scale) == rigid
    assert w[rigid] > 1e-6 * scale  # the smallest deformation mode is clearly positive


@pytest.mark.parametrize("order", [1, 2])
def test_newton_converges_quadratically(order):
    mesh = rectangle((0, 0), (4, 1), (8, 2), order=order)
    sim = Simulation(
        integrator="quasistatic",
        time_step=1.0,
        newton=NewtonOptions(gradient_tolerance=1e-13, max_iterations=50),
    )
    mat = make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.499)
    body = sim.add_body("beam", mesh, mat, formulation="mean_dilatation")
    body.fix(vertices_on_plane(body.mesh, 0, 0.0))
    body.add_traction(facets_on_plane(body.mesh, 0, 4.0), [0.0, -5.0])
    record = sim.step()
    norms = np.array(record.residual_norms[-1])
    tail = norms[norms > 1e-11 * norms[0]][-4:]
    rates = np.log(tail[2:] / tail[1:-1]) / np.log(tail[1:-1] / tail[:-2])
    assert rates.max() > 1.8


def test_mean_dilatation_removes_locking_in_cooks_membrane():
    """nu = 0.4999: P1 locks (tip deflection far too small); both mean-dilatation variants and
    P2 agree within a few percent at a coarse mesh."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "cook", Path(__file__).resolve().parents[2] / "benchmarks" / "cook_membrane.py"
    )
    cook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(cook)
    tip = {
        (o, f): cook.tip_deflection(8, o, f, 0.4999, 100.0, 2)["uy"]
        for o in (1, 2)
        for f in ("displacement", "mean_dilatation")
    }
    ref = tip[2, "mean_dilatation"]
    assert tip[1, "displacement"] < 0.85 * ref  # locked
    assert abs(tip[1, "mean_dilatation"] - ref) < 0.75 * abs(tip[1, "displacement"] - ref)
    assert tip[2, "displacement"] < tip[2, "mean_dilatation"]
    finer = cook.tip_deflection(16, 2, "mean_dilatation", 0.4999, 100.0, 2)["uy"]
    assert ref == pytest.approx(finer, rel=0.01)


def test_bad_formulation_and_law_are_one_clear_error():
    mesh = rectangle(divisions=(2, 2))
    sim = Simulation(integrator="quasistatic")
    mat = make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    with pytest.raises(InputError, match="formulation must be one of"):
        sim.add_body("a", mesh, mat, formulation="mixed")
    with pytest.raises(InputError, match="order must be 1 or 2"):
        sim.add_body("b", mesh, mat, order=3)
    with pytest.raises(InputError, match="order 1 was asked for"):
        sim.add_body("c", rectangle(divisions=(2, 2), order=2), mat, order=1)

    class Custom(type(mat)):
        name = "custom"

    with pytest.raises(InputError, match="needs a law with a known volumetric part"):
        Model(
            mesh,
            Custom(youngs_modulus=1e3, poisson_ratio=0.3),
            np.ones(mesh.n_cells),
            formulation="mean_dilatation",
        )


@pytest.mark.parametrize("name", MESHES)
def test_output_stress_uses_the_patch_pressure(name):
    from tissuesim.bodies.fem import FemBody

    mesh = MESHES[name]()
    mat = make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.49)
    body = FemBody(
        "b",
        mesh,
        mat,
        density=1.0,
        mass="consistent",
        backend="numpy",
        claim_name=lambda n: n,
        changed=lambda: None,
        formulation="mean_dilatation",
    )
    d = mesh.dim
    A = np.eye(d) * 1.02
    A[0, 1] = 0.05
    uniform = (mesh.points @ A.T).ravel()
    plain = FemBody(
        "c", mesh, mat, density=1.0, mass="consistent", backend="numpy",
        claim_name=lambda n: n, changed=lambda: None,
    )  # fmt: skip
    # a uniform deformation: the patch pressure is the point pressure, nothing changes
    np.testing.assert_allclose(
        body.cell_fields(uniform)["cauchy_stress"], plain.cell_fields(uniform)["cauchy_stress"],
        atol=1e-9 * 1e3,
    )  # fmt: skip
    rng = np.random.default_rng(4)
    x = uniform + 0.02 * rng.standard_normal(uniform.size)
    fields = body.cell_fields(x)
    energy = body.model.evaluate(x, 0, False).value
    volumes = body.model.kinematics.cell_weights
    assert volumes @ fields["energy_density"] == pytest.approx(energy, rel=1e-10)
    # a non-uniform one: the pressure differs from the locking point-wise one
    assert not np.allclose(fields["cauchy_stress"], plain.cell_fields(x)["cauchy_stress"])


def test_an_uncoupled_viscoelastic_law_on_the_mean_dilatation_form_matches_differences():
    """An uncoupled viscoelastic law (FEBio's three-field hex8 with it): the bulk term is the
    elastic law's on the patch's mean dilatation, the Prony series acts on the deviatoric part
    at the points; with a history built over a first step, the energy's gradient and Hessian
    within a step match finite differences."""
    mesh = box(divisions=(2, 1, 1), element="hex")
    elastic = {"model": "mooney_rivlin", "c1": 200.0, "c2": 50.0, "k": 5e3}
    law = make_material("uncoupled_viscoelastic", elastic=elastic, g=[0.5], tau=[0.2])
    md = Model(mesh, law, np.ones(mesh.n_cells), backend="numpy", formulation="mean_dilatation")
    rng = np.random.default_rng(5)
    x1 = (mesh.points * [1.15, 0.95, 0.97]).ravel() + 0.01 * rng.standard_normal(mesh.points.size)
    md.material.begin_step(0.1)  # the model's bound copy of the law holds the history
    md.end_step(x1)  # a first step's history
    md.material.begin_step(0.1)
    x = x1 + 0.02 * rng.standard_normal(x1.size)
    acc = md.evaluate(x, 2, False)
    H = md.pattern.matrix(acc.hessian)
    dx = rng.standard_normal(x.size)
    eps = 1e-6
    plus, minus = md.evaluate(x + eps * dx, 1, False), md.evaluate(x - eps * dx, 1, False)
    assert (plus.value - minus.value) / (2 * eps) == pytest.approx(acc.gradient @ dx, rel=1e-6)
    fd_H = (plus.gradient - minus.gradient) / (2 * eps)
    np.testing.assert_allclose(fd_H, H @ dx, rtol=0, atol=1e-6 * np.abs(H @ dx).max())
    coupled = make_material("viscoelastic", elastic=elastic, g=[0.5], tau=[0.2])
    with pytest.raises(InputError, match="volumetric part"):
        Model(mesh, coupled, np.ones(mesh.n_cells), backend="numpy", formulation="mean_dilatation")
