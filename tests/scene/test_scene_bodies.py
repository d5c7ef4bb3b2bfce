"""Scenes of several bodies in the one format: [[bodies]] (FEM or frames, with their own
condition tables), [[attachments]], [[graspers]]; every selector and generator on every body."""

from __future__ import annotations

import json
import textwrap

import meshio
import numpy as np
import pytest

from tissuesim.cli import example_path, main
from tissuesim.errors import SceneError
from tissuesim.scene.loader import load_scene

TWO_BLOCKS = """
[simulation]
integrator = "quasistatic"
time_step = 1.0

[gravity]
acceleration = [0.0, 0.0, -9.81]

[[bodies]]
name = "lower"
mesh = { generator = "box", lower = [0, 0, -0.5], upper = [1, 1, 0], divisions = [2, 2, 2] }
material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.3 }
density = 10.0

[[bodies.dirichlet]]
name = "floor"
vertices = { where = "z < -0.49" }

[[bodies]]
name = "upper"
mesh = { generator = "box", lower = [0, 0, 0], upper = [1, 1, 0.5], divisions = [3, 3, 2] }
material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.3 }
density = 10.0

[[attachments]]
body = "upper"
to = "lower"
name = "glue"

[newton]
gradient_tolerance = 1e-11
absolute_tolerance = 1e-12
"""

FRAME_BODY = """
[[bodies]]
name = "{name}"
frames = {{ grid = {{ lower = [{x}, 0.2, 0.0], upper = [{x}, 0.2, 1.0], counts = [1, 1, 3] }} }}
region = {{ box = {{ lower = [{x0}, 0.0, 0.0], upper = [{x1}, 0.4, 1.0] }}, spacing = 0.1 }}
material = {{ model = "stvk", youngs_modulus = 1000.0, poisson_ratio = 0.3 }}
density = 10.0

[[bodies.fixed_frames]]
frames = {{ on_plane = {{ axis = 2, value = 0.0 }} }}
"""


def write(tmp_path, text: str):
    path = tmp_path / "scene.toml"
    path.write_text(textwrap.dedent(text))
    return path


def scene_error(tmp_path, text: str) -> str:
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, text))
    return str(info.value)


def test_two_tied_fem_blocks_from_a_scene_file(tmp_path):
    scene = load_scene(write(tmp_path, TWO_BLOCKS))
    sim = scene.simulation
    assert list(sim.bodies) == ["lower", "upper"] and [t.name for t in sim.ties] == ["glue"]
    floor = dict(sim.bodies["lower"].conditions)["floor"].vertices
    np.testing.assert_array_equal(
        floor, np.flatnonzero(sim.bodies["lower"].mesh.points[:, 2] < -0.49)
    )
    record = sim.step()
    weight = 10.0 * 0.5 * 9.81
    np.testing.assert_allclose(record.extra["forces"]["floor"], [0, 0, 2 * weight], atol=1e-6)
    np.testing.assert_allclose(record.extra["forces"]["glue"], [0, 0, weight], atol=1e-6)


def test_frames_only_scene_of_two_bodies_runs_and_writes_each(tmp_path):
    text = "[simulation]\nintegrator = 'backward_euler'\ntime_step = 0.05\n"
    text += "[gravity]\nacceleration = [0.0, -9.81, 0.0]\n"
    text += FRAME_BODY.format(name="left", x=0.2, x0=0.0, x1=0.4)
    text += FRAME_BODY.format(name="right", x=1.2, x0=1.0, x1=1.4)
    text += "[run]\nsteps = 2\nrender = false\n"
    out = tmp_path / "o"
    assert main(["run", str(write(tmp_path, text)), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert set(summary["simulation"]["bodies"]) == {"left", "right"}
    for name in ("left", "right"):
        last = meshio.read(out / f"{name}_00002.vtu")
        u = last.point_data["displacement"]
        assert u[:, 1].min() < 0  # both sag
        assert {"J", "von_mises", "cauchy_stress"} <= set(last.point_data)
    forces = summary["forces"][-1]
    assert forces["left.fixed_frames"][1] > 0 and forces["right.fixed_frames"][1] > 0
    assert (out / "forces.csv").read_text().splitlines()[0].startswith("time_s,")


def test_fem_and_frame_bodies_mix_and_use_every_selector_and_generator(tmp_path):
    text = """
    [simulation]
    integrator = "quasistatic"
    time_step = 0.5

    [[bodies]]
    name = "ball"
    mesh = { generator = "ellipsoid", center = [0, 0, 0], radii = [0.1, 0.1, 0.1], divisions = 4 }
    material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.3 }
    fix = { where = "z < -0.07" }

    [[bodies.traction]]
    facets = { where = "z > 0.07" }
    traction = [0.0, 0.0, "-20 * t"]

    [[bodies.nodal_forces]]
    vertices = { in_box = { lower = [-1, -1, 0.09], upper = [1, 1, 1] } }
    force = [0.01, 0.0, 0.0]
    """ + FRAME_BODY.format(name="sheet", x=1.2, x0=1.0, x1=1.4)
    sim = load_scene(write(tmp_path, text)).simulation
    assert [b.kind for b in sim.bodies.values()] == ["fem", "frames"]
    record = sim.step()
    assert record.converged and sim.body_positions("ball")[:, 2].max() < 0.1  # pressed down
    assert (
        "ball.support" in record.extra["forces"] and "sheet.fixed_frames" in record.extra["forces"]
    )


def test_the_shipped_two_block_example_runs(tmp_path):
    out = tmp_path / "tied"
    path = example_path("two_blocks_tied")
    assert (
        main(["run", str(path), "--steps", "2", "--out", str(out), "--quiet", "--no-render"]) == 0
    )
    summary = json.loads((out / "summary.json").read_text())
    f = summary["forces"][-1]
    total = np.array(f["grasper"]) + np.array(f["muscle.support"])
    np.testing.assert_allclose(total, 0.0, atol=1e-6 * np.abs(f["grasper"]).max())  # no gravity
    scale = np.abs(f["grasper"]).max()
    np.testing.assert_allclose(f["glue"], -np.array(f["grasper"]), rtol=1e-3, atol=1e-9 * scale)


@pytest.mark.parametrize(
    ("edit", "expected"),
    [
        (
            lambda t: t.replace(
                'mesh = { generator = "box", lower = [0, 0, 0]',
                'msh = { generator = "box", lower = [0, 0, 0]',
            ),
            ["bodies[2]", "give exactly one"],
        ),
        (
            lambda t: t.replace(
                "density = 10.0\n\n[[bodies.dirichlet]]", "densty = 10.0\n\n[[bodies.dirichlet]]"
            ),
            ["bodies[1]", "did you mean 'density'"],
        ),
        (
            lambda t: t.replace(
                'vertices = { where = "z < -0.49" }', 'vertices = { where = "z < -5" }'
            ),
            ["bodies[1].dirichlet[1] vertices", "selects no vertex"],
        ),
        (
            lambda t: t.replace('to = "lower"', 'to = "lowr"'),
            ["attachments[1]", "did you mean 'lower'"],
        ),
        (
            lambda t: t.replace('name = "upper"', 'name = "lower"'),
            ["bodies[2]", "'lower' is taken"],
        ),
        (
            lambda t: t.replace('name = "glue"', 'name = "floor"'),
            ["attachments[1]", "'floor' exists"],
        ),
    ],
)
def test_errors_name_the_body_table_and_key(tmp_path, edit, expected):
    message = scene_error(tmp_path, edit(TWO_BLOCKS))
    for part in expected:
        assert part in message, (part, message)


def test_where_selects_frames_by_their_rest_origins(tmp_path):
    text = FRAME_BODY.format(name="sheet", x=0.2, x0=0.0, x1=0.4).replace(
        "frames = {{ on_plane = {{ axis = 2, value = 0.0 }} }}".replace("{{", "{").replace(
            "}}", "}"
        ),
        'frames = { where = "z < 0.6" }',
    )
    sim = load_scene(write(tmp_path, "[simulation]\ntime_step = 0.1\n" + text)).simulation
    np.testing.assert_array_equal(sim.bodies["sheet"].model.prescribed_frames, [0, 1])
    message = scene_error(
        tmp_path, "[simulation]\ntime_step = 0.1\n" + text.replace("z < 0.6", "z > 5")
    )
    assert "bodies[1].fixed_frames[1] frames where" in message and "selects no frame" in message


def test_a_frame_body_attached_to_a_fem_body_in_a_scene(tmp_path):
    text = """
    [simulation]
    integrator = "quasistatic"
    time_step = 1.0

    [gravity]
    acceleration = [0.0, 0.0, -9.81]

    [[bodies]]
    name = "lower"
    mesh = { generator = "box", lower = [0, 0, -0.5], upper = [1, 1, 0], divisions = [3, 3, 2] }
    material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.3 }
    density = 10.0
    fix = { tagged = "zmin" }

    [[bodies]]
    name = "cap"
    region = { box = { lower = [0, 0, 0], upper = [1, 1, 0.4] }, spacing = 0.1 }
    material = { model = "stvk", youngs_modulus = 500.0, poisson_ratio = 0.3 }
    density = 10.0

    [bodies.frames]
    type = "affine"
    grid = { lower = [0.25, 0.25, 0.1], upper = [0.75, 0.75, 0.3], counts = [2, 2, 2] }

    [[attachments]]
    body = "cap"
    to = "lower"
    name = "seat"
    """
    sim = load_scene(write(tmp_path, text)).simulation
    record = sim.step()
    cap = 10.0 * 0.4 * 9.81
    np.testing.assert_allclose(record.extra["forces"]["seat"], [0, 0, cap], atol=1e-5)
    message = scene_error(tmp_path, text.replace('to = "lower"', 'to = "lowr"'))
    assert "attachments[1]" in message and "did you mean 'lower'" in message


def test_values_that_depend_on_t_only_refuse_x_y_z(tmp_path):
    """A nodal force is one vector for its vertex set: x, y, z in it would be evaluated at
    some point, so they are refused (as for a grasper's displacement)."""
    text = (
        TWO_BLOCKS
        + """
[[bodies.nodal_forces]]
vertices = { tagged = "zmax" }
force = ["0.1 * t", "x", "0"]
"""
    )
    message = scene_error(tmp_path, text)
    assert "nodal_forces[1] force[1]" in message and "depends on t only" in message
    ok = load_scene(write(tmp_path, text.replace('"x"', '"0"'))).simulation
    assert ok.step().converged
