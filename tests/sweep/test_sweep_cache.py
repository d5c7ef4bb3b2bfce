"""The worker's mesh cache (sweep/cache.py): a second run on the same mesh file (or surface) in
the same process reads it from the cache, and its results equal those of an uncached run bit
for bit; a rewritten file is read again; every run gets its own copy; outside a study's run
nothing is cached."""

from __future__ import annotations

import tomllib
from concurrent.futures import ThreadPoolExecutor

import meshio
import numpy as np
import pytest

import tissuesim
from tissuesim.mesh.io import write_mesh
from tissuesim.scene.loader import build_scene
from tissuesim.sweep import cache
from tissuesim.sweep.runs import prepare_worker

VARY = {"material.youngs_modulus": [800.0, 1500.0, 2500.0]}


@pytest.fixture
def fresh_cache():
    prepare_worker()  # installs the wrappers (once per process)
    cache.clear()
    yield
    cache.clear()


def _uncached(scene, youngs_modulus):
    data = tomllib.loads(scene.read_text())
    data["material"]["youngs_modulus"] = youngs_modulus
    sim = build_scene(data, base_dir=scene.parent, source=str(scene)).simulation
    sim.run(2, progress=False, render=False)
    return sim


def test_a_second_run_reads_the_mesh_from_the_cache_bit_for_bit(bar_scene, tmp_path, fresh_cache):
    out = tmp_path / "s"
    with ThreadPoolExecutor(1) as pool:  # the runs in this process: its cache is seen here
        results = tissuesim.sweep(
            bar_scene, VARY, out=out, executor=pool, fields=["displacement"], progress=False
        )
    assert cache.stats() == {"hits": 2, "misses": 1, "meshes": 1}
    data = tissuesim.sweep.load_dataset(out)
    for i, result in enumerate(results):
        assert result["status"] == "completed", result["error"]
        sim = _uncached(bar_scene, result["params"]["material.youngs_modulus"])
        assert result["forces"] == sim.forces()  # exact
        assert np.array_equal(data["body/displacement"][i], sim.body_displacement("body"))
    assert cache.stats()["hits"] == 2  # the uncached runs above did not use it


def test_the_sparsity_analysis_of_a_shared_mesh_is_made_once_per_worker(
    bar_scene, tmp_path, fresh_cache
):
    with ThreadPoolExecutor(1) as pool:
        results = tissuesim.sweep(bar_scene, VARY, out=tmp_path / "s", executor=pool,
                                  progress=False)  # fmt: skip
    counts = cache.pattern_stats()
    assert counts["misses"] >= 1 and counts["hits"] == 2 * counts["misses"]  # 3 runs, 1 mesh
    for result in results:
        sim = _uncached(bar_scene, result["params"]["material.youngs_modulus"])
        assert result["forces"] == sim.forces()  # exact
    assert cache.pattern_stats()["hits"] == counts["hits"]  # outside a run: not cached
    # each run has its own copy: changing one does not change what the next run gets
    from tissuesim.assembly.pattern import SparsityPattern

    stencil = np.array([[0, 1, 2, 3, 4, 5]])
    with cache.enabled():
        first = SparsityPattern.from_stencils(6, [stencil])
        first.indices[:] = 0
        second = SparsityPattern.from_stencils(6, [stencil])
    assert np.array_equal(second.indices, SparsityPattern.from_stencils(6, [stencil]).indices)
    assert not np.array_equal(first.indices, second.indices)


def test_a_rewritten_mesh_file_is_read_again(bar_scene, tmp_path, fresh_cache):
    folder = tmp_path / "scene"
    (folder / "mesh").mkdir(parents=True)
    scene = folder / "bar.toml"
    scene.write_text(bar_scene.read_text())
    mesh_file = folder / "mesh" / "bar.vtu"
    vary = {"material.youngs_modulus": [800.0]}
    with ThreadPoolExecutor(1) as pool:
        write_mesh(tissuesim.box((0, 0, 0), (1.0, 0.25, 0.25), (4, 1, 1)), mesh_file)
        a = tissuesim.sweep(scene, vary, out=tmp_path / "a", executor=pool, progress=False)
        write_mesh(tissuesim.box((0, 0, 0), (1.0, 0.25, 0.25), (8, 1, 1)), mesh_file)
        b = tissuesim.sweep(scene, vary, out=tmp_path / "b", executor=pool, progress=False)
    assert cache.stats() == {"hits": 0, "misses": 2, "meshes": 2}
    assert a[0]["forces"] == _uncached(bar_scene, 800.0).forces()
    assert b[0]["forces"] == _uncached(scene, 800.0).forces()  # the 8-box bar's
    assert a[0]["forces"] != b[0]["forces"]


def test_each_run_gets_its_own_copy_and_outside_a_run_nothing_is_cached(bar_scene, fresh_cache):
    path = bar_scene.parent / "mesh" / "bar.vtu"
    first = tissuesim.mesh.read_mesh(path)
    assert cache.stats() == {"hits": 0, "misses": 0, "meshes": 0}  # not in a study's run
    with cache.enabled():
        a = tissuesim.mesh.read_mesh(path)
        a.points[0, 0] = 99.0  # a run changing its mesh
        b = tissuesim.read_mesh(path)
    assert cache.stats() == {"hits": 1, "misses": 1, "meshes": 1}
    assert np.array_equal(b.points, first.points) and b.points is not a.points
    assert sorted(b.point_sets) == sorted(first.point_sets)
    for name in first.point_sets:
        assert np.array_equal(b.point_sets[name], first.point_sets[name])
    with cache.enabled(), pytest.raises(tissuesim.MeshError, match="no such mesh file"):
        tissuesim.mesh.read_mesh(path.parent / "missing.vtu")  # errors as without the cache


def test_the_cache_keeps_at_most_max_meshes(bar_scene, tmp_path, fresh_cache, monkeypatch):
    monkeypatch.setattr(cache, "MAX_MESHES", 2)
    for n in (2, 3, 4):
        write_mesh(tissuesim.box((0, 0, 0), (1.0, 0.25, 0.25), (n, 1, 1)), tmp_path / f"{n}.vtu")
    with cache.enabled():
        for n in (2, 3, 4, 2):
            assert tissuesim.mesh.read_mesh(tmp_path / f"{n}.vtu").n_cells == 6 * n
    assert cache.stats() == {"hits": 0, "misses": 4, "meshes": 2}  # bar2 was dropped


def test_a_surface_is_meshed_once_per_worker(tmp_path, fresh_cache):
    from tissuesim.mesh.from_surface import meshers

    if "pytetwild" not in meshers.available_meshers():
        pytest.skip("pytetwild (a dependency) is not installed")
    surface = tissuesim.ellipsoid(radii=(0.05, 0.03, 0.02), divisions=4)
    meshio.write_points_cells(
        tmp_path / "organ.stl", surface.points, [("triangle", surface.facet_sets["surface"])]
    )
    scene = tmp_path / "organ.toml"
    scene.write_text(
        '[mesh]\nsurface = "organ.stl"\nsize = 0.02\n\n[material]\nmodel = "neo_hookean"\n'
        "youngs_modulus = 3000.0\npoisson_ratio = 0.4\n\n[simulation]\n"
        'integrator = "quasistatic"\ntime_step = 0.5\n\n[[dirichlet]]\n'
        'vertices = { where = "z < 0" }\n\n[run]\nsteps = 1\n'
    )
    with ThreadPoolExecutor(1) as pool:
        results = tissuesim.sweep(
            scene, {"material.youngs_modulus": [2e3, 4e3]}, out=tmp_path / "s",
            executor=pool, fields=["displacement"], progress=False,
        )  # fmt: skip
    assert [r["status"] for r in results] == ["completed", "completed"], results[0]["error"]
    assert cache.stats() == {"hits": 1, "misses": 1, "meshes": 1}
    data = tissuesim.sweep.load_dataset(tmp_path / "s")
    assert data["body/displacement"].shape[0] == 2


def test_a_generated_mesh_is_made_once_per_worker(bar_scene, tmp_path, fresh_cache):
    scene = tmp_path / "bar.toml"
    scene.write_text(
        bar_scene.read_text().replace(
            'file = "mesh/bar.vtu"',
            'generator = "box"\nlower = [0.0, 0.0, 0.0]\nupper = [1.0, 0.25, 0.25]\n'
            "divisions = [4, 1, 1]",
        )
    )
    with ThreadPoolExecutor(1) as pool:
        results = tissuesim.sweep(scene, VARY, out=tmp_path / "s", executor=pool, progress=False)
    assert cache.stats() == {"hits": 2, "misses": 1, "meshes": 1}
    for result in results:
        sim = _uncached(scene, result["params"]["material.youngs_modulus"])
        assert result["forces"] == sim.forces()  # exact
    assert results[0]["forces"] == _uncached(bar_scene, 800.0).forces()  # the file's bar


def test_the_cache_is_off_with_the_environment_variable(bar_scene, fresh_cache, monkeypatch):
    monkeypatch.setenv("TISSUESIM_SWEEP_CACHE", "0")
    with cache.enabled():
        tissuesim.mesh.read_mesh(bar_scene.parent / "mesh" / "bar.vtu")
        tissuesim.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    assert cache.stats() == {"hits": 0, "misses": 0, "meshes": 0}


def test_arguments_key_by_value_arrays_by_their_bytes():
    import numpy as np

    a = np.arange(5000.0)
    b = a.copy()
    b[2500] = -1.0  # the same repr ("...") but other bytes
    assert cache._option_key({"x": a}) != cache._option_key({"x": b})
    assert cache._option_key({"x": a}) == cache._option_key({"x": a.copy()})
    assert cache._option_key({"x": [1, 2]}) != cache._option_key({"x": (1, 2)})
    assert cache._option_key({"x": 1}) != cache._option_key({"x": 1.0})
    assert cache._option_key({"x": object()}) is None  # not cached


def test_the_glue_between_two_bodies_is_searched_once_per_worker(tmp_path, fresh_cache):
    # two_blocks_tied glues its fat layer on the muscle: the closest-point search of the tie
    # is the same in every run that keeps the meshes (a stiffness varied)
    vary = {"bodies[0].material.youngs_modulus": [2e3, 6e3]}
    with ThreadPoolExecutor(1) as pool:
        results = tissuesim.sweep("two_blocks_tied", vary, out=tmp_path / "s", steps=2,
                                  executor=pool, progress=False)  # fmt: skip
    assert cache.tie_stats() == {"hits": 1, "misses": 1, "ties": 1}
    from tissuesim.scene.examples import example_path

    scene = example_path("two_blocks_tied")
    for result in results:
        data = tomllib.loads(scene.read_text())
        data["bodies"][0]["material"]["youngs_modulus"] = result["params"][next(iter(vary))]
        sim = build_scene(data, base_dir=scene.parent, source=str(scene)).simulation
        sim.run(2, progress=False, render=False)
        assert result["forces"] == sim.forces()  # exact
    assert results[0]["forces"] != results[1]["forces"]
    # another layer thickness (moved mesh) is searched again, not taken from the cache
    from tissuesim.coupling.tie import tie_bodies

    upper = tissuesim.box((0, 0, 0.0), (1.0, 1.0, 0.5), (2, 2, 1))
    lower = tissuesim.box((0, 0, -0.5), (1.0, 1.0, 0.0), (2, 2, 1))
    with cache.enabled():
        first = tie_bodies("t", "u", upper, "l", lower, distance=1e-6, stiffness_per_area=1.0)
        stiffer = tie_bodies("t", "u", upper, "l", lower, distance=1e-6, stiffness_per_area=2.0)
        upper.points[:, 2] += 1e-7
        moved = tie_bodies("t", "u", upper, "l", lower, distance=1e-6, stiffness_per_area=1.0)
    assert cache.tie_stats() == {"hits": 2, "misses": 3, "ties": 3}
    assert np.array_equal(stiffer.stiffness, 2.0 * first.stiffness)  # applied after the search
    assert not np.array_equal(first.offset, moved.offset)
