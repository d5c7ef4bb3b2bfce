"""Coupled scenes ([[organs]] tables): a scene builds what the Python API of CoupledSimulation
builds, a cut in a scene parts the organs, and every mistake is a SceneError naming the file,
the table and the key, saying how to fix it."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest

from tissuesim.cli import example_path, list_examples
from tissuesim.errors import SceneError
from tissuesim.materials import make_material
from tissuesim.mesh import box, ellipsoid, write_mesh
from tissuesim.scene.loader import load_scene
from tissuesim.simulation import Simulation

# Two boxes 0.2 m apart joined by a tissue layer (as tests/coupling/test_coupled_mechanics.py's
# two_boxes): the lower one held at its bottom, the upper one lifted 0.1 m over 0.5 s.
BASE = """
[simulation]
integrator = "quasistatic"
time_step = 0.25

[[organs]]
name = "lower"
mesh = { generator = "box", lower = [0, 0, -0.5], upper = [1, 1, 0], divisions = [3, 3, 2] }
material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.3 }
density = 10.0
fix = { tagged = "zmin" }

[[organs]]
name = "upper"
mesh = { generator = "box", lower = [0, 0, 0.2], upper = [1, 1, 0.7], divisions = [3, 3, 2] }
material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.3 }
density = 10.0

[[graspers]]
organ = "upper"
vertices = { where = "z > 0.69" }
displacement = ["0", "0", "0.1 * min(t / 0.5, 1)"]

[tissue]
material = { model = "stvk", youngs_modulus = 300.0, poisson_ratio = 0.3 }
thickness = 0.2
spacing = 0.1
frames = 8
density = 10.0
region = { where = "(x > 0) * (x < 1) * (y > 0) * (y < 1)" }
"""

# sweeps x from -0.2 to 1.2 at z = 0.15 (the middle of the lifted layer) during 0.5 <= t <= 1
CUT = """
[[cuts]]
blade = [["-0.2 + 2.8 * (t - 0.5)", "-0.2", "0.15"], ["-0.2 + 2.8 * (t - 0.5)", "1.2", "0.15"]]
start = 0.5
end = 1.0
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


def two_boxes_api() -> Simulation:
    """BASE written with the Python API."""
    mat = make_material("neo_hookean", youngs_modulus=1000.0, poisson_ratio=0.3)
    lower = box((0, 0, -0.5), (1, 1, 0), (3, 3, 2))
    upper = box((0, 0, 0.2), (1, 1, 0.7), (3, 3, 2))
    sim = Simulation(integrator="quasistatic", time_step=0.25)
    sim.add_body("lower", lower, mat, density=10.0)
    sim.add_body("upper", upper, mat, density=10.0)
    sim.fix("lower", lower.point_sets["zmin"])
    sim.grasp("upper", upper.point_sets["zmax"], lambda t: (0, 0, 0.1 * min(t / 0.5, 1)))
    sim.add_tissue(
        make_material("stvk", youngs_modulus=300.0, poisson_ratio=0.3),
        thickness=0.2,
        spacing=0.1,
        frames=8,
        density=10.0,
        region=lambda p: (p[:, 0] > 0) & (p[:, 0] < 1) & (p[:, 1] > 0) & (p[:, 1] < 1),
    )
    return sim


# -- the shipped example ------------------------------------------------------------------------


def test_coupled_example_is_the_python_scene():
    """organs_retraction_cut.toml builds what the Python API builds (no steps: a full run
    takes minutes; tests/cli/test_cli_coupled.py runs two)."""
    assert "organs_retraction_cut" in list_examples()
    scene = load_scene(example_path("organs_retraction_cut"))
    sim = scene.simulation
    assert isinstance(sim, Simulation)
    assert scene.run == {"steps": 120, "every": 2, "field": "green_strain"}
    assert sim.integrator == "backward_euler" and sim.time_step == 0.025
    np.testing.assert_array_equal(sim.gravity[0], [0.0, 0.0, -9.81])
    assert [n for n, b in sim.bodies.items() if b.kind == "fem"] == ["liver", "gallbladder"]

    liver = ellipsoid((0, 0, -0.02), (0.06, 0.04, 0.02), 8)
    gb = ellipsoid((0, 0, 0.022), (0.035, 0.02, 0.015), 8)
    organs = sim.bodies
    np.testing.assert_array_equal(organs["liver"].mesh.points, liver.points)
    np.testing.assert_array_equal(organs["gallbladder"].mesh.points, gb.points)
    assert np.all(organs["liver"].model.density == 1050.0)
    assert np.all(organs["gallbladder"].model.density == 1030.0)
    assert organs["liver"].model.material.mu == pytest.approx(5000.0 / (2 * 1.45))
    assert organs["gallbladder"].model.material.mu == pytest.approx(10000.0 / (2 * 1.45))
    np.testing.assert_array_equal(
        dict(organs["liver"].conditions)["liver.support"].vertices,
        np.flatnonzero(liver.points[:, 2] < -0.032),
    )
    (grasper,) = organs["gallbladder"].graspers
    assert grasper.name == "grasper" and grasper.stiffness is None
    np.testing.assert_array_equal(grasper.vertices, np.flatnonzero(gb.points[:, 2] > 0.031))
    for t, z in ((0.0, 0.0), (0.5, 0.0075), (1.0, 0.015), (3.0, 0.015)):
        np.testing.assert_allclose(grasper.displacement(t), [0.0, 0.0, z])

    tissue = sim.tissue
    assert tissue.material.mu == pytest.approx(1000.0 / 2.8)
    assert len(tissue.frames) == 30 and tissue.density == 1000.0
    assert tissue.frame_type == "affine" and tissue.samples.n > 1000
    assert {c.organ for c in tissue.contacts} == {"liver", "gallbladder"}
    (cut,) = sim.tissue.cuts
    assert (cut.start, cut.end, cut.name) == (1.2, 2.2, "cut")
    np.testing.assert_allclose(cut.positions(1.7), [[0.0, -0.05, 0.01], [0.0, 0.05, 0.01]])
    assert sim.tissue.tear_threshold is None


# -- a scene is the Python API ------------------------------------------------------------------


def test_scene_equals_python_api(tmp_path):
    scene_sim = build(tmp_path, BASE)
    sim = two_boxes_api()
    np.testing.assert_array_equal(scene_sim.tissue.samples.points, sim.tissue.samples.points)
    np.testing.assert_array_equal(scene_sim.tissue.frames, sim.tissue.frames)
    g_scene = scene_sim.bodies["upper"].graspers[0]
    np.testing.assert_array_equal(g_scene.vertices, sim.bodies["upper"].graspers[0].vertices)
    for _ in range(2):
        a, b = scene_sim.step(), sim.step()
    np.testing.assert_allclose(scene_sim.state.x, sim.state.x, rtol=1e-12, atol=1e-14)
    for key in ("grasper", "lower.support"):
        np.testing.assert_allclose(a.extra["forces"][key], b.extra["forces"][key], rtol=1e-9)
    assert a.extra["forces"]["grasper"][2] > 1.0  # the stretched tissue pulls back


def test_cut_in_a_scene_separates_the_organs(tmp_path):
    """Cutting through the layer leaves the grasper (no gravity) holding nothing."""
    sim = build(tmp_path, BASE + CUT)
    records = [sim.step() for _ in range(5)]  # t = 0.25 ... 1.25
    before = records[1].extra["forces"]["grasper"][2]  # t = 0.5, lifted, not cut yet
    after = records[-1].extra["forces"]["grasper"]
    cuts = [e for r in records for e in r.extra["events"] if e["kind"] == "cut"]
    assert cuts and sum(e["severed_pairs"] for e in cuts) > 0
    assert before > 1.0
    assert np.linalg.norm(after) < 1e-6 * before
    np.testing.assert_allclose(records[-1].extra["forces"]["lower.support"], 0.0, atol=1e-6)


def test_options_reach_the_api(tmp_path):
    text = BASE.replace(
        'fix = { tagged = "zmin" }', 'fix = { where = "z < -0.49" }\nmass = "lumped"'
    )
    text = text.replace(
        'displacement = ["0", "0", "0.1 * min(t / 0.5, 1)"]',
        'displacement = [0, 0, 0.05]\nstiffness = 50.0\nname = "forceps"',
    )
    text = text.replace(
        "frames = 8",
        "frames = [[0.2, 0.2, 0.1], [0.8, 0.8, 0.1], [0.5, 0.5, 0.1]]\nframe_type = 'rigid'\n"
        "shape = 'shepard'\nradius_factor = 2.0\nattach_distance = 0.12\n"
        "attachment_stiffness = 1e5",
    )
    text += "[gravity]\nacceleration = [0.0, 0.0, -1.0]\n[tearing]\nthreshold = 0.5\n"
    text += "[newton]\nmax_iterations = 7\n"
    text += CUT.replace("start = 0.5", "start = 0.5\nkerf = 0.01\nname = 'scalpel'")
    text += "[run]\nsteps = 3\nevery = 1\nrender = false\n"
    scene = load_scene(write_scene(tmp_path, text))
    sim = scene.simulation
    assert scene.run == {"steps": 3, "every": 1, "render": False}
    lower = sim.bodies["lower"]
    np.testing.assert_array_equal(
        dict(lower.conditions)["lower.support"].vertices, np.sort(lower.mesh.point_sets["zmin"])
    )
    assert lower.model.mass_kind == "lumped"
    (g,) = sim.bodies["upper"].graspers
    assert (g.name, g.stiffness) == ("forceps", 50.0)
    np.testing.assert_array_equal(g.displacement(7.0), [0.0, 0.0, 0.05])
    t = sim.tissue
    np.testing.assert_array_equal(t.frames[2], [0.5, 0.5, 0.1])
    assert (t.frame_type, t.shape, t.radius_factor) == ("rigid", "shepard", 2.0)
    assert (t.attach_distance, t.attachment_stiffness) == (0.12, 1e5)
    np.testing.assert_array_equal(sim.gravity[0], [0.0, 0.0, -1.0])
    assert sim.tissue.tear_threshold == 0.5 and sim.newton.max_iterations == 7
    (cut,) = sim.tissue.cuts
    assert (cut.name, cut.kerf) == ("scalpel", 0.01)
    assert sim.describe()["bodies"]["upper"]["graspers"]["forceps"] == "spring"


def test_mesh_file_relative_to_the_scene_and_plane_selector(tmp_path, monkeypatch):
    scenes = tmp_path / "scenes"
    scenes.mkdir()
    write_mesh(box((0, 0, -0.5), (1, 1, 0), (3, 3, 2)), scenes / "lower.vtu")
    assert LOWER_MESH in BASE
    text = BASE.replace(LOWER_MESH, 'mesh = { file = "lower.vtu" }').replace(
        'fix = { tagged = "zmin" }', "fix = { on_plane = { axis = 2, value = -0.5 } }"
    )
    path = write_scene(scenes, text)
    monkeypatch.chdir(tmp_path)
    sim = load_scene(path).simulation
    lower = sim.bodies["lower"]
    assert lower.mesh.n_points == 4 * 4 * 3
    np.testing.assert_array_equal(
        dict(lower.conditions)["lower.support"].vertices,
        np.flatnonzero(np.abs(lower.mesh.points[:, 2] + 0.5) < 1e-9),
    )


def test_organs_without_tissue(tmp_path):
    tissue = BASE.index("[tissue]")
    sim = build(tmp_path, BASE[:tissue])
    assert sim.tissue is None
    assert sim.step().converged


# -- errors -------------------------------------------------------------------------------------

ELLIPSOID = (
    'mesh = { generator = "ellipsoid", center = [0.5, 0.5, 0.45], radii = [0.5, 0.5, 0.25] }'
)
UPPER_MESH = (
    'mesh = { generator = "box", lower = [0, 0, 0.2], upper = [1, 1, 0.7], divisions = [3, 3, 2] }'
)
LOWER_MESH = UPPER_MESH.replace("0.2], upper = [1, 1, 0.7]", "-0.5], upper = [1, 1, 0]")
MATERIAL = 'material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.3 }'
GRASPER_DISPLACEMENT = 'displacement = ["0", "0", "0.1 * min(t / 0.5, 1)"]'


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        # organs
        ("density = 10.0\nfix", "densty = 10.0\nfix", ["organs[1]", "did you mean 'density'"]),
        ("density = 10.0\nfix", "density = -10.0\nfix", ["organs[1] density", "> 0"]),
        ("density = 10.0\nfix", 'mass = "full"\nfix', ["organs[1]", "'lumped' or 'element_rule'"]),
        ('name = "upper"', 'name = "lower"', ["organs[2]", "'lower' is taken"]),
        ('name = "upper"', 'name = "tissue"', ["organs[2]", "'tissue' is taken"]),
        ('name = "upper"\n', "", ["organs[2]", "missing key 'name'"]),
        (UPPER_MESH, "", ["organs[2]", "missing key 'mesh'", "generator"]),
        (UPPER_MESH, 'mesh = "upper.vtu"', ["organs[2].mesh", "must be a table"]),
        (UPPER_MESH, 'mesh = { generator = "sphere" }', ["organs[2].mesh", "'box' | 'ellipsoid'"]),
        (
            UPPER_MESH,
            ELLIPSOID.replace("radii", "radius"),
            ["organs[2].mesh", "did you mean 'radii'"],
        ),
        (
            UPPER_MESH,
            ELLIPSOID.replace("center", "lower"),
            ["organs[2].mesh", "'lower' is not an argument of generator 'ellipsoid'"],
        ),
        (
            UPPER_MESH,
            UPPER_MESH.replace("[3, 3, 2]", "4"),
            ["organs[2].mesh", "divisions must be 3 integers"],
        ),
        (UPPER_MESH, 'mesh = { file = "missing.vtu" }', ["organs[2].mesh", "missing.vtu"]),
        (
            UPPER_MESH,
            'mesh = { file = "a.vtu", divisions = 2 }',
            ["organs[2].mesh", "'file' cannot be combined"],
        ),
        (
            f"{MATERIAL}\ndensity = 10.0\n\n[[graspers]]",
            "density = 10.0\n\n[[graspers]]",
            ["organs[2]", "missing key 'material'", "neo_hookean"],
        ),
        (
            f"{MATERIAL}\ndensity = 10.0\nfix",
            "material = { youngs_modulus = 1000.0 }\ndensity = 10.0\nfix",
            ["organs[1] material", "missing key 'model'"],
        ),
        (
            f"{MATERIAL}\ndensity = 10.0\nfix",
            f"{MATERIAL.replace('0.3', '0.7')}\ndensity = 10.0\nfix",
            ["organs[1] material", "poisson"],
        ),
        # selectors
        (
            'fix = { tagged = "zmin" }',
            'fix = { where = "z < -5" }',
            [
                "organs[1] fix",
                "selects no vertex",
                "span [0, 1] x [0, 1] x [-0.5, 0]",
            ],
        ),
        (
            'fix = { tagged = "zmin" }',
            "fix = { on_plane = { axis = 2, value = -0.7 } }",
            ["organs[1] fix", "no vertices on the plane z = -0.7"],
        ),
        (
            'fix = { tagged = "zmin" }',
            'fix = { tagged = "bottom" }',
            ["organs[1] fix", "no set named 'bottom'"],
        ),
        (
            'fix = { tagged = "zmin" }',
            'fix = { wher = "z < 0" }',
            ["organs[1] fix", "did you mean 'where'"],
        ),
        (
            'fix = { tagged = "zmin" }',
            'fix = { where = "z < 0.1 * t" }',
            ["organs[1] fix where", "uses t"],
        ),
        (
            'fix = { tagged = "zmin" }',
            'fix = { where = "z <" }',
            ["organs[1] fix where", "cannot parse"],
        ),
        (
            'fix = { tagged = "zmin" }',
            "fix = { where = 1 }",
            ["organs[1] fix where", "as a string"],
        ),
        (
            'fix = { tagged = "zmin" }',
            "fix = [0, 1]",
            ["organs[1]", "one selector out of", "where"],
        ),
        # graspers
        (
            'organ = "upper"',
            'organ = "uper"',
            ["graspers[1]", "unknown organ 'uper'", "did you mean 'upper'"],
        ),
        ('organ = "upper"\n', "", ["graspers[1]", "name the grasped body with body"]),
        (
            'vertices = { where = "z > 0.69" }',
            'vertices = { where = "z > 5" }',
            ["graspers[1] vertices", "selects no vertex"],
        ),
        (
            GRASPER_DISPLACEMENT,
            'displacement = ["0", "0.1 * t"]',
            ["graspers[1] displacement", "3 numbers"],
        ),
        (
            GRASPER_DISPLACEMENT,
            'displacement = ["0", "0", "0.1 * z"]',
            ["graspers[1] displacement[2]", "depends on t only"],
        ),
        (
            GRASPER_DISPLACEMENT,
            'displacement = ["0", "0", "s"]',
            ["graspers[1] displacement[2]", "unknown name 's'"],
        ),
        (
            GRASPER_DISPLACEMENT,
            'displacement = ["0", "0", "log(t)"]',
            ["graspers[1] displacement", "not finite at the start time t = 0 s"],
        ),
        (
            GRASPER_DISPLACEMENT,
            GRASPER_DISPLACEMENT + "\nstiffness = -1.0",
            ["graspers[1] stiffness", "> 0"],
        ),
        (
            GRASPER_DISPLACEMENT,
            GRASPER_DISPLACEMENT + "\nforce = 1.0",
            ["graspers[1]", "unknown key 'force'"],
        ),
        # tissue
        ("thickness = 0.2\n", "", ["[tissue]", "missing key 'thickness'"]),
        ("spacing = 0.1\n", "", ["[tissue]", "missing key 'spacing'"]),
        ("spacing = 0.1", "spacing = 0.0", ["[tissue] spacing", "> 0"]),
        ("frames = 8", "frames = 0", ["[tissue]", "frames must be an integer >= 1"]),
        ("frames = 8", "frames = 100000", ["[tissue]", "frames must be between 1 and the number"]),
        ("frames = 8", "frames = [[0, 0]]", ["[tissue] frames[0]", "3 numbers"]),
        (
            "frames = 8",
            "frame_type = 'bent'",
            ["[tissue]", "frame_type must be 'affine' or 'rigid'"],
        ),
        ("frames = 8", "shape = 'gauss'", ["[tissue]", "'wendland' or 'shepard'"]),
        ("frames = 8", "frame = 8", ["[tissue]", "did you mean 'frames'"]),
        ("thickness = 0.2", "thickness = 0.01", ["[tissue]", "thickness"]),
        (
            'region = { where = "(x > 0) * (x < 1) * (y > 0) * (y < 1)" }',
            'region = "x > 0"',
            ["[tissue]", "region must be { where = "],
        ),
        (
            'material = { model = "stvk"',
            'material = { model = "stvj"',
            ["[tissue] material", "stvk"],
        ),
        # simulation, gravity, top level
        (
            'integrator = "quasistatic"',
            'integrator = "implicit"',
            ["[simulation]", "integrator must be"],
        ),
        ("time_step = 0.25", "time_step = -1", ["[simulation]", "time_step"]),
        (
            "time_step = 0.25",
            "time_step = 0.25\ndensity = 1.0",
            ["[simulation]", "density is set per body"],
        ),
        ("time_step = 0.25", "time_stp = 0.25", ["[simulation]", "did you mean 'time_step'"]),
        (
            "[tissue]",
            "[gravity]\nacceleration = [0, -9.81]\n\n[tissue]",
            ["[gravity] acceleration", "3 numbers"],
        ),
        ("[tissue]", "[tisue]", ["top level", "did you mean 'tissue'"]),
        (
            "[tissue]",
            "[mesh]\ngenerator = 'box'\n\n[tissue]",
            ["[mesh] does not belong", "[[organs]]"],
        ),
        ("[tissue]", "[[dirichlet]]\nvertices = 1\n\n[tissue]", ["[dirichlet]", "fix = {...}"]),
        ("[[graspers]]", "[graspers]", ["[[graspers]]", "array of tables"]),
    ],
)
def test_bad_scene_names_file_table_and_key(tmp_path, old, new, expected):
    assert old in BASE
    message = scene_error(tmp_path, BASE.replace(old, new, 1))
    for text in expected:
        assert text in message, (text, message)


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        ("blade = [[", "blade = [[0, 0, 0]]\nold = [[", ["cuts[1]", "unknown key 'old'"]),
        (
            'blade = [["-0.2 + 2.8 * (t - 0.5)", "-0.2", "0.15"], ',
            "blade = [",
            ["cuts[1]", "at least 2 points", "got 1"],
        ),
        ('"1.2", "0.15"]]', '"1.2"]]', ["cuts[1] blade[1]", "3 numbers"]),
        ('"1.2", "0.15"]]', '"1.2", "0.15 + x"]]', ["cuts[1] blade[1][2]", "depends on t only"]),
        ("end = 1.0", "end = 0.5", ["cuts[1]", "end (0.5 s) must be after start (0.5 s)"]),
        ("start = 0.5\n", "", ["cuts[1]", "missing key 'start'"]),
        ("end = 1.0", "end = 1.0\nkerf = 0", ["cuts[1] kerf", "> 0"]),
        ("end = 1.0", "end = '1.0'", ["cuts[1] end", "a time (s)"]),
    ],
)
def test_bad_cut(tmp_path, old, new, expected):
    assert old in CUT
    message = scene_error(tmp_path, BASE + CUT.replace(old, new, 1))
    for text in expected:
        assert text in message, (text, message)


def test_cut_errors_beyond_one_table(tmp_path):
    blade = CUT.splitlines()[2]
    message = scene_error(tmp_path, BASE + CUT.replace(blade, 'blade = "x"'))
    assert "cuts[1]" in message and "blade must be a polyline" in message
    message = scene_error(tmp_path, BASE + CUT + CUT)
    assert "cuts[2]" in message and "a cut named 'cut' exists" in message and "name =" in message
    tissue = BASE.index("[tissue]")
    message = scene_error(tmp_path, BASE[:tissue] + CUT)
    assert "cuts[1]" in message and "add a [tissue] table" in message
    message = scene_error(tmp_path, BASE[:tissue] + "[tearing]\nthreshold = 0.5\n")
    assert "[tearing]" in message and "add a [tissue] table" in message
    message = scene_error(tmp_path, BASE + "[tearing]\nthreshold = -0.5\n")
    assert "[tearing] threshold" in message and "> 0" in message
    message = scene_error(tmp_path, BASE + "[tearing]\nstrain = 0.5\n")
    assert "[tearing]" in message and "unknown key 'strain'" in message and "threshold" in message


def test_run_table_is_checked(tmp_path):
    message = scene_error(tmp_path, BASE + "[run]\nsteps = -1\n")
    assert "[run]" in message and "steps must be an integer >= 0" in message


def test_other_scenes_point_to_organs(tmp_path):
    """A [mesh] scene with coupled tables, or a misspelt [[organs]], says what is meant."""
    mesh = (
        "[mesh]\ngenerator = 'box'\nlower = [0, 0, 0]\nupper = [1, 1, 1]\ndivisions = [1, 1, 1]\n"
        "[material]\nmodel = 'stvk'\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n"
    )
    message = scene_error(tmp_path, mesh + "[tissue]\nthickness = 0.1\n")
    assert "[tissue] belongs to coupled scenes" in message and "[[organs]]" in message
    message = scene_error(tmp_path, mesh + "[[organ]]\nname = 'a'\n")
    assert "did you mean 'organs'" in message
    message = scene_error(tmp_path, "[organs]\nname = 'liver'\n")
    assert "write [[organs]]" in message
