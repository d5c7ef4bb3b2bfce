"""FEBio's quad8 shells (kinematics/shell.py, febio/shells.py): hexahedron20 cells read as
the 16-node shell (quad8 in the plane times linear through the thickness, FEBio's
FEShellQuad8G18 rule); its shape functions and rule, patch test, energy, gradient and
Hessian against finite differences on both backends, mass; a quad8 cantilever deck against
the beam and against the same plate built with ``solid_shell`` in the API."""

import os
import warnings
from pathlib import Path

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.backend import numba_available
from tissuesim.febio import load_febio, read_feb
from tissuesim.kinematics.shell import shell_rule, shell_shape_functions
from tissuesim.materials.registry import make_material
from tissuesim.mesh.cells import tensor_quadratic as tq
from tissuesim.mesh.checks import validate_mesh
from tissuesim.model import Model

L, W, H, E = 1.0, 0.2, 0.1, 1000.0  # the plate (neo-Hookean, v = 0)
NX = 10  # quad8 elements along the plate (one across)
P = 1e-4  # the tip's load


def distorted_box(amount=0.03, seed=4):
    """A 2 x 2 x 1 hexahedron20 box with every node moved a little (curved, warped cells)."""
    mesh = ts.box(divisions=(2, 2, 1), element="hex20")
    p = mesh.points + amount * np.random.default_rng(seed).uniform(-1, 1, mesh.points.shape)
    return validate_mesh(p, mesh.cells, source="distorted")


def model(mesh, law="neo_hookean", backend="numpy", nu=0.3):
    mat = make_material(law, youngs_modulus=1e3, poisson_ratio=nu)
    return Model(mesh, mat, np.full(mesh.n_cells, 2.0), backend=backend, formulation="shell")


def test_shape_functions_and_febios_rule():
    """The 16 functions are 1 at their node and 0 at the others (VTK's hexahedron20 nodes),
    sum to 1, their gradients to 0; nodes 16-19 have none; the rule is FEBio's
    FEShellQuad8G18 (3 x 3 Gauss points in the plane, +-1/sqrt(3) through the thickness)."""
    nodes = tq.NODES["hexahedron20"]
    N, dN = shell_shape_functions(nodes[:16])
    np.testing.assert_allclose(N[:, :16], np.eye(16), atol=1e-15)
    assert not N[:, 16:].any() and not dN[:, 16:].any()
    xi = np.random.default_rng(1).uniform(-1, 1, (7, 3))
    N, dN = shell_shape_functions(xi)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(dN.sum(axis=1), 0.0, atol=1e-14)
    h = 1e-6  # the gradients against central differences
    for k in range(3):
        step = np.zeros(3)
        step[k] = h
        fd = (shell_shape_functions(xi + step)[0] - shell_shape_functions(xi - step)[0]) / (2 * h)
        np.testing.assert_allclose(dN[:, :, k], fd, atol=1e-9)
    points, weights = shell_rule()
    a, c = 0.774596669241483, 0.577350269189626
    w1, w2 = 5 / 9, 8 / 9
    febio = {(r, s, t): wr * ws for t in (-c, c) for (s, ws) in ((-a, w1), (0, w2), (a, w1))
             for (r, wr) in ((-a, w1), (0, w2), (a, w1))}  # fmt: skip
    assert len(points) == 18
    for p, w in zip(points, weights, strict=True):
        key = min(febio, key=lambda q: np.linalg.norm(np.subtract(q, p)))
        np.testing.assert_allclose(p, key, atol=1e-14)
        assert w == pytest.approx(febio[key], rel=1e-12)


def test_patch_test_and_midsides_held():
    """A linear field gives the same F at every point of every warped cell, the weights sum
    to the volume; the vertical edges' midside nodes carry no force and are held."""
    mesh = distorted_box()
    md = model(mesh)
    A = np.eye(3) + 0.1 * np.arange(9).reshape(3, 3) / 9
    x = (mesh.points @ A.T + 0.3).ravel()
    F = md.kinematics.deformation_gradients(x)
    np.testing.assert_allclose(F, np.broadcast_to(A, F.shape), atol=1e-13)
    q1 = model(ts.box(divisions=(2, 2, 1), element="hex20"))
    assert q1.kinematics.weights.sum() == pytest.approx(1.0, rel=1e-13)
    mid = np.unique(mesh.cells[:, 16:])
    assert len(mid) == 9
    y = mesh.points.ravel() + 0.05 * np.random.default_rng(3).standard_normal(mesh.points.size)
    g = md.evaluate(y, 1, False).gradient.reshape(-1, 3)
    assert not g[mid].any() and abs(g).max() > 1.0
    np.testing.assert_array_equal(
        md.prescribed.dofs, np.sort((mid[:, None] * 3 + range(3)).ravel())
    )


@pytest.mark.parametrize("law", ["neo_hookean", "stvk", "fixed_corotated"])
def test_energy_gradient_hessian_match_finite_differences(law):
    mesh = distorted_box()
    md = model(mesh, law, nu=0.45)
    rng = np.random.default_rng(7)
    x = mesh.points.ravel() + 0.02 * rng.standard_normal(mesh.points.size)
    acc = md.evaluate(x, 2, False)
    Hm = md.pattern.matrix(acc.hessian)
    dx = rng.standard_normal(x.size)
    eps = 1e-6
    e_plus, e_minus = md.evaluate(x + eps * dx, 1, False), md.evaluate(x - eps * dx, 1, False)
    assert (e_plus.value - e_minus.value) / (2 * eps) == pytest.approx(acc.gradient @ dx, rel=1e-6)
    fd_H = (e_plus.gradient - e_minus.gradient) / (2 * eps)
    np.testing.assert_allclose(fd_H, Hm @ dx, rtol=0, atol=1e-6 * np.abs(Hm @ dx).max())
    assert abs(Hm - Hm.T).max() <= 1e-12 * abs(Hm).max()


@pytest.mark.skipif(not numba_available(), reason="numba not installed")
def test_fused_numba_loop_equals_numpy():
    mesh = distorted_box()
    x = mesh.points.ravel() + 0.02 * np.random.default_rng(2).standard_normal(mesh.points.size)
    a = model(mesh).evaluate(x, 2, False)
    fused = model(mesh, backend="numba")
    assert fused.elastic.fused
    b = fused.evaluate(x, 2, False)
    assert b.value == pytest.approx(a.value, rel=1e-12)
    np.testing.assert_allclose(b.gradient, a.gradient, atol=1e-11 * abs(a.gradient).max())
    np.testing.assert_allclose(b.hessian, a.hessian, atol=1e-11 * abs(a.hessian).max())


def test_mass_is_the_shells_and_exact():
    """The consistent mass of the 16 functions: total rho V, none on the midside nodes
    through the thickness, and on a box the same as a 5 x 5 x 4 Gauss rule's (exact)."""
    mesh = ts.box(upper=(2.0, 1.0, 0.1), divisions=(2, 1, 1), element="hex20")
    md = model(mesh)
    ones = np.tile([1.0, 0.0, 0.0], mesh.n_points)
    assert ones @ md.mass.dot(ones) == pytest.approx(2.0 * 0.2, rel=1e-13)
    mid = np.unique(mesh.cells[:, 16:])
    e = np.zeros(mesh.n_points * 3)
    e[mid * 3] = 1.0
    assert not md.mass.dot(e).any()
    x5, w5 = np.polynomial.legendre.leggauss(5)
    x4, w4 = np.polynomial.legendre.leggauss(4)
    t, s, r = np.meshgrid(x4, x5, x5, indexing="ij")
    xi = np.column_stack([r.ravel(), s.ravel(), t.ravel()])
    w = np.einsum("i,j,k->ijk", w4, w5, w5).ravel()
    N, dN = shell_shape_functions(xi)
    J = np.einsum("mai,qaj->mqij", mesh.points[mesh.cells], dN)
    exact = np.einsum("mq,qa,qb->mab", 2.0 * w * np.linalg.det(J), N, N)
    u = np.random.default_rng(5).standard_normal(mesh.n_points)
    v = np.zeros(mesh.n_points * 3)
    v[0::3] = u
    want = np.einsum("mab,mb->ma", exact, u[mesh.cells])
    got = np.zeros(mesh.n_points)
    np.add.at(got, mesh.cells, want)
    np.testing.assert_allclose(md.mass.dot(v)[0::3], got, atol=1e-14)


# -- a quad8 cantilever deck ------------------------------------------------------------------
def plate() -> tuple[np.ndarray, np.ndarray]:
    """(points, quad8 faces) of the L x W plate, NX x 1 elements, node ids in row order."""
    ids, points = {}, []
    for j in range(3):
        for i in range(2 * NX + 1):
            if i % 2 and j % 2:
                continue  # no centre node
            ids[i, j] = len(points)
            points.append((i * L / (2 * NX), j * W / 2, 0.0))
    faces = [
        [ids[i, 0], ids[i + 2, 0], ids[i + 2, 2], ids[i, 2],
         ids[i + 1, 0], ids[i + 2, 1], ids[i + 1, 2], ids[i, 1]]
        for i in range(0, 2 * NX, 2)
    ]  # fmt: skip
    return np.array(points), np.array(faces)


def deck() -> str:
    points, faces = plate()
    nodes = "\n".join(
        f'      <node id="{k + 1}">{x!r},{y!r},{z!r}</node>'
        for k, (x, y, z) in enumerate(points.tolist())
    )
    elems = "\n".join(
        f'      <elem id="{k + 1}">{", ".join(str(i + 1) for i in f)}</elem>'
        for k, f in enumerate(faces)
    )
    clamped = ", ".join(str(i + 1) for i in np.flatnonzero(np.isclose(points[:, 0], 0.0)))
    tip = ", ".join(str(i + 1) for i in np.flatnonzero(np.isclose(points[:, 0], L)))
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>2</time_steps>
    <step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="plate" type="neo-Hookean">
      <density>1</density>
      <E>{E}</E>
      <v>0</v>
    </material>
  </Material>
  <Mesh>
    <Nodes name="all">
{nodes}
    </Nodes>
    <Elements type="quad8" name="plate">
{elems}
    </Elements>
    <NodeSet name="clamped">{clamped}</NodeSet>
    <NodeSet name="tip">{tip}</NodeSet>
  </Mesh>
  <MeshDomains>
    <ShellDomain name="plate" mat="plate">
      <shell_thickness>{H}</shell_thickness>
    </ShellDomain>
  </MeshDomains>
  <Boundary>
    <bc name="clamp" node_set="clamped" type="zero displacement">
      <x_dof>1</x_dof><y_dof>1</y_dof><z_dof>1</z_dof>
    </bc>
    <bc name="clamp_back" node_set="clamped" type="zero shell displacement">
      <sx_dof>1</sx_dof><sy_dof>1</sy_dof><sz_dof>1</sz_dof>
    </bc>
  </Boundary>
  <Loads>
    <nodal_load name="tip" node_set="tip" type="nodal_force">
      <value lc="1">0,0,{1 / 3!r}</value>
    </nodal_load>
  </Loads>
  <LoadData>
    <load_controller id="1" name="LC1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <points><pt>0,0</pt><pt>1,{P!r}</pt></points>
    </load_controller>
  </LoadData>
</febio_spec>
"""


def run_deck(path: Path):
    """(model, scene, simulation) of the deck at ``path``, run to its end."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = read_feb(path)
        scene = load_febio(path)
        sim = scene.simulation
        for _ in range(scene.run["steps"]):
            sim.step()
    return model, scene, sim


@pytest.fixture(scope="module")
def cantilever(tmp_path_factory):
    path = tmp_path_factory.mktemp("quad8") / "cantilever_quad8.feb"
    path.write_text(deck())
    model, scene, sim = run_deck(path)
    return model, sim.body_positions("body"), scene, path


def test_quad8_cantilever_against_the_beam(cantilever):
    """Tip deflection of the 10 x 1 quad8 plate: the Timoshenko beam P L^3 / (3 E I) +
    P L / (k G A) (0.002012) within 0.3 %: the quadratic element bends without the bilinear
    one's locking (80 quad4 elements give 0.9911 of it, test_febio_shells.py)."""
    model, x, scene, _ = cantilever
    assert scene.simulation.mesh.cell_type == "hexahedron20"
    n = len(plate()[0])
    tip = np.isclose(model.nodes[:n, 0], L)
    deflection = (x - model.nodes)[:n][tip, 2].mean()
    I, G = W * H**3 / 12, E / 2
    beam = P * L**3 / (3 * E * I) + P * L / (5 / 6 * G * W * H)
    assert deflection == pytest.approx(beam, rel=3e-3)


def test_back_nodes_and_midsides_of_the_deck(cantilever):
    """One back node per shell node at X - D (D = 0.1 z on the flat plate), one midside node
    per corner node halfway; the cells are hexahedra20, the back face first."""
    model, _, _, _ = cantilever
    points, faces = plate()
    n, corners = len(points), len(np.unique(faces[:, :4]))
    assert model.nodes.shape == (2 * n + corners, 3)
    np.testing.assert_allclose(model.nodes[n : 2 * n], points - [0, 0, H], atol=1e-15)
    np.testing.assert_allclose(model.nodes[2 * n :, 2], -H / 2, atol=1e-15)
    cells = model.parts["plate"][1]
    assert cells.shape == (NX, 20)
    np.testing.assert_array_equal(cells[:, 4:8], faces[:, :4])
    np.testing.assert_array_equal(cells[:, 12:16], faces[:, 4:])
    assert (cells[:, :4] >= n).all() and (cells[:, 16:] >= 2 * n).all()


def test_quad8_plate_equals_the_solid_shell_built_in_the_api(cantilever):
    """The same plate through the API: solid_shell on the quad8 faces (reference "top",
    FEBio's directors), formulation "shell", clamped and loaded as the deck: the same
    positions to round-off (the deck's rows are the API mesh's: front, back, midsides)."""
    model, x, _, _ = cantilever
    points, faces = plate()
    mesh = ts.mesh.solid_shell(points, faces, H, reference="top", normalize=False)
    assert mesh.cell_type == "hexahedron20"
    np.testing.assert_allclose(mesh.points, model.nodes, atol=1e-15)
    sim = ts.Simulation(integrator="quasistatic", time_step=0.5)
    sim.add_body("body", mesh, ts.NeoHookean(youngs_modulus=E, poisson_ratio=0.0),
                 density=1.0, formulation="shell")  # fmt: skip
    n = len(points)
    sim.add_dirichlet(np.flatnonzero(np.isclose(mesh.points[: 2 * n, 0], 0.0)))
    tip = np.flatnonzero(np.isclose(mesh.points[:n, 0], L))
    sim.add_nodal_forces(tip, lambda t: np.tile([0.0, 0.0, P * t / 3], (len(tip), 1)))
    sim.step()
    sim.step()
    np.testing.assert_allclose(sim.body_positions("body"), x, rtol=0, atol=1e-12)


def test_three_field_quad8_is_refused_in_one_line(cantilever, tmp_path):
    from tissuesim.errors import InputError

    path = Path(cantilever[3])
    text = path.read_text().replace(
        '<ShellDomain name="plate" mat="plate">',
        '<ShellDomain name="plate" mat="plate" type="three-field-shell">',
    )
    bad = tmp_path / "three.feb"
    bad.write_text(text)
    with pytest.raises(
        InputError, match=r"three.feb:\d+ <ShellDomain>: three-field-shell on quad8"
    ):
        read_feb(bad)


# -- a follower pressure on quad8 faces ------------------------------------------------------
def test_quad8_face_pressure_loads_and_their_stiffness():
    """FEBio's FEQuad8G9 pressure on a flat rectangle a x b (midside nodes halfway): p a b
    along the normal, -1/12 of it at each corner and 1/3 at each midside node (the
    serendipity element's consistent load); on a warped face its stiffness dG/dx against
    central differences."""
    from tissuesim.energies.pressure_lag import facet_loads, facet_stiffness

    a, b, p = 2.0, 0.5, 3.0
    corners = np.array([[0, 0, 0], [a, 0, 0], [a, b, 0], [0, b, 0]], dtype=float)
    X = np.concatenate([corners, 0.5 * (corners + np.roll(corners, -1, axis=0))])[None]
    G = facet_loads(X, p)[0]
    np.testing.assert_allclose(G[:, :2], 0.0, atol=1e-14)
    np.testing.assert_allclose(G[:4, 2], -p * a * b / 12, rtol=1e-13)
    np.testing.assert_allclose(G[4:, 2], p * a * b / 3, rtol=1e-13)
    rng = np.random.default_rng(8)
    Y = X + 0.1 * rng.standard_normal(X.shape)
    K = facet_stiffness(Y, p)[0].reshape(24, 24)
    dx = rng.standard_normal(24)
    eps = 1e-6
    up = facet_loads(Y + eps * dx.reshape(1, 8, 3), p)[0].ravel()
    down = facet_loads(Y - eps * dx.reshape(1, 8, 3), p)[0].ravel()
    np.testing.assert_allclose((up - down) / (2 * eps), K @ dx, atol=1e-8 * abs(K @ dx).max())


def with_pressure(text: str, p: float) -> str:
    """The cantilever deck with a follower pressure p on its shells' front faces (all of
    them) instead of the tip load."""
    _, faces = plate()
    quads = "".join(
        f'<quad8 id="{k + 1}">{",".join(str(i + 1) for i in f)}</quad8>'
        for k, f in enumerate(faces)
    )
    text = text.replace("  </Mesh>", f'    <Surface name="top">{quads}</Surface>\n  </Mesh>')
    start, end = text.index("    <nodal_load"), text.index("</nodal_load>") + len("</nodal_load>")
    load = (
        '<surface_load name="press" surface="top" type="pressure">'
        f'<pressure lc="1">{p / P!r}</pressure><linear>0</linear></surface_load>'
    )
    return text[:start] + load + text[end:]


def test_quad8_plate_under_a_follower_pressure_equals_the_api(tmp_path):
    """A follower pressure on the quad8 shells' front faces (FEBio's pressure load, sh55,
    sh57): the deck and the API's solid_shell with add_follower_pressure on the mesh's top
    facets end at the same positions (1e-10), the tip's deflection within 0.3 % of the
    Timoshenko beam under q = p W."""
    path = tmp_path / "pressed.feb"
    p = 2e-2
    path.write_text(with_pressure(deck(), p))
    model, scene, sim = run_deck(path)
    x = sim.body_positions("body")
    points, faces = plate()
    mesh = ts.mesh.solid_shell(points, faces, H, reference="top", normalize=False)
    api = ts.Simulation(integrator="quasistatic", time_step=0.5)
    api.add_body("body", mesh, ts.NeoHookean(youngs_modulus=E, poisson_ratio=0.0),
                 density=1.0, formulation="shell")  # fmt: skip
    n = len(points)
    api.add_dirichlet(np.flatnonzero(np.isclose(mesh.points[: 2 * n, 0], 0.0)))
    api.add_follower_pressure(mesh.facet_sets["top"], lambda t: p * t)
    api.step()
    api.step()
    np.testing.assert_allclose(api.body_positions("body"), x, rtol=0, atol=1e-10)
    tip = np.isclose(model.nodes[:n, 0], L)
    q, I, G = p * W, W * H**3 / 12, E / 2  # the beam under q per length, down (the normal's +z)
    beam = q * L**4 / (8 * E * I) + q * L**2 / (2 * 5 / 6 * G * W * H)
    assert (x - model.nodes)[:n][tip, 2].mean() == pytest.approx(-beam, rel=3e-3)


@pytest.mark.skipif(
    not numba_available() or os.environ.get("TISSUESIM_BACKEND", "auto") not in ("", "auto"),
    reason="numba not installed, or the backend set by TISSUESIM_BACKEND",
)
def test_auto_backend_weighs_a_shell_cell_as_the_work_it_is():
    """A shell cell is 18 points of 60 x 60 Hessians: "auto" counts it as 450 tetrahedra, so
    even a small shell mesh runs the fused loop (NumPy took 0.7 s per Hessian on FEBio's
    sh57, 180 cells), while the same cells as plain hexahedra20 stay under the threshold."""
    mesh = ts.box(divisions=(2, 2, 1), element="hex20")
    mat = make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    shell = Model(mesh, mat, np.full(mesh.n_cells, 2.0), formulation="shell")
    solid = Model(mesh, mat, np.full(mesh.n_cells, 2.0))
    assert shell.backend == "numba" and shell.elastic.fused
    assert solid.backend == "numpy"


def test_a_scene_of_quad8_shell_faces_runs_as_the_api(cantilever):
    """A scene's mesh = { generator = "shell", quad8 faces } with formulation = "shell" builds
    the same hexahedra20 and runs the shell element: the plate's tip load through the scene
    gives the deck's positions (1e-12; the flat plate's directors need no normalize = false)."""
    from tissuesim.scene.loader import build_scene

    _, x, _, _ = cantilever
    points, faces = plate()
    mesh = {"generator": "shell", "points": points.tolist(), "faces": faces.tolist(),
            "thickness": H, "reference": "top"}  # fmt: skip
    table = {
        "simulation": {
            "integrator": "quasistatic",
            "time_step": 0.5,
            "density": 1.0,
            "formulation": "shell",
        },
        "mesh": mesh,
        "material": {"model": "neo_hookean", "youngs_modulus": E, "poisson_ratio": 0.0},
        "dirichlet": [{"vertices": {"on_plane": {"axis": 0, "value": 0.0}}}],
        "nodal_forces": [
            {
                "vertices": {
                    "in_box": {"lower": [L - 1e-9, -1.0, -1e-9], "upper": [2.0, 1.0, 1.0]}
                },
                "force": ["0.0", "0.0", f"{P / 3!r} * t"],
            }
        ],  # the front face's tip: its 3 nodes
    }
    sim = build_scene(table, name="shell").simulation
    assert sim.mesh.cell_type == "hexahedron20"
    sim.step()
    sim.step()
    np.testing.assert_allclose(sim.body_positions("body"), x, rtol=0, atol=1e-12)


def test_a_condition_on_a_quad8_surface_holds_its_midside_nodes(tmp_path):
    """ "@surface:name" in a condition is every node of the surface's facets, as in FEBio: a
    quad8 facet's four midside nodes too (the reader had kept only the corners of the set,
    which is what FEBio's norm and the logfiles read: ma57, sh24). The tip element's facet
    lifted by d: its eight front nodes end at z = d, the corners and the midsides."""
    _, faces = plate()
    tip = faces[-1]
    facet = f'<quad8 id="1">{",".join(str(i + 1) for i in tip)}</quad8>'
    text = deck().replace("  </Mesh>", f'    <Surface name="tip_face">{facet}</Surface>\n  </Mesh>')
    start, end = text.index("    <nodal_load"), text.index("</nodal_load>") + len("</nodal_load>")
    d = 1e-3
    lift = (
        '<bc name="lift" node_set="@surface:tip_face" type="prescribed displacement">'
        f'<dof>z</dof><value lc="1">{d / P!r}</value><relative>0</relative></bc>\n'
    )
    text = (text[:start] + text[end:]).replace("  </Boundary>", f"    {lift}  </Boundary>")
    path = tmp_path / "lifted.feb"
    path.write_text(text)
    model, scene, sim = run_deck(path)
    np.testing.assert_array_equal(model.node_sets["@surface:tip_face"], np.sort(tip))
    assert model.surfaces["tip_face"][0].tolist() == [tip[:4].tolist()]  # the corner facet
    u = sim.body_positions("body") - model.nodes
    np.testing.assert_allclose(u[tip, 2], d, rtol=1e-12)
    assert u[: len(plate()[0]), 2].max() == pytest.approx(d, rel=1e-12)  # the tip is the top
