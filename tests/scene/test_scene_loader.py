"""TOML scene files: the shipped examples build, every mistake is a SceneError that names the
file and suggests the fix, and a scene builds exactly what the Python API builds."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.cli import example_path, list_examples
from tissuesim.errors import SceneError
from tissuesim.mesh import select, write_mesh
from tissuesim.scene.loader import load_scene

BASE = """
[mesh]
generator = "rectangle"
lower = [0.0, 0.0]
upper = [1.0, 1.0]
divisions = [3, 3]

[material]
model = "course_neo_hookean"
youngs_modulus = 1000.0
poisson_ratio = 0.3

[simulation]
density = 1.0
time_step = 0.05

[[dirichlet]]
vertices = { on_plane = { axis = 0, value = 0.0 } }
"""

GENERATED = BASE.split("\n\n[material]")[0].strip()


def write_scene(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def scene_error(tmp_path, text) -> str:
    path = write_scene(tmp_path, text)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert str(path) in message  # every error names the file
    return message


# -- the shipped examples -----------------------------------------------------------------------


def test_examples_are_listed():
    assert {"course_stretch", "course_literal", "beam_3d_gravity"} <= set(list_examples())


@pytest.mark.parametrize("name", list_examples())
def test_each_example_builds(name):
    scene = load_scene(example_path(name))
    assert scene.name == name
    sim = scene.simulation
    assert isinstance(sim, ts.Simulation)
    if sim.tissue is not None:
        assert sim.tissue.cuts
        assert any(
            b["prescribed_sets"] for b in sim.describe()["bodies"].values() if b["kind"] == "fem"
        )
    else:  # something holds the bodies: supports, or an obstacle they rest on
        assert sim.system.prescribed_dofs.size > 0 or sim.obstacles
    assert scene.run["steps"] > 0


def test_plain_scene_builds(tmp_path):
    scene = load_scene(write_scene(tmp_path, BASE + "[run]\nsteps = 3\nrender = false\n"))
    sim = scene.simulation
    assert sim.mesh.n_points == 16 and sim.time_step == 0.05
    assert sim.integrator == "backward_euler"
    assert scene.run == {"steps": 3, "render": False}
    assert scene.name == "scene"


# -- unknown keys suggest the right one ---------------------------------------------------------


def test_unknown_top_level_table(tmp_path):
    message = scene_error(tmp_path, BASE.replace("[material]", "[materail]"))
    assert "did you mean 'material'" in message


def test_unknown_simulation_key(tmp_path):
    message = scene_error(tmp_path, BASE.replace("time_step", "time_stpe"))
    assert "[simulation]" in message and "did you mean 'time_step'" in message


def test_unknown_newton_option(tmp_path):
    message = scene_error(tmp_path, BASE + "[newton]\nmax_iteration = 3\n")
    assert "[newton]" in message and "did you mean 'max_iterations'" in message


def test_bad_newton_value_names_the_table(tmp_path):
    message = scene_error(tmp_path, BASE + "[newton]\nhessian_projection = 'sometimes'\n")
    assert "[newton]" in message and "hessian_projection" in message


def test_unknown_linear_solver_fails_at_load_time(tmp_path):
    message = scene_error(tmp_path, BASE + "[newton]\nlinear_solver = 'magic'\n")
    assert "linear_solver" in message and "'magic'" in message


def test_unknown_material_model(tmp_path):
    message = scene_error(tmp_path, BASE.replace('"course_neo_hookean"', '"neo_hookan"'))
    assert "[material]" in message and "did you mean 'neo_hookean'" in message


def test_unknown_material_parameter(tmp_path):
    message = scene_error(tmp_path, BASE.replace("youngs_modulus", "youngs_modulos"))
    assert "[material]" in message and "did you mean 'youngs_modulus'" in message


def test_unknown_run_key_and_bad_run_values(tmp_path):
    assert "did you mean 'steps'" in scene_error(tmp_path, BASE + "[run]\nstep = 3\n")
    assert "steps must be an integer >= 0" in scene_error(tmp_path, BASE + "[run]\nsteps = -3\n")
    assert "every must be an integer >= 1" in scene_error(tmp_path, BASE + "[run]\nevery = 0\n")
    assert "render must be true or false" in scene_error(tmp_path, BASE + "[run]\nrender = 1\n")


# -- impossible values ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ("poisson_ratio = 0.3", "poisson_ratio = 0.5", "poisson_ratio"),
        ("youngs_modulus = 1000.0", "youngs_modulus = -1", "youngs_modulus"),
        ("poisson_ratio = 0.3", "poisson_ratio = -1.0", "poisson_ratio"),
    ],
)
def test_impossible_material_value_names_the_key(tmp_path, old, new, key):
    message = scene_error(tmp_path, BASE.replace(old, new))
    assert key in message and "[material]" in message


@pytest.mark.parametrize(
    ("old", "new", "named"),
    [
        ("time_step = 0.05", "time_step = -1.0", "time_step"),
        ("time_step = 0.05", "time_step = 0.0", "time_step"),
        ("time_step = 0.05", "time_step = true", "time_step"),
        ("time_step = 0.05", "time_step = '0.05'", "time_step"),
        ("density = 1.0", "density = 0.0", "density"),
        ("density = 1.0", "density = 1.0\nintegrator = 'rk4'", "integrator"),
        ("density = 1.0", "density = 1.0\nmass = 'lumpy'", "mass"),
        ("density = 1.0", "density = 1.0\nmax_step_halvings = -1", "max_step_halvings"),
    ],
)
def test_impossible_simulation_value_names_the_key(tmp_path, old, new, named):
    message = scene_error(tmp_path, BASE.replace(old, new))
    assert named in message and "[simulation]" in message


def test_missing_material_model(tmp_path):
    message = scene_error(tmp_path, BASE.replace('model = "course_neo_hookean"', ""))
    assert "[material]" in message and "missing key 'model'" in message


# -- selectors ---------------------------------------------------------------------------------


def test_selector_that_selects_nothing_names_the_plane(tmp_path):
    message = scene_error(tmp_path, BASE.replace("value = 0.0", "value = 5.0"))
    assert "[[dirichlet]] #1" in message
    assert "plane x = 5.0" in message
    assert "bounding box" in message


def test_bad_selector_kind(tmp_path):
    message = scene_error(tmp_path, BASE.replace("on_plane", "on_plain"))
    assert "[[dirichlet]] #1" in message and "did you mean 'on_plane'" in message


def test_bad_selector_argument(tmp_path):
    message = scene_error(tmp_path, BASE.replace("value = 0.0", "valu = 0.0"))
    assert "did you mean 'value'" in message


def test_selector_must_be_a_single_table(tmp_path):
    two = BASE.replace(
        "{ on_plane = { axis = 0, value = 0.0 } }",
        "{ on_plane = { axis = 0, value = 0.0 }, boundary = true }",
    )
    assert "one selector" in scene_error(tmp_path, two)
    assert "boundary = true" in scene_error(
        tmp_path, BASE + "[[traction]]\nfacets = { boundary = 1 }\ntraction = [0, 0]\n"
    )


def test_tagged_selector_lists_the_sets(tmp_path):
    message = scene_error(
        tmp_path, BASE.replace("on_plane = { axis = 0, value = 0.0 }", "tagged = 'nope'")
    )
    assert "'nope'" in message and "left" in message


def test_other_selectors_build(tmp_path):
    text = BASE + textwrap.dedent(
        """
        [[dirichlet]]
        vertices = { tagged = "right" }
        components = [1]

        [[dirichlet]]
        vertices = { in_box = { lower = [0.3, 0.9], upper = [0.7, 1.1] } }
        components = [0]

        [[traction]]
        facets = { boundary = true }
        traction = [0.0, 0.0]
        """
    )
    sim = load_scene(write_scene(tmp_path, text)).simulation
    right = select.vertices_on_plane(sim.mesh, 0, 1.0)
    top_middle = select.vertices_in_box(sim.mesh, [0.3, 0.9], [0.7, 1.1])
    left = select.vertices_on_plane(sim.mesh, 0, 0.0)
    expected = np.concatenate([2 * left, 2 * left + 1, 2 * right + 1, 2 * top_middle])
    np.testing.assert_array_equal(sim.model.prescribed.dofs, np.unique(expected))


# -- file errors -------------------------------------------------------------------------------


def test_invalid_toml_names_the_file(tmp_path):
    message = scene_error(tmp_path, BASE + "[simulation\n")
    assert "not valid TOML" in message


def test_missing_scene_file(tmp_path):
    with pytest.raises(SceneError, match="no such scene file"):
        load_scene(tmp_path / "nope.toml")


def test_missing_mesh_file_names_the_path(tmp_path):
    message = scene_error(tmp_path, BASE.replace(GENERATED, '[mesh]\nfile = "missing.vtu"'))
    assert str(tmp_path / "missing.vtu") in message and "[mesh]" in message


def test_mesh_file_cannot_be_combined_with_a_generator(tmp_path):
    message = scene_error(tmp_path, BASE.replace("[mesh]", '[mesh]\nfile = "a.vtu"'))
    assert "'file' cannot be combined" in message


def test_bad_generator_and_divisions(tmp_path):
    assert "generator" in scene_error(tmp_path, BASE.replace('"rectangle"', '"circle"'))
    message = scene_error(tmp_path, BASE.replace("divisions = [3, 3]", "divisions = [0, 3]"))
    assert "[mesh]" in message and "divisions" in message


def test_mesh_file_relative_to_the_scene_file(tmp_path, monkeypatch):
    scene_dir = tmp_path / "scenes"
    scene_dir.mkdir()
    mesh = ts.rectangle(lower=(0, 0), upper=(2, 1), divisions=(4, 2))
    write_mesh(mesh, scene_dir / "strip.vtu")
    path = write_scene(scene_dir, BASE.replace(GENERATED, '[mesh]\nfile = "strip.vtu"'))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    sim = load_scene(path).simulation
    np.testing.assert_allclose(sim.mesh.points, mesh.points)
    np.testing.assert_array_equal(sim.mesh.cells, mesh.cells)
    record = sim.step()
    assert record.converged


# -- conditions and loads ------------------------------------------------------------------------


def test_dirichlet_components_restricts_axes(tmp_path):
    text = BASE + textwrap.dedent(
        """
        [[dirichlet]]
        vertices = { on_plane = { axis = 0, value = 1.0 } }
        displacement = ["0.1 * t", "5.0"]
        components = [0]
        """
    )
    sim = load_scene(write_scene(tmp_path, text)).simulation
    right = select.vertices_on_plane(sim.mesh, 0, 1.0)
    sim.step()
    u = sim.displacement
    np.testing.assert_allclose(u[right, 0], 0.1 * sim.time, rtol=1e-12)
    assert np.abs(u[right, 1]).max() < 1.0  # y is free: the 5.0 was not imposed
    left = select.vertices_on_plane(sim.mesh, 0, 0.0)
    np.testing.assert_array_equal(u[left], 0.0)


@pytest.mark.parametrize(
    ("components", "named"), [("[5]", "components"), ("[]", "components"), ("0", "list of axes")]
)
def test_bad_dirichlet_components(tmp_path, components, named):
    text = BASE.replace("value = 0.0 } }", f"value = 0.0 }} }}\ncomponents = {components}")
    message = scene_error(tmp_path, text)
    assert named in message and "[[dirichlet]] #1" in message


def test_dirichlet_errors(tmp_path):
    assert "missing key 'vertices'" in scene_error(
        tmp_path, BASE + "[[dirichlet]]\ndisplacement = [0, 0]\n"
    )
    assert "write [[dirichlet]]" in scene_error(
        tmp_path, BASE.replace("[[dirichlet]]", "[dirichlet]")
    )
    message = scene_error(
        tmp_path, BASE.replace("value = 0.0 } }", "value = 0.0 } }\ndisplacement = 0.1")
    )
    assert "expected a list of 2" in message


def test_traction_with_a_time_expression(tmp_path):
    text = BASE + textwrap.dedent(
        """
        [[traction]]
        facets = { on_plane = { axis = 0, value = 1.0 } }
        traction = ["100 * t", 0]
        """
    )
    sim = load_scene(write_scene(tmp_path, text)).simulation
    x0 = sim.positions.copy()
    sim.step()
    right = select.vertices_on_plane(sim.mesh, 0, 1.0)
    assert np.all(sim.positions[right, 0] > x0[right, 0])  # pulled in +x


def test_traction_errors(tmp_path):
    right = "facets = { on_plane = { axis = 0, value = 1.0 } }\n"
    assert "missing key 'traction'" in scene_error(tmp_path, BASE + "[[traction]]\n" + right)
    assert "expected 2 components" in scene_error(
        tmp_path, BASE + "[[traction]]\n" + right + "traction = [1.0]\n"
    )
    message = scene_error(
        tmp_path, BASE + "[[traction]]\n" + right + "traction = ['sin(t)', 'q']\n"
    )
    assert "traction[1]" in message and "unknown name 'q'" in message
    message = scene_error(
        tmp_path,
        BASE
        + "[[traction]]\nfacets = { on_plane = { axis = 0, value = 0.5 } }\ntraction = [1, 0]\n",
    )
    assert "[[traction]] #1" in message and "no boundary facets on the plane x = 0.5" in message


def test_gravity_pulls_down(tmp_path):
    sim = load_scene(
        write_scene(tmp_path, BASE + "[gravity]\nacceleration = [0.0, -9.81]\n")
    ).simulation
    sim.step()
    free = np.setdiff1d(np.arange(sim.mesh.n_points), select.vertices_on_plane(sim.mesh, 0, 0.0))
    assert np.all(sim.displacement[free, 1] < 0)
    assert np.all(sim.velocity[free, 1] < 0)


def test_gravity_errors(tmp_path):
    message = scene_error(tmp_path, BASE + "[gravity]\nacceleration = [0.0, -9.81, 0.0]\n")
    assert "[gravity]" in message and "2 components" in message
    assert "acceleration" in scene_error(tmp_path, BASE + "[gravity]\naccel = [0.0, -9.81]\n")


def test_body_force(tmp_path):
    text = BASE + "[[body_force]]\nforce_density = [0, '-10 * x']\n"
    sim = load_scene(write_scene(tmp_path, text)).simulation
    sim.step()
    right = select.vertices_on_plane(sim.mesh, 0, 1.0)
    assert np.all(sim.displacement[right, 1] < 0)
    assert "missing key 'force_density'" in scene_error(tmp_path, BASE + "[[body_force]]\n")
    message = scene_error(tmp_path, BASE + "[[body_force]]\nforce_densty = [0, 1]\n")
    assert "did you mean 'force_density'" in message


def test_initial_velocity(tmp_path):
    text = BASE.replace("[[dirichlet]]\nvertices = { on_plane = { axis = 0, value = 0.0 } }\n", "")
    text += "[initial]\nvelocity = ['-y', 'x + 2**3']\n"
    sim = load_scene(write_scene(tmp_path, text)).simulation
    X = sim.mesh.points
    np.testing.assert_allclose(sim.velocity, np.column_stack([-X[:, 1], X[:, 0] + 8.0]))
    assert "expected a list of 2" in scene_error(
        tmp_path, BASE + "[initial]\nvelocity = [1, 2, 3]\n"
    )


def test_expression_that_would_write_into_the_mesh_is_refused(tmp_path):
    # sin(x, y) would pass y as NumPy's ``out`` and overwrite the rest positions.
    message = scene_error(tmp_path, BASE + "[initial]\nvelocity = ['sin(x, y)', 0]\n")
    assert "sin() takes 1 argument" in message


# -- a scene is the Python API -------------------------------------------------------------------


def test_scene_equals_python_api(tmp_path):
    text = textwrap.dedent(
        """
        [mesh]
        generator = "rectangle"
        lower = [-1.0, -1.0]
        upper = [1.0, 1.0]
        divisions = [4, 4]

        [material]
        model = "course_neo_hookean"
        youngs_modulus = 1000.0
        poisson_ratio = 0.3

        [simulation]
        density = 2.0
        integrator = "backward_euler"
        time_step = 0.05
        mass = "lumped"

        [newton]
        gradient_tolerance = 1e-10

        [[dirichlet]]
        vertices = { on_plane = { axis = 0, value = -1.0 } }
        displacement = ["x * sin(t)", "0"]

        [[dirichlet]]
        vertices = { on_plane = { axis = 0, value = 1.0 } }
        displacement = ["x * sin(t)", "0"]

        [[traction]]
        facets = { on_plane = { axis = 1, value = 1.0 } }
        traction = ["0", "3 * t"]

        [gravity]
        acceleration = [0.0, -9.81]

        [initial]
        velocity = ["0", "0.1 * x"]
        """
    )
    from_scene = load_scene(write_scene(tmp_path, text)).simulation

    mesh = ts.rectangle(lower=(-1.0, -1.0), upper=(1.0, 1.0), divisions=(4, 4))
    sim = ts.Simulation(
        mesh,
        ts.make_material("course_neo_hookean", youngs_modulus=1000.0, poisson_ratio=0.3),
        density=2.0,
        integrator="backward_euler",
        time_step=0.05,
        mass="lumped",
        newton=ts.NewtonOptions(gradient_tolerance=1e-10),
    )

    def stretch(X, t):
        return np.column_stack([X[:, 0] * np.sin(t), np.zeros(len(X))])

    sim.add_dirichlet(select.vertices_on_plane(mesh, 0, -1.0), stretch)
    sim.add_dirichlet(select.vertices_on_plane(mesh, 0, 1.0), stretch)
    sim.add_traction(
        select.facets_on_plane(mesh, 1, 1.0),
        lambda X, t: np.column_stack([np.zeros(len(X)), np.full(len(X), 3 * t)]),
    )
    sim.add_gravity([0.0, -9.81])
    sim.set_velocity(np.column_stack([np.zeros(mesh.n_points), 0.1 * mesh.points[:, 0]]))

    for _ in range(3):
        a, b = from_scene.step(), sim.step()
        assert a.newton_iterations == b.newton_iterations
    assert from_scene.time == sim.time
    np.testing.assert_allclose(from_scene.positions, sim.positions, rtol=0, atol=1e-12)
    np.testing.assert_allclose(from_scene.velocity, sim.velocity, rtol=0, atol=1e-12)
    assert np.abs(sim.displacement).max() > 1e-3  # something happened
