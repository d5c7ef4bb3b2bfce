"""[mesh] surface = "organ.stl": a scene meshes a surface file (relative to the scene file) with
mesh_surface; its keys are checked like the other [mesh] keys."""

from __future__ import annotations

import textwrap

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import SceneError
from tissuesim.mesh import signed_volumes
from tissuesim.mesh.from_surface import meshers
from tissuesim.scene.loader import load_scene

RADII = (0.05, 0.03, 0.02)

SCENE = """
[mesh]
{mesh}

[material]
model = "neo_hookean"
youngs_modulus = 3000.0
poisson_ratio = 0.4

[simulation]
density = 1000.0
integrator = "backward_euler"
time_step = 0.01

[gravity]
acceleration = [0.0, 0.0, -9.81]

[[dirichlet]]
vertices = {{ where = "x < -0.04" }}
"""


@pytest.fixture
def scene_dir(tmp_path):
    directory = tmp_path / "scenes"
    directory.mkdir()
    m = ts.ellipsoid(radii=RADII, divisions=8)
    meshio.write_points_cells(
        directory / "organ.stl", m.points, [("triangle", m.facet_sets["surface"])], binary=True
    )
    return directory


def write(directory, mesh_table: str):
    path = directory / "scene.toml"
    path.write_text(textwrap.dedent(SCENE.format(mesh=mesh_table)))
    return path


@pytest.mark.skipif(
    "pytetwild" not in meshers.available_meshers(),
    reason="pytetwild (the default mesher, a dependency) is not installed: pip install pytetwild",
)
def test_surface_key_meshes_the_file_and_the_scene_runs(scene_dir, tmp_path, monkeypatch):
    path = write(scene_dir, 'surface = "organ.stl"\nsize = 0.01')
    monkeypatch.chdir(tmp_path)  # the surface is found relative to the scene, not the cwd
    sim = load_scene(path).simulation
    mesh = sim.mesh
    assert mesh.dim == 3 and "organ.stl" in mesh.source and "pytetwild" in mesh.source
    volume = signed_volumes(mesh.points, mesh.cells)
    assert (volume > 0).all()
    assert volume.sum() == pytest.approx(4 / 3 * np.pi * np.prod(RADII), rel=0.03)
    for _ in range(2):
        assert sim.step().converged
    u = sim.displacement
    clamped = mesh.points[:, 0] < -0.04
    np.testing.assert_array_equal(u[clamped], 0.0)
    assert u[~clamped, 2].min() < 0.0  # it sags under gravity


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ('surface = "organ.stl"\nsizes = 0.01', "unknown key 'sizes'; did you mean 'size'"),
        ('surface = "organ.stl"\nsize = "4 mm"', "size must be a length in metres"),
        ('surface = "organ.stl"\nmesher = 3', "mesher must be a string"),
        ('surface = "organ.stl"\nmesher = "netgen"', "mesher must be 'auto' or one of"),
        ('surface = "organ.stl"\ndivisions = 4', "'surface' cannot be combined with"),
        ("surface = 4", "surface must be a path"),
        ('surface = "missing.stl"', "missing.stl: no such surface file"),
        ('generator = "box"\nsize = 0.01', "size: options of meshing a surface"),
        ('surface = "organ.stl"\nsize = -1.0', "size must be > 0"),
    ],
)
def test_surface_key_errors(scene_dir, table, message):
    path = write(scene_dir, table)
    with pytest.raises(SceneError, match=message) as info:
        load_scene(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)
