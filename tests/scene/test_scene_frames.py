"""Frame scenes ([frames] tables): every table and selector builds what the Python API builds,
and every mistake is a SceneError naming the file, the table and the key, saying how to fix it."""

from __future__ import annotations

import textwrap

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.cli import example_path, list_examples
from tissuesim.errors import SceneError
from tissuesim.frames.placement import farthest_point_frames, grid_frames
from tissuesim.frames.sampling import (
    box_surface,
    ellipsoid_surface,
    sample_box,
    sample_ellipsoid,
    sample_mesh,
    sample_surface,
    surface_from_mesh,
)
from tissuesim.mesh import write_mesh
from tissuesim.scene.loader import load_scene
from tissuesim.simulation import Simulation

# A small body (40 integration points, 4 frames) so that every test builds in milliseconds.
BASE = """
[frames]
grid = { lower = [0.2, 0.2, 0.0], upper = [0.2, 0.2, 2.0], counts = [1, 1, 4] }

[region]
box = { lower = [0.0, 0.0, 0.0], upper = [0.4, 0.4, 2.0] }
spacing = 0.2

[material]
model = "stvk"
youngs_modulus = 1e5
poisson_ratio = 0.3

[simulation]
density = 1000.0
time_step = 0.02

[[fixed_frames]]
frames = { on_plane = { axis = 2, value = 0.0 } }
"""

FEM = """
[mesh]
generator = "rectangle"
lower = [0.0, 0.0]
upper = [1.0, 1.0]
divisions = [2, 2]

[material]
model = "linear"
youngs_modulus = 1000.0
poisson_ratio = 0.3
"""


def write_scene(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def build(tmp_path, text) -> Simulation:
    sim = load_scene(write_scene(tmp_path, text)).simulation
    assert isinstance(sim, Simulation)
    return sim


def scene_error(tmp_path, text) -> str:
    path = write_scene(tmp_path, text)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert str(path) in message  # every error names the file
    return message


# -- the shipped example ------------------------------------------------------------------------


def test_frames_example_is_listed():
    assert "frames_block_sag" in list_examples()


def test_frames_example_loads_and_runs_two_steps():
    scene = load_scene(example_path("frames_block_sag"))
    sim = scene.simulation
    assert isinstance(sim, Simulation)
    assert sim.n_frames == 6 and sim.model.samples.n == 320
    assert sim.model.frame_type.name == "rigid" and sim.integrator == "backward_euler"
    np.testing.assert_array_equal(sim.model.prescribed_frames, [0])  # the z = 0 frame
    assert sim.surface is not None
    assert scene.run["steps"] > 0 and scene.run.get("every", 1) >= 1
    for _ in range(2):
        assert sim.step().converged
    u = sim.frame_positions - sim.rest_frames
    assert np.all(u[0] == 0)
    assert u[-1, 1] < 0 and abs(u[-1, 0]) < 1e-9  # the tip moves down (-y), not sideways


# -- a scene is the Python API ------------------------------------------------------------------


def test_scene_equals_python_api(tmp_path):
    text = BASE + textwrap.dedent(
        """
        [gravity]
        acceleration = [0.0, -9.81, 0.0]

        [[prescribed_frames]]
        frames = { on_plane = { axis = 2, value = 2.0 } }
        displacement = ["0", "0.1 * t", "0"]
        rotation = ["0", "0", "0.5 * t"]

        [[springs]]
        points = [[0.2, 0.2, 1.0]]
        stiffness = 100.0
        target = ["0.2", "0.2 - 0.1 * t", "1.0"]

        [[point_forces]]
        points = { surface_on_plane = { axis = 2, value = 2.0 } }
        force = ["0", "-0.01", "0"]

        [initial]
        velocity = [0.0, 0.0, 0.01]
        """
    )
    scene_sim = build(tmp_path, text)

    lower, upper = [0.0, 0.0, 0.0], [0.4, 0.4, 2.0]
    frames = grid_frames([0.2, 0.2, 0.0], [0.2, 0.2, 2.0], (1, 1, 4))
    material = ts.StVenantKirchhoff(youngs_modulus=1e5, poisson_ratio=0.3)
    sim = Simulation.from_frames(
        frames, sample_box(lower, upper, 0.2), material, density=1000.0, time_step=0.02
    )
    sim.embed_surface(box_surface(lower, upper, (2, 2, 10)))  # the scene's: extent / spacing
    sim.add_gravity([0.0, -9.81, 0.0])
    sim.fix_frames([0])
    sim.prescribe_frames([3], lambda t: ([0.0, 0.1 * t, 0.0], [0.0, 0.0, 0.5 * t]))
    sim.add_spring(
        np.array([[0.2, 0.2, 1.0]]), 100.0, lambda t: np.array([[0.2, 0.2 - 0.1 * t, 1.0]])
    )
    top = sim.surface.points[np.abs(sim.surface.points[:, 2] - 2.0) < 1e-9]
    sim.add_point_forces(top, [0.0, -0.01, 0.0])
    sim.set_velocity([0.0, 0.0, 0.01])

    np.testing.assert_array_equal(scene_sim.rest_frames, sim.rest_frames)
    assert scene_sim.model.samples.n == sim.model.samples.n == 40
    np.testing.assert_array_equal(scene_sim.model.samples.points, sim.model.samples.points)
    np.testing.assert_array_equal(scene_sim.surface.triangles, sim.surface.triangles)
    np.testing.assert_array_equal(scene_sim.model.prescribed_frames, [0, 3])
    np.testing.assert_array_equal(scene_sim.state.v, sim.state.v)
    for _ in range(2):
        scene_sim.step()
        sim.step()
    assert scene_sim.time == pytest.approx(0.04)
    np.testing.assert_allclose(scene_sim.state.x, sim.state.x, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(scene_sim.state.v, sim.state.v, rtol=1e-10, atol=1e-12)
    # the prescribed tip frame is where its expressions put it
    np.testing.assert_allclose(scene_sim.frame_positions[3], [0.2, 0.2 + 0.1 * 0.04, 2.0])


# -- frames, region and simulation options -------------------------------------------------------


def test_frame_options_reach_the_model(tmp_path):
    text = BASE.replace(
        "[frames]",
        '[frames]\ntype = "affine"\nshape = "shepard"\nmin_frames = 2\nradius_factor = 2.0',
    ).replace("time_step = 0.02", 'time_step = 0.05\nintegrator = "quasistatic"\nmass = "lumped"')
    sim = build(tmp_path, text)
    assert sim.model.frame_type.name == "affine" and sim.model.shape == "shepard"
    assert sim.model.min_frames == 2 and sim.model.radius_factor == 2.0
    assert sim.integrator == "quasistatic" and sim.time_step == 0.05
    assert sim.model.mass_kind == "lumped"


def test_scalar_radius(tmp_path):
    sim = build(tmp_path, BASE.replace("[frames]", "[frames]\nradius = 0.9"))
    np.testing.assert_allclose(sim.model.shapes.radii, 0.9)


def test_frames_by_count_use_farthest_point_sampling(tmp_path):
    text = BASE.replace(
        "grid = { lower = [0.2, 0.2, 0.0], upper = [0.2, 0.2, 2.0], counts = [1, 1, 4] }",
        "count = 5",
    ).replace("value = 0.0 }", "value = 0.1 }")  # sample points are cell centres: z = 0.1
    sim = build(tmp_path, text)
    samples = sample_box([0, 0, 0], [0.4, 0.4, 2.0], 0.2)
    np.testing.assert_array_equal(sim.rest_frames, farthest_point_frames(samples.points, 5))
    assert sim.model.prescribed_frames.size >= 1


def test_frames_by_positions(tmp_path):
    text = BASE.replace(
        "grid = { lower = [0.2, 0.2, 0.0], upper = [0.2, 0.2, 2.0], counts = [1, 1, 4] }",
        "positions = [[0.2, 0.2, 0.0], [0.2, 0.2, 1.0], [0.2, 0.2, 2.0]]",
    )
    sim = build(tmp_path, text)
    np.testing.assert_array_equal(sim.rest_frames[:, 2], [0.0, 1.0, 2.0])


def test_ellipsoid_region(tmp_path):
    text = BASE.replace(
        "box = { lower = [0.0, 0.0, 0.0], upper = [0.4, 0.4, 2.0] }",
        "ellipsoid = { center = [0.2, 0.2, 1.0], semi_axes = [0.2, 0.2, 1.0] }\nsubsamples = 2",
    )
    sim = build(tmp_path, text)
    expected = sample_ellipsoid([0.2, 0.2, 1.0], [0.2, 0.2, 1.0], 0.2, subsamples=2)
    np.testing.assert_array_equal(sim.model.samples.points, expected.points)
    shown = ellipsoid_surface([0.2, 0.2, 1.0], [0.2, 0.2, 1.0])
    np.testing.assert_array_equal(sim.surface.points, shown.points)


def test_surface_region_relative_to_the_scene_file(tmp_path, monkeypatch):
    scenes = tmp_path / "scenes"
    scenes.mkdir()
    closed = box_surface([0.0, 0.0, 0.0], [0.4, 0.4, 2.0], (1, 1, 4))
    meshio.write(scenes / "block.stl", meshio.Mesh(closed.points, [("triangle", closed.triangles)]))
    text = BASE.replace(
        "box = { lower = [0.0, 0.0, 0.0], upper = [0.4, 0.4, 2.0] }",
        'surface = "block.stl"\nsubsamples = 2',
    )
    path = write_scene(scenes, text)
    monkeypatch.chdir(tmp_path)
    sim = load_scene(path).simulation
    assert sim.model.samples.volume == pytest.approx(0.32)
    expected = sample_surface(closed, 0.2, subsamples=2)
    np.testing.assert_allclose(sim.model.samples.points, expected.points, atol=1e-6)
    assert len(sim.surface.triangles) == len(closed.triangles)  # the file is the display


def test_mesh_region(tmp_path):
    mesh = ts.box(lower=(0.0, 0.0, 0.0), upper=(0.4, 0.4, 2.0), divisions=(1, 1, 5))
    write_mesh(mesh, tmp_path / "block.vtu")
    text = BASE.replace(
        "box = { lower = [0.0, 0.0, 0.0], upper = [0.4, 0.4, 2.0] }", 'mesh = "block.vtu"'
    ).replace("spacing = 0.2\n", "")
    sim = build(tmp_path, text)
    read = ts.read_mesh(tmp_path / "block.vtu")
    assert sim.model.samples.n == sample_mesh(read).n == read.n_cells
    assert len(sim.surface.triangles) == len(surface_from_mesh(read).triangles)
    grouped = build(
        tmp_path, text.replace('mesh = "block.vtu"', 'mesh = "block.vtu"\nspacing = 1.0')
    )
    assert grouped.model.samples.n == sample_mesh(read, 1.0).n < read.n_cells


def test_display_false_embeds_no_surface(tmp_path):
    sim = build(tmp_path, BASE.replace("spacing = 0.2", "spacing = 0.2\ndisplay = false"))
    assert sim.surface is None and "surface" not in sim.embedded


# -- selectors ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("selector", "expected"),
    [
        ("{ on_plane = { axis = 2, value = 2.0 } }", [3]),
        ("{ on_plane = { axis = 2, value = 0.6666 } }", None),  # no frame there: tested below
        ("{ on_plane = { axis = 2, value = 0.6666, tolerance = 0.001 } }", [1]),
        ("{ in_box = { lower = [0, 0, 0.5], upper = [0.4, 0.4, 2.0] } }", [1, 2, 3]),
        ("{ indices = [2, 1] }", [1, 2]),
    ],
)
def test_frame_selectors(tmp_path, selector, expected):
    text = BASE + f"\n[[prescribed_frames]]\nframes = {selector}\ndisplacement = [0, 0, '0.1*t']\n"
    if expected is None:
        message = scene_error(tmp_path, text)
        assert (
            "[[prescribed_frames]] #1" in message and "no frames on the plane z = 0.6666" in message
        )
        return
    sim = build(tmp_path, text)
    np.testing.assert_array_equal(sim.model.prescribed_frames, [0, *expected])


def test_plane_tolerance_is_relative_to_the_body(tmp_path):
    # 1e-6 of the bounding-box diagonal (about 2.08e-6 here), as for mesh vertices
    sim = build(tmp_path, BASE.replace("value = 0.0 }", "value = 1.5e-6 }"))
    np.testing.assert_array_equal(sim.model.prescribed_frames, [0])
    message = scene_error(tmp_path, BASE.replace("value = 0.0 }", "value = 3e-6 }"))
    assert "no frames on the plane z = 3e-06" in message


def test_point_selectors(tmp_path):
    text = BASE + textwrap.dedent(
        """
        [[springs]]
        points = { surface_in_box = { lower = [0, 0, 1.9], upper = [0.4, 0.4, 2.0] } }
        stiffness = 50.0
        target = ["x", "y - 0.2 * t", "z"]

        [[point_forces]]
        points = [[0.2, 0.2, 2.0], [0.2, 0.2, 1.0]]
        force = ["0", "-0.01 * t * z", "0"]
        """
    )
    sim = build(tmp_path, text)
    (spring,) = sim.model.springs
    top = sim.surface.points[np.abs(sim.surface.points[:, 2] - 2.0) < 1e-9]
    np.testing.assert_array_equal(spring.embedding.points, top)
    np.testing.assert_allclose(spring.targets(0.5), top - [0.0, 0.1, 0.0])
    (forces,) = [load for load in sim.model.loads if hasattr(load, "embedding")]
    np.testing.assert_allclose(forces.force(2.0), [[0, -0.04, 0], [0, -0.02, 0]])
    sim.step()
    assert sim.frame_positions[-1, 1] < 0.2  # pulled down


def test_spring_stiffness_per_point_and_rest_target(tmp_path):
    text = BASE + "[[springs]]\npoints = [[0.2, 0.2, 2.0], [0.2, 0.2, 1.0]]\nstiffness = [1, 2]\n"
    (spring,) = build(tmp_path, text).model.springs
    np.testing.assert_array_equal(spring.stiffness, [1.0, 2.0])
    np.testing.assert_array_equal(spring.targets(1.0), spring.embedding.points)


def test_initial_angular_velocity(tmp_path):
    text = BASE + "[initial]\nvelocity = [0, 0, 1]\nangular = [0, 0, 2]\n"
    v = build(tmp_path, text).state.v.reshape(-1, 6)
    np.testing.assert_array_equal(v, [[0, 0, 1, 0, 0, 2]] * 4)  # as set_velocity sets it


# -- errors ---------------------------------------------------------------------------------------


def test_mesh_and_frames_choose_one(tmp_path):
    mesh = FEM.split("\n\n[material]")[0]
    message = scene_error(tmp_path, mesh + "\n" + BASE)
    assert "[mesh]" in message and "[frames]" in message and "choose one" in message


def test_frames_without_region(tmp_path):
    text = BASE.replace("[region]\n", "").replace(
        "box = { lower = [0.0, 0.0, 0.0], upper = [0.4, 0.4, 2.0] }\nspacing = 0.2\n", ""
    )
    message = scene_error(tmp_path, text)
    assert "needs a [region] table" in message and "box" in message


def test_frame_tables_in_a_mesh_scene(tmp_path):
    text = FEM + "[[fixed_frames]]\nframes = { indices = [0] }\n"
    message = scene_error(tmp_path, text)
    assert "[fixed_frames]" in message and "add a [frames] table" in message


def test_mesh_tables_in_a_frame_scene(tmp_path):
    message = scene_error(
        tmp_path, BASE + "[[dirichlet]]\nvertices = { on_plane = { axis = 0, value = 0.0 } }\n"
    )
    assert "[[dirichlet]]" in message and "[[fixed_frames]]" in message


def test_misspelt_frames_table_in_a_mesh_scene(tmp_path):
    assert "did you mean 'frames'" in scene_error(tmp_path, FEM + "[frame]\ncount = 3\n")


@pytest.mark.parametrize(
    ("old", "new", "table", "hint"),
    [
        ("[frames]", "[frames]\nradus = 0.5", "[frames]", "did you mean 'radius'"),
        ("[frames]", "[frames]\nwobble = 1", "[frames]", "valid keys: ['count', 'grid'"),
        ("spacing = 0.2", "spacing = 0.2\ndisplya = true", "[region]", "did you mean 'display'"),
        ("time_step", "time_stpe", "[simulation]", "did you mean 'time_step'"),
        ("[[fixed_frames]]\nframes", "[[fixed_frames]]\nframe", "[[fixed_frames]] #1", "'frames'"),
        ("[region]", "[regoin]", "top level", "did you mean 'region'"),
        ("counts = [1", "count = [1", "[frames] grid", "did you mean 'counts'"),
        ("on_plane", "on_plain", "[[fixed_frames]] #1 frames", "did you mean 'on_plane'"),
        ("axis = 2,", "axes = 2,", "frames on_plane", "did you mean 'axis'"),
    ],
)
def test_unknown_keys_name_the_table(tmp_path, old, new, table, hint):
    message = scene_error(tmp_path, BASE.replace(old, new, 1))
    assert table in message and hint in message


def test_unknown_key_in_a_later_table_is_numbered(tmp_path):
    text = BASE + "[[fixed_frames]]\nframes = { indices = [3] }\n"
    text += "[[fixed_frames]]\nframes = { indices = [2] }\nstiffness = 1\n"
    message = scene_error(tmp_path, text)
    assert (
        "[[fixed_frames]] #3" in message
        and "'stiffness'" in message
        and "['frames', 'name']" in message
    )


def test_selector_matching_no_frame(tmp_path):
    text = (
        BASE + "[[fixed_frames]]\nframes = { in_box = { lower = [1, 1, 1], upper = [2, 2, 2] } }\n"
    )
    message = scene_error(tmp_path, text)
    assert "[[fixed_frames]] #2" in message and "no frames in the box" in message
    assert "span [0.2, 0.2] x [0.2, 0.2] x [0, 2]" in message


@pytest.mark.parametrize(
    ("selector", "expected"),
    [
        ("{ indices = [0, 9] }", "frame indices must be in 0..3, got [9]"),
        ("{ indices = 'all' }", "expected a list of frame indices"),
        ("{ on_plane = { axis = 3, value = 0.0 } }", "axis must be 0, 1 or 2"),
        ("{ on_plane = { axis = 2 } }", "missing key 'value'"),
        ("{ on_plane = { axis = 2, value = 0.0, tolerance = -1 } }", "tolerance must be"),
        ("{ on_plane = 2 }", "on_plane takes a table"),
        ("[0]", "one selector out of ['on_plane', 'in_box', 'indices', 'where']"),
        ("{ indices = [0], on_plane = { axis = 2, value = 0.0 } }", "one selector"),
    ],
)
def test_bad_frame_selectors(tmp_path, selector, expected):
    text = BASE + f"[[prescribed_frames]]\nframes = {selector}\nrotation = [0, 0, 't']\n"
    message = scene_error(tmp_path, text)
    assert "[[prescribed_frames]] #1" in message and expected in message


def test_frames_already_fixed(tmp_path):
    message = scene_error(tmp_path, BASE + "[[fixed_frames]]\nframes = { indices = [0, 1] }\n")
    assert "[[fixed_frames]] #2" in message and "already fixed or prescribed" in message


def test_prescribed_frames_errors(tmp_path):
    item = "[[prescribed_frames]]\nframes = { indices = [3] }\n"
    message = scene_error(tmp_path, BASE + item)
    assert "[[prescribed_frames]] #1" in message and "displacement" in message
    assert "[[fixed_frames]]" in message
    message = scene_error(tmp_path, BASE + item + "displacement = ['0', 'q * t', '0']\n")
    assert "displacement[1]" in message and "unknown name 'q'" in message
    message = scene_error(tmp_path, BASE + item + "rotation = [0, 1]\n")
    assert "rotation" in message and "expected a list of 3" in message
    assert "missing key 'frames'" in scene_error(
        tmp_path, BASE + "[[prescribed_frames]]\nrotation = [0, 0, 1]\n"
    )


def test_bad_integrator_lists_the_integrators(tmp_path):
    text = BASE.replace("time_step = 0.02", "time_step = 0.02\nintegrator = 'rk4'")
    message = scene_error(tmp_path, text)
    assert "[simulation]" in message and "integrator must be one of" in message
    assert "'backward_euler', 'quasistatic', 'explicit'" in message and "not 'rk4'" in message
    # symplectic_euler is the explicit scheme's other name, for frame bodies as for FEM
    text = BASE.replace("time_step = 0.02", "time_step = 0.02\nintegrator = 'symplectic_euler'")
    assert build(tmp_path, text).explicit


@pytest.mark.parametrize(
    ("old", "new", "named"),
    [
        ("time_step = 0.02", "time_step = 0.0", "time_step"),
        ("time_step = 0.02", "time_step = '0.02'", "time_step"),
        ("density = 1000.0", "density = -1.0", "density"),
        ("density = 1000.0", "density = 1000.0\nmass = 'lumpy'", "mass"),
        ("density = 1000.0", "density = 1000.0\nmax_step_halvings = -1", "max_step_halvings"),
        ("density = 1000.0", "density = 1000.0\nbackend = 'gpu'", "backend"),
    ],
)
def test_bad_simulation_values_name_the_table(tmp_path, old, new, named):
    message = scene_error(tmp_path, BASE.replace(old, new))
    assert "[simulation]" in message and named in message


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        ("[frames]", '[frames]\ntype = "rigd"', "frame type must be one of"),
        ("[frames]", '[frames]\nshape = "gauss"', "gauss"),
        ("[frames]", "[frames]\nradius = 0.05", "integration point 0 at"),
        ("counts = [1, 1, 4]", "counts = [1, 1, 0]", "counts must be >= 1"),
        ("counts = [1, 1, 4]", "counts = [1, 1]", "counts must be 3 integers"),
        ("grid = {", "count = 3\ngrid = {", "exactly one of grid"),
    ],
)
def test_bad_frames_values(tmp_path, old, new, expected):
    message = scene_error(tmp_path, BASE.replace(old, new))
    assert "[frames]" in message and expected in message


def test_frames_placement_errors(tmp_path):
    grid = "grid = { lower = [0.2, 0.2, 0.0], upper = [0.2, 0.2, 2.0], counts = [1, 1, 4] }"
    message = scene_error(tmp_path, BASE.replace(grid, ""))
    assert "[frames]" in message and "exactly one of grid" in message and "got none" in message
    message = scene_error(tmp_path, BASE.replace(grid, "count = 100"))
    assert "count = 100" in message and "only 40 integration points" in message
    message = scene_error(tmp_path, BASE.replace(grid, "positions = [[0.2, 0.2]]"))
    assert "[frames] positions[0]" in message and "expected 3 numbers" in message


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        ("spacing = 0.2\n", "", "missing key 'spacing'"),
        ("spacing = 0.2", "spacing = -0.2", "spacing must be finite and > 0"),
        (
            "spacing = 0.2",
            "spacing = 0.2\nellipsoid = { center = [0, 0, 0], semi_axes = [1, 1, 1] }",
            "exactly one of box",
        ),
        ("box = { lower = [0.0, 0.0, 0.0], upper = [0.4, 0.4, 2.0] }", "", "got none"),
        ("upper = [0.4, 0.4, 2.0] }", "upper = [0.4, 0.4] }", "[region] box upper"),
        ("upper = [0.4, 0.4, 2.0] }", "uper = [0.4, 0.4, 2.0] }", "did you mean 'upper'"),
        ("box = {", "box = 3\nunused = {", "unknown key 'unused'"),
        ("spacing = 0.2", "spacing = 0.2\nsubsamples = 2", "subsamples applies to ellipsoid"),
        ("spacing = 0.2", "spacing = 0.2\ndisplay = 1", "display must be true or false"),
    ],
)
def test_bad_region(tmp_path, old, new, expected):
    message = scene_error(tmp_path, BASE.replace(old, new))
    assert "[region]" in message and expected in message


def test_missing_surface_file_names_the_path(tmp_path):
    text = BASE.replace(
        "box = { lower = [0.0, 0.0, 0.0], upper = [0.4, 0.4, 2.0] }", 'surface = "organ.stl"'
    )
    message = scene_error(tmp_path, text)
    assert "[region] surface" in message and str(tmp_path / "organ.stl") in message


def test_points_need_a_display_surface(tmp_path):
    text = BASE.replace("spacing = 0.2", "spacing = 0.2\ndisplay = false")
    text += "[[point_forces]]\npoints = { surface_on_plane = { axis = 2, value = 2.0 } }\n"
    text += "force = [0, -1, 0]\n"
    message = scene_error(tmp_path, text)
    assert "[[point_forces]] #1" in message and "display = true" in message


@pytest.mark.parametrize(
    ("item", "expected"),
    [
        ("points = [[0.2, 0.2, 2.0]]\n", "missing key 'force'"),
        ("force = [0, 1, 0]\n", "missing key 'points'"),
        ("points = [[0.2, 0.2, 2.0]]\nforce = [0, 1]\n", "force: expected 3 numbers"),
        ("points = [[0.2, 0.2, 2.0]]\nforce = [0, 'sqrt(', 0]\n", "force[1]"),
        ("points = [0.2, 0.2, 2.0]\nforce = [0, 1, 0]\n", "list of points"),
        (
            "points = { surface_on_plane = { axis = 2, value = 9.0 } }\nforce = [0, 1, 0]\n",
            "no display-surface vertices on the plane z = 9.0",
        ),
        (
            "points = { on_plane = { axis = 2, value = 2.0 } }\nforce = [0, 1, 0]\n",
            "did you mean 'surface_on_plane'",
        ),
        ("points = [[5.0, 5.0, 5.0]]\nforce = [0, 1, 0]\n", "loaded point"),
    ],
)
def test_point_force_errors(tmp_path, item, expected):
    message = scene_error(tmp_path, BASE + "[[point_forces]]\n" + item)
    assert "[[point_forces]] #1" in message and expected in message


@pytest.mark.parametrize(
    ("item", "expected"),
    [
        ("points = [[0.2, 0.2, 2.0]]\n", "missing key 'stiffness'"),
        ("points = [[0.2, 0.2, 2.0]]\nstiffness = -1.0\n", "stiffness must be finite and > 0"),
        ("points = [[0.2, 0.2, 2.0]]\nstiffness = [1, 2]\n", "a list of 1 numbers"),
        ("points = [[0.2, 0.2, 2.0]]\nstiffness = 1\ntarget = ['t', 'y']\n", "target"),
    ],
)
def test_spring_errors(tmp_path, item, expected):
    message = scene_error(tmp_path, BASE + "[[springs]]\n" + item)
    assert "[[springs]] #1" in message and expected in message


def test_initial_and_gravity_errors(tmp_path):
    message = scene_error(tmp_path, BASE + "[initial]\nvelocity = ['x', 0, 0]\n")
    assert "[initial] velocity" in message and "3 numbers" in message
    message = scene_error(tmp_path, BASE + "[initial]\nspin = [0, 0, 1]\n")
    assert "[initial]" in message and "did you mean 'angular'" in message or "'spin'" in message
    affine = BASE.replace("[frames]", '[frames]\ntype = "affine"')
    message = scene_error(tmp_path, affine + "[initial]\nangular = [0, 0, 1]\n")
    assert "[initial]" in message and "rigid frames" in message
    message = scene_error(tmp_path, BASE + "[gravity]\nacceleration = [0.0, -9.81]\n")
    assert "[gravity] acceleration" in message and "3 numbers" in message


def test_run_table_is_checked(tmp_path):
    assert "steps must be an integer >= 0" in scene_error(tmp_path, BASE + "[run]\nsteps = -1\n")
    scene = load_scene(write_scene(tmp_path, BASE + "[run]\nsteps = 3\nrender = false\n"))
    assert scene.run == {"steps": 3, "render": False}
