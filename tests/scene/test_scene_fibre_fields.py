"""Fibre directions per element from a mesh file's cell data or from expressions of x, y, z
(scene/tables/fibre_fields.py), and their one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.errors import SceneError
from tissuesim.mesh import box
from tissuesim.scene.loader import build_scene

MATERIAL = {"model": "trans_iso_mooney_rivlin", "c1": 2000.0, "c3": 100.0, "c4": 5.0,
            "c5": 3e4, "lam_max": 1.2, "k": 1e5}  # fmt: skip


def _scene(tmp_path, fiber, data=None, mesh_file=True):
    mesh = box(lower=(0, 0, 0), upper=(1, 0.4, 0.4), divisions=(3, 1, 1))
    if mesh_file:  # a VTU file with a named cell array (gmsh 2.2 ElementData: not via meshio)
        import meshio

        cells = [("tetra", mesh.cells)]
        data = {k: [v] for k, v in (data or {}).items()}
        meshio.Mesh(mesh.points, cells, cell_data=data).write(tmp_path / "box.vtu")
        table = {"file": str(tmp_path / "box.vtu")}
    else:
        table = {"generator": "box", "lower": [0, 0, 0], "upper": [1, 0.4, 0.4],
                 "divisions": [3, 1, 1]}  # fmt: skip
    scene = {
        "mesh": table,
        "material": {**MATERIAL, "fiber": fiber},
        "simulation": {"integrator": "quasistatic", "time_step": 1.0},
        "run": {"steps": 1},
    }
    return mesh, build_scene(scene, name="fibres").simulation


def _fibres(sim) -> np.ndarray:
    return sim.body("body").model.material.fibres[:, 0, :]


def test_directions_from_the_mesh_files_cell_data(tmp_path):
    rng = np.random.default_rng(3)
    mesh = box(lower=(0, 0, 0), upper=(1, 0.4, 0.4), divisions=(3, 1, 1))
    directions = rng.normal(size=(mesh.n_cells, 3))
    _, sim = _scene(tmp_path, {"cell_data": "fibre"}, {"fibre": directions})
    law = sim.body("body").model.material
    expected = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    assert law.fibres.shape[0] in (mesh.n_cells, len(_fibres(sim)))
    np.testing.assert_allclose(_fibres(sim)[:: len(_fibres(sim)) // mesh.n_cells], expected)


def test_directions_from_expressions_at_the_cell_centroids(tmp_path):
    mesh, sim = _scene(tmp_path, ["1", "y + 0.5", "-z"], mesh_file=False)
    c = mesh.points[mesh.cells].mean(axis=1)
    expected = np.column_stack([np.ones(len(c)), c[:, 1] + 0.5, -c[:, 2]])
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    got = _fibres(sim)
    np.testing.assert_allclose(got[:: len(got) // mesh.n_cells], expected)


@pytest.mark.parametrize(
    "fiber, data, mesh_file, message",
    [
        ({"cell_data": "nope"}, {"fibre": np.ones((18, 3))}, True, "no cell data named 'nope'"),
        ({"cell_data": "fibre"}, {"fibre": np.ones((18, 1))}, True, "has shape (18, 1)"),
        ({"cell_data": "fibre"}, {"fibre": np.zeros((18, 3))}, True, "zero or non-finite"),
        ({"cell_data": "fibre"}, None, False, "needs a mesh read from a file"),
        ({"cell": "fibre"}, None, False, "expected a vector, expressions or"),
        (["x", "t", "0"], None, False, "uses t"),
        (["x", "y"], None, False, "expected 3 expressions"),
        (["x", "foo", "0"], None, False, "unknown name 'foo'"),
        (["0", "0", "0 * z"], None, False, "zero or non-finite direction at cell"),
    ],
)
def test_bad_directions_are_one_line_naming_the_key(tmp_path, fiber, data, mesh_file, message):
    with pytest.raises(SceneError) as info:
        _scene(tmp_path, fiber, data, mesh_file)
    said = str(info.value)
    assert "\n" not in said and "[material] fiber" in said and message in said
