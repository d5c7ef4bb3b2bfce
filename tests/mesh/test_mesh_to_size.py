"""Meshing a segmentation (issue 41): a requested element count within 30 %, smoothing a voxel
staircase (volume kept, steps removed), pytetwild's envelope and coarsening, and bad options as
one error line naming the option, alike from the API, the CLI and a scene."""

from __future__ import annotations

import importlib.util
import textwrap
from pathlib import Path

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.cli import main
from tissuesim.errors import InputError, MeshError, SceneError
from tissuesim.mesh.from_surface import meshers
from tissuesim.mesh.from_surface import tetrahedralize as tet
from tissuesim.mesh.from_surface.sizing import ELEMENT_TOLERANCE, MAX_PASSES, next_size, to_count
from tissuesim.mesh.from_surface.smoothing import normal_variation, smooth_surface
from tissuesim.scene.loader import load_scene

ROOT = Path(__file__).resolve().parents[2]
#: a 10 x 7 x 5 cm organ segmented at 2.5 mm voxels (coarse, so that it meshes in seconds)
RADII = (0.05, 0.035, 0.025)
VOXEL = 2.5e-3

needs_pytetwild = pytest.mark.skipif(
    "pytetwild" not in meshers.available_meshers(),
    reason="pytetwild (the default mesher, a dependency) is not installed: pip install pytetwild",
)


def _benchmark():
    spec = importlib.util.spec_from_file_location(
        "mesh_to_size", ROOT / "benchmarks/mesh_to_size.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def stairs() -> tuple[np.ndarray, np.ndarray]:
    """A noisy staircase: the ellipsoid voxelised with 1-voxel label noise, marching cubes."""
    pytest.importorskip("pyvista")
    return _benchmark().staircase(RADII, VOXEL, noise=VOXEL)


@pytest.fixture(scope="module")
def clean_stairs() -> tuple[np.ndarray, np.ndarray]:
    """The same without noise: every deviation from the ellipsoid is the staircase."""
    pytest.importorskip("pyvista")
    return _benchmark().staircase(RADII, VOXEL, noise=0.0)


@pytest.fixture(autouse=True)
def one_thread(monkeypatch):
    monkeypatch.setenv("TISSUESIM_MESH_THREADS", "1")  # modest on CPU (counts still vary)


# -- the element count --------------------------------------------------------------------------


@needs_pytetwild
@pytest.mark.parametrize("smoothing", [None, "taubin"])
def test_target_elements_is_reached_within_30_percent_on_a_staircase(stairs, smoothing):
    requested = 2000
    r = tet.tetrahedralize(stairs, target_elements=requested, smoothing=smoothing).report
    assert abs(r["n_tets"] / requested - 1.0) <= ELEMENT_TOLERANCE
    assert 1 <= len(r["passes"]) <= MAX_PASSES and r["target_elements"] == requested
    assert r["n_tets"] in [p["n_tets"] for p in r["passes"]]
    assert r["size"] in [p["size"] for p in r["passes"]]
    assert r["envelope"] == pytest.approx(r["size"] / 20)  # the envelope follows the size
    assert r["volume_ratio"] == pytest.approx(1.0, abs=0.02)
    assert r["min_dihedral_deg"] > 5.0


@needs_pytetwild
def test_size_changes_the_count_of_a_staircase(stairs):
    """The symptom of issue 41: with fTetWild's fixed envelope (1e-3 of the diagonal) the
    count barely follows the size (102k / 97k / 98k at 14 / 10 / 7 mm); the default envelope
    (size / 20) follows it. fTetWild is not deterministic: half the size gave more than 2x the
    tetrahedra in the helper's runs and 1.88x in one CI run (7,256 against 3,855), so the
    bound is 1.5x."""
    fine, coarse = (tet.tetrahedralize(stairs, h).report["n_tets"] for h in (0.012, 0.024))
    assert fine > 1.5 * coarse


def _quadratic_counts(h: float) -> tuple:
    class Counted:
        n_cells = int(round(3.0 / h**2))  # a surface-dominated count: ~ size^-2

    return Counted(), 0.1


def test_to_count_corrects_the_size_and_warns_when_the_count_has_a_floor():
    surface = tet.read_surface((ts.ellipsoid(radii=RADII, divisions=4).points, _faces()))
    mesh, h, seconds, passes = to_count(_quadratic_counts, 5000, surface, "organ.stl")
    assert abs(mesh.n_cells / 5000 - 1) <= ELEMENT_TOLERANCE and len(passes) <= 2
    assert seconds == pytest.approx(0.1 * len(passes)) and h == passes[-1]["size"]

    class Floor:
        n_cells = 9000

    with pytest.warns(UserWarning, match="target_elements 1000 not reached within 30 %"):
        mesh, _, _, passes = to_count(lambda h: (Floor(), 0.0), 1000, surface, "organ.stl")
    assert 2 <= len(passes) <= MAX_PASSES and mesh.n_cells == 9000
    assert passes[-1]["size"] == pytest.approx(0.5 * surface.diagonal)  # no pass twice
    # never a step the wrong way; between passes on both sides of the request, log-log
    volume, area = 1.8e-4, 0.016
    assert next_size([(0.01, 4000)], 2000, volume, area) > 0.01
    assert next_size([(0.01, 1000)], 2000, volume, area) < 0.01
    assert next_size([(0.02, 1000), (0.01, 4000)], 2000, volume, area) == pytest.approx(
        0.02 / np.sqrt(2)
    )


def _faces() -> np.ndarray:
    return ts.ellipsoid(radii=RADII, divisions=4).facet_sets["surface"]


# -- smoothing ----------------------------------------------------------------------------------


def _normal_error(points: np.ndarray, faces: np.ndarray) -> float:
    """The mean angle (degrees) between the triangles' normals and the ellipsoid's."""
    x = points[faces]
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    g = x.mean(axis=1) / np.asarray(RADII) ** 2
    cos = np.einsum("ki,ki->k", n, g) / np.linalg.norm(n, axis=1) / np.linalg.norm(g, axis=1)
    return float(np.degrees(np.arccos(np.clip(cos, -1, 1))).mean())


@pytest.mark.parametrize("method", ["taubin", "sinc"])
def test_smoothing_keeps_the_volume_and_removes_the_staircase(clean_stairs, method):
    if method == "sinc":
        pytest.importorskip("vtkmodules")
    surface = tet.read_surface(clean_stairs)
    smoothed, report = smooth_surface(surface, method, 20)
    exact = 4 / 3 * np.pi * np.prod(RADII)
    assert surface.volume == pytest.approx(exact, rel=0.01)  # the voxelisation's volume
    assert smoothed.volume == pytest.approx(surface.volume, rel=1e-9)  # kept by the scaling
    assert abs(report["shrinkage"]) < 0.01 and report["volume_restored"]  # even before it
    assert np.array_equal(smoothed.faces, surface.faces)
    # the steps: the normals turn towards the ellipsoid's, neighbours agree
    before, after = (
        _normal_error(surface.points, surface.faces),
        _normal_error(smoothed.points, smoothed.faces),
    )
    assert before > 15.0 and after < 0.5 * before
    assert report["normal_variation_after_deg"] < 0.6 * report["normal_variation_before_deg"]
    assert report["normal_variation_after_deg"] == pytest.approx(
        normal_variation(smoothed.points, smoothed.faces), abs=1e-3
    )
    # the surface stays where it was: within a voxel of the ellipsoid
    level = np.sqrt(((smoothed.points / np.asarray(RADII)) ** 2).sum(axis=1))
    assert np.abs(level - 1.0).max() * min(RADII) < VOXEL


@needs_pytetwild
def test_a_smoothed_staircase_is_meshed_with_its_volume(stairs):
    r = tet.tetrahedralize(stairs, 0.015, smoothing="taubin", smoothing_iterations=30).report
    surface = tet.read_surface(stairs)
    assert r["smoothing"]["method"] == "taubin" and r["smoothing"]["iterations"] == 30
    assert r["volume"] == pytest.approx(surface.volume, rel=0.02)
    assert (
        r["smoothing"]["normal_variation_after_deg"] < r["smoothing"]["normal_variation_before_deg"]
    )


# -- options: errors, and one code path from the API, the CLI and a scene ----------------------


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"epsilon": -1e-3}, "epsilon must be > 0"),
        ({"epsilon": 0.7}, "epsilon must be below 0.5"),
        ({"epsilon": "1e-3"}, "epsilon must be a number"),
        ({"envelope": 0.0}, "envelope must be > 0"),
        ({"epsilon": 1e-3, "envelope": 1e-4}, "give epsilon .* or envelope .*, not both"),
        ({"target_elements": 0}, "target_elements must be a whole number >= 1, not 0"),
        ({"target_elements": -5}, "target_elements must be a whole number >= 1"),
        ({"target_elements": 2.5}, "target_elements must be a whole number >= 1"),
        ({"target_elements": 10**8}, "target_elements must be at most 5e\\+06"),
        ({"target_elements": 1000, "size": 0.01}, "give size .* or target_elements"),
        ({"smoothing": "gauss"}, "smoothing must be one of 'none', 'taubin', 'sinc', not 'gauss'"),
        ({"smoothing_iterations": 0}, "smoothing_iterations must be a whole number >= 1"),
        ({"coarsen": "yes"}, "coarsen must be true or false"),
        ({"epsilon": 1e-3, "mesher": "tetgen"}, "epsilon: options of mesher 'pytetwild'"),
        ({"coarsen": True, "mesher": "gmsh"}, "coarsen: options of mesher 'pytetwild'"),
    ],
)
def test_bad_options_are_one_error_line_naming_the_option(options, message, monkeypatch):
    monkeypatch.setattr(tet, "run_mesher", _never)
    monkeypatch.setattr(meshers, "_import", lambda name: None)
    points, faces = ts.ellipsoid(radii=RADII, divisions=4).points, _faces()
    with pytest.raises(InputError, match=message) as info:
        tet.tetrahedralize((points, faces), **options)
    assert "\n" not in str(info.value)


def _never(*args):
    raise AssertionError("meshed although an option was bad")


def test_bad_threads_variable_names_it(monkeypatch):
    monkeypatch.setenv("TISSUESIM_MESH_THREADS", "two")
    with pytest.raises(InputError, match="TISSUESIM_MESH_THREADS='two': give a whole number"):
        meshers.mesh_threads()
    monkeypatch.setenv("TISSUESIM_MESH_THREADS", "2")
    assert meshers.mesh_threads() == 2


@pytest.fixture
def organ(tmp_path) -> Path:
    m = ts.ellipsoid(radii=RADII, divisions=6)
    path = tmp_path / "organ.stl"
    meshio.write_points_cells(path, m.points, [("triangle", m.facet_sets["surface"])], binary=True)
    return path


class _Recorded(Exception):
    pass


def _record(calls: list):
    def run_mesher(name, points, faces, size, source, options=None):
        calls.append({"name": name, "points": points.copy(), "size": size, **(options or {})})
        raise _Recorded

    return run_mesher


def test_the_cli_and_the_scene_keys_reach_the_same_meshing(organ, tmp_path, monkeypatch):
    calls: list[dict] = []
    monkeypatch.setattr(tet, "run_mesher", _record(calls))
    with pytest.raises(_Recorded):
        ts.mesh_surface(
            organ, target_elements=3000, epsilon=2e-3, coarsen=True, smoothing="taubin",
            smoothing_iterations=7,
        )  # fmt: skip
    command = ["mesh", str(organ), "-o", str(tmp_path / "o.vtu"), "--elements", "3000"]
    command += ["--epsilon", "2e-3", "--coarsen", "--smoothing", "taubin"]
    command += ["--smoothing-iterations", "7", "--debug"]
    with pytest.raises(_Recorded):
        main(command)
    scene = tmp_path / "scene.toml"
    scene.write_text(
        textwrap.dedent(
            """
            [mesh]
            surface = "organ.stl"
            target_elements = 3000
            epsilon = 2e-3
            coarsen = true
            smoothing = "taubin"
            smoothing_iterations = 7

            [material]
            model = "neo_hookean"
            youngs_modulus = 3000.0
            poisson_ratio = 0.4

            [simulation]
            density = 1000.0
            integrator = "quasistatic"
            time_step = 0.1
            """
        )
    )
    with pytest.raises(_Recorded):
        load_scene(scene)
    api, cli, keys = calls
    assert api["name"] == "pytetwild" and api["epsilon"] == 2e-3 and api["coarsen"] is True
    for other in (cli, keys):
        assert other.keys() == api.keys()
        assert all(np.array_equal(other[k], api[k]) for k in api)  # the smoothed surface too


def test_the_default_envelope_follows_the_size(organ, monkeypatch):
    calls: list[dict] = []
    monkeypatch.setattr(tet, "run_mesher", _record(calls))
    for options in ({"size": 0.01}, {"size": 0.01, "envelope": 3e-4}, {"epsilon": 4e-3}):
        with pytest.raises(_Recorded):
            ts.mesh_surface(organ, **options)
    diagonal = tet.read_surface(organ).diagonal
    assert calls[0]["epsilon"] == pytest.approx(0.01 / 20 / diagonal)
    assert calls[1]["epsilon"] == pytest.approx(3e-4 / diagonal)
    assert calls[2]["epsilon"] == 4e-3 and calls[2]["coarsen"] is False


@pytest.mark.parametrize(
    ("argument", "message"),
    [
        (["--elements", "0"], "argument --elements: must be a whole number >= 1, not '0'"),
        (["--elements", "many"], "argument --elements: must be a whole number >= 1"),
        (["--epsilon", "-0.001"], "argument --epsilon: must be a fraction"),
        (["--envelope", "-1"], "argument --envelope: must be a length in metres > 0"),
        (["--smoothing", "gauss"], "argument --smoothing: invalid choice: 'gauss'"),
        (["--smoothing-iterations", "0"], "argument --smoothing-iterations: must be a whole"),
        (["--size", "0.01", "--elements", "100"], "argument --elements: not allowed with"),
        (["--epsilon", "1e-3", "--envelope", "1e-4"], "argument --envelope: not allowed with"),
    ],
)
def test_bad_cli_options_name_the_option(organ, tmp_path, capsys, argument, message):
    with pytest.raises(SystemExit) as info:
        main(["mesh", str(organ), "-o", str(tmp_path / "o.vtu"), *argument])
    err = capsys.readouterr().err
    assert info.value.code == 2 and message in err
    assert [line for line in err.splitlines() if "error" in line] == [err.splitlines()[-1]]


@pytest.mark.parametrize(
    ("keys", "message"),
    [
        ("target_elements = 0", "target_elements must be a whole number >= 1"),
        ('smoothing = "gauss"', "smoothing must be one of"),
        ("epsilon = -0.001", "epsilon must be > 0"),
        ("coarsen = 1", "coarsen must be true or false"),
        ("size = 0.01\ntarget_elements = 100", "give size .* or target_elements"),
    ],
)
def test_bad_scene_keys_name_the_key(organ, tmp_path, keys, message):
    scene = tmp_path / "scene.toml"
    scene.write_text(
        f'[mesh]\nsurface = "organ.stl"\n{keys}\n\n[material]\nmodel = "neo_hookean"\n'
        "youngs_modulus = 3000.0\npoisson_ratio = 0.4\n\n[simulation]\ndensity = 1000.0\n"
        'integrator = "quasistatic"\ntime_step = 0.1\n'
    )
    with pytest.raises(SceneError, match=message) as info:
        load_scene(scene)
    assert "[mesh]" in str(info.value) and "\n" not in str(info.value)


@needs_pytetwild
def test_cli_meshes_to_an_element_count(organ, tmp_path, capsys):
    import json

    out = tmp_path / "organ.vtu"
    assert main(["mesh", str(organ), "-o", str(out), "--elements", "1500", "--coarsen"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["target_elements"] == 1500 and summary["coarsen"] is True
    assert abs(summary["n_tets"] / 1500 - 1) <= ELEMENT_TOLERANCE
    assert ts.read_mesh(out).n_cells == summary["n_tets"] and summary["passes"]


def test_mesh_errors_keep_their_type(monkeypatch, organ):
    """A mesher failure inside the count's passes is the MeshError it was."""
    monkeypatch.setattr(tet, "available_meshers", lambda: ["pytetwild"])
    monkeypatch.setattr(
        tet, "run_mesher", lambda *a: (np.zeros((4, 3)), np.zeros((0, 4), dtype=np.int64))
    )
    with pytest.raises(MeshError, match="produced no tetrahedra"):
        ts.mesh_surface(organ, target_elements=100)
