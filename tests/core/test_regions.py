"""Regions: several materials (and formulations) in one FEM body sharing its vertices
(``Simulation.add_body(..., regions=...)``, ``model_regions.py``, ``bodies/regions.py``)."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.bodies.regions import Region
from tissuesim.energies.mass import Inertia
from tissuesim.errors import InputError
from tissuesim.model import Model


def _fd(f, x, eps=1e-6):
    g = np.zeros_like(x)
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = eps
        g[i] = (f(x + e) - f(x - e)) / (2 * eps)
    return g


def _halves(mesh):
    c = mesh.points[mesh.cells].mean(axis=1)
    return np.flatnonzero(c[:, 0] < 0.5 * mesh.points[:, 0].max())


def test_bar_of_two_materials_is_two_springs_in_series():
    """A bar, 4 cm of E1 then 6 cm of E2 (nu = 0), pulled at its end: the end moves by
    F (L1 / E1 + L2 / E2) / A, springs in series (small strain)."""
    L, W = 0.1, 0.02
    mesh = ts.box((0, 0, 0), (L, W, W), (10, 2, 2), element="hex")
    c = mesh.points[mesh.cells].mean(axis=1)
    soft = np.flatnonzero(c[:, 0] < 0.04)
    E1, E2 = 1e4, 4e4
    m1 = ts.make_material("linear", youngs_modulus=E1, poisson_ratio=0.0)
    m2 = ts.make_material("linear", youngs_modulus=E2, poisson_ratio=0.0)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0)
    body = sim.add_body("bar", mesh, m2, regions={"soft": (soft, m1)})
    x = mesh.points
    for axis in range(3):
        sim.add_dirichlet(np.flatnonzero(np.isclose(x[:, axis], 0)), None, (axis,), body="bar")
    F = 1e-4  # N: a strain of 1e-4, where the linear law's geometric terms are round-off
    sim.add_traction(mesh.facet_sets["xmax"], [F / W**2, 0, 0], body="bar")
    sim.step()
    _, xc, _ = sim.body_state("bar")
    right = np.flatnonzero(np.isclose(x[:, 0], L))
    u = xc.reshape(-1, 3)[right, 0] - x[right, 0]
    exact = F / W**2 * (0.04 / E1 + 0.06 / E2)
    np.testing.assert_allclose(u, exact, rtol=1e-3)
    fields = body.cell_fields(xc)
    np.testing.assert_array_equal(fields["region"], np.isin(np.arange(40), soft) == 0)
    np.testing.assert_allclose(fields["cauchy_stress"][:, 0, 0], F / W**2, rtol=1e-3)
    materials = body.model.material  # scales: the stiffest region's, and each cell's
    assert materials.mu == E2 / 2
    np.testing.assert_array_equal(
        materials.cell_mu, np.where(np.isin(np.arange(40), soft), E1 / 2, E2 / 2)
    )


@pytest.mark.parametrize("cell", ["tet", "hex"])
def test_two_region_energy_gradient_hessian_match_finite_differences(cell):
    mesh = ts.box((0, 0, 0), (1, 0.6, 0.5), (2, 2, 1), element=cell)
    soft = _halves(mesh)
    stiff = np.setdiff1d(np.arange(mesh.n_cells), soft)
    m1 = ts.make_material("neo_hookean", youngs_modulus=3.0, poisson_ratio=0.3)
    m2 = ts.make_material("mooney_rivlin", c1=2.0, c2=0.5, k=20.0)
    regions = (
        ("soft", soft, m1, "displacement", 2.0),
        ("stiff", stiff, m2, "mean_dilatation" if cell == "hex" else "displacement", 5.0),
    )
    model = Model(mesh, m1, 1.0, backend="numpy", regions=regions)
    rng = np.random.default_rng(0)
    x = (mesh.points + 0.03 * rng.standard_normal(mesh.points.shape)).ravel()
    energies = (Inertia(model.mass, x + 0.01, 0.05),)
    acc = model.evaluate(x, 2, False, energies)
    g_fd = _fd(lambda y: model.evaluate(y, 0, False, energies).value, x)
    np.testing.assert_allclose(acc.gradient, g_fd, atol=1e-6 * np.abs(acc.gradient).max())
    H = model.pattern.matrix(acc.hessian).toarray()
    H_fd = np.stack(
        [_fd(lambda y, i=i: model.evaluate(y, 1, False, energies).gradient[i], x)
         for i in range(x.size)]
    )  # fmt: skip
    np.testing.assert_allclose(H, H_fd, atol=1e-6 * np.abs(H).max())
    # the energy is the sum of each region's as a body of its own
    sub = [Model(ts.Mesh(mesh.points, mesh.cells[c]), m, 1.0, backend="numpy", formulation=f)
           for _, c, m, f, _ in regions]  # fmt: skip
    total = sum(s.evaluate(x, 0, False).value for s in sub)
    assert model.evaluate(x, 0, False).value == pytest.approx(total, rel=1e-13)
    # mass: each region's density on its cells
    volume = [s.kinematics.cell_weights.sum() for s in sub]
    assert model.mass.row_sums.sum() / 3 == pytest.approx(2.0 * volume[0] + 5.0 * volume[1])


def test_one_region_is_the_plain_body_bit_for_bit():
    mesh = ts.box((0, 0, 0), (0.1, 0.05, 0.05), (3, 2, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.45)
    results = []
    for regions in (None, {"all": (np.arange(mesh.n_cells), material)}):
        sim = ts.Simulation(integrator="backward_euler", time_step=0.01)
        sim.add_body("b", mesh, None if regions else material, regions=regions)
        sim.add_gravity([0, 0, -9.81])
        sim.fix(np.flatnonzero(mesh.points[:, 0] == 0))
        sim.step()
        _, x, v = sim.body_state("b")
        assert sim.body("b").model.parts is None
        results.append((x, v))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])


def test_two_regions_of_one_material_are_the_plain_body():
    mesh = ts.box((0, 0, 0), (0.1, 0.05, 0.05), (3, 2, 2), element="hex")
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    soft = _halves(mesh)
    plain = Model(mesh, material, 1000.0)
    rest = np.setdiff1d(np.arange(mesh.n_cells), soft)
    regions = (
        ("a", soft, material, "displacement", None),
        ("b", rest, material, "displacement", None),
    )
    two = Model(mesh, material, 1000.0, regions=regions)
    x = mesh.points.ravel() * 1.01 + 1e-4
    a, b = plain.evaluate(x, 2, False), two.evaluate(x, 2, False)
    assert a.value == pytest.approx(b.value, rel=1e-13)
    np.testing.assert_allclose(a.gradient, b.gradient, atol=1e-12 * np.abs(a.gradient).max())
    Ha = plain.pattern.matrix(a.hessian).toarray()
    Hb = two.pattern.matrix(b.hessian).toarray()
    np.testing.assert_allclose(Ha, Hb, atol=1e-12 * np.abs(Ha).max())
    np.testing.assert_allclose(plain.mass.data.sum(), two.mass.data.sum(), rtol=1e-13)


def test_regions_by_cell_set_and_their_errors():
    mesh = ts.box((0, 0, 0), (0.1, 0.05, 0.05), (2, 1, 1), element="hex")
    mesh = ts.Mesh(mesh.points, mesh.cells, cell_sets={"left": np.array([0])})
    m = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0)
    body = sim.add_body("a", mesh, regions={"l": ("left", m), "r": Region([1], m, density=2.0)})
    assert [p.name for p in body.model.parts] == ["l", "r"]
    np.testing.assert_array_equal(body.model.density, [1000.0, 2.0])
    with pytest.raises(InputError, match="'nope' is not a cell set"):
        sim.add_body("b", mesh, m, regions={"x": ("nope", m)})
    with pytest.raises(InputError, match="cell 1 .* is in no region"):
        sim.add_body("c", mesh, regions={"x": ([0], m)})
    with pytest.raises(InputError, match="cell 0 is in two regions"):
        sim.add_body("d", mesh, regions={"x": ([0], m), "y": ([0, 1], m)})
    with pytest.raises(InputError, match="body 'a' has several regions: it cannot be cut"):
        body.apply_cut(None, None, None)


def test_output_has_each_cell_with_its_region_and_cell_means(tmp_path):
    """The VTU series holds every cell once with a `region` field; element means of the
    regions' points are each cell's (equal Gauss weights on a box's hexahedra)."""
    import meshio

    mesh = ts.box((0, 0, 0), (0.1, 0.05, 0.05), (4, 2, 2), element="hex")
    soft = _halves(mesh)
    m1 = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    m2 = ts.make_material("neo_hookean", youngs_modulus=3e4, poisson_ratio=0.3)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0)
    body = sim.add_body("b", mesh, m2, regions={"soft": (soft, m1)})
    sim.fix(np.flatnonzero(mesh.points[:, 0] == 0))
    sim.add_body_force([0, 0, -1e4])
    sim.run(1, tmp_path / "out", progress=False, render=False)
    (vtu,) = sorted((tmp_path / "out").glob("b*.vtu"))[-1:]
    out = meshio.read(vtu)
    assert sum(len(c.data) for c in out.cells) == mesh.n_cells
    region = np.concatenate(out.cell_data["region"])
    np.testing.assert_array_equal(region, np.where(np.isin(np.arange(16), soft), 0, 1))
    _, x, _ = sim.body_state("b")
    J = body.cell_means(body.quadrature_fields(x)["J"])
    np.testing.assert_allclose(J, body.cell_fields(x)["J"], rtol=1e-12)
    assert np.ptp(J) > 1e-6  # a field that varies, so the order of the cells is tested


def test_regions_on_the_numba_path_equal_the_numpy_path():
    """Each region's fused loop scatters through its own stencil of the body's pattern."""
    from tissuesim.backend import numba_available

    if not numba_available():
        pytest.skip("numba not installed")
    mesh = ts.box((0, 0, 0), (1, 0.6, 0.5), (3, 2, 2))
    soft = _halves(mesh)
    rest = np.setdiff1d(np.arange(mesh.n_cells), soft)
    m1 = ts.make_material("neo_hookean", youngs_modulus=3.0, poisson_ratio=0.3)
    m2 = ts.make_material("stvk", youngs_modulus=7.0, poisson_ratio=0.2)
    regions = (("a", soft, m1, "displacement", None), ("b", rest, m2, "displacement", None))
    x = (mesh.points * 1.02 + 0.01 * np.sin(7 * mesh.points)).ravel()
    accs = []
    for backend in ("numpy", "numba"):
        model = Model(mesh, m1, 1.0, backend=backend, regions=regions)
        assert model.elastic.fused == (backend == "numba")
        accs.append(model.evaluate(x, 2, False))
    a, b = accs
    assert a.value == pytest.approx(b.value, rel=1e-12)
    np.testing.assert_allclose(a.gradient, b.gradient, atol=1e-12 * np.abs(a.gradient).max())
    np.testing.assert_allclose(a.hessian, b.hessian, atol=1e-12 * np.abs(a.hessian).max())


def test_a_resumed_run_keeps_each_regions_viscoelastic_history(tmp_path):
    """Checkpoints save the history of every region's law ("r<k>_H", ...): 2 steps, then a
    resumed run to 4, ends where 4 steps in one run end."""

    def make() -> ts.Simulation:
        mesh = ts.box((0, 0, 0), (0.1, 0.04, 0.04), (4, 2, 2), element="hex")
        elastic = {"model": "neo_hookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3}
        visco = ts.make_material("viscoelastic", elastic=elastic, g=[0.5], tau=[0.05])
        plain = ts.make_material("neo_hookean", youngs_modulus=2e4, poisson_ratio=0.3)
        sim = ts.Simulation(integrator="quasistatic", time_step=0.02)
        sim.add_body("b", mesh, plain, regions={"visco": (_halves(mesh), visco)})
        X = mesh.points
        sim.fix(np.flatnonzero(X[:, 0] == 0))
        end = np.flatnonzero(np.isclose(X[:, 0], 0.1))
        sim.add_dirichlet(end, lambda X, t: np.array([0.2 * t, 0, 0]) + 0 * X, body="b")
        return sim

    straight = make()
    straight.run(4, progress=False)
    make().run(2, tmp_path / "out", progress=False, render=False)
    resumed = make()
    resumed.run(4, tmp_path / "out", progress=False, render=False, resume=True)
    keys = resumed.body("b").model.material.state_arrays()
    assert sorted(keys) == ["r0_H", "r0_Se"]
    np.testing.assert_allclose(
        resumed.body_positions("b"), straight.body_positions("b"), rtol=0, atol=1e-12
    )


def test_a_scene_names_its_regions_by_the_mesh_files_cell_sets(tmp_path):
    """[[bodies.regions]]: cells by a cell set of the mesh file, an inline material; a cell
    set the file lacks is one line naming the table."""
    from tissuesim.errors import SceneError
    from tissuesim.mesh.io import write_mesh
    from tissuesim.scene.loader import load_scene

    mesh = ts.box((0, 0, 0), (0.1, 0.04, 0.04), (4, 2, 2), element="hex")
    soft = _halves(mesh)
    rest = np.setdiff1d(np.arange(mesh.n_cells), soft)
    write_mesh(ts.Mesh(mesh.points, mesh.cells, cell_sets={"soft": soft, "hard": rest}),
               tmp_path / "bar.msh")  # fmt: skip
    law = 'material = {{ model = "neo_hookean", youngs_modulus = {}, poisson_ratio = 0.3 }}'
    scene = f"""
[simulation]
integrator = "quasistatic"
time_step = 1.0

[[bodies]]
name = "bar"
mesh = {{ file = "bar.msh" }}

[[bodies.regions]]
name = "soft"
cells = "soft"
{law.format(1e4)}

[[bodies.regions]]
name = "hard"
cells = "hard"
density = 2000.0
{law.format(4e4)}
"""
    (tmp_path / "s.toml").write_text(scene)
    body = load_scene(tmp_path / "s.toml").simulation.body("bar")
    assert [(p.name, p.cells.size) for p in body.model.parts] == [("soft", 8), ("hard", 8)]
    assert body.model.parts[1].material.mu == pytest.approx(4e4 / 2.6)
    np.testing.assert_array_equal(body.model.density[rest], 2000.0)
    (tmp_path / "s.toml").write_text(scene.replace('cells = "hard"', 'cells = "bone"'))
    with pytest.raises(SceneError, match=r"bodies\[1\].regions\[2\]: cells must name one of"):
        load_scene(tmp_path / "s.toml")
