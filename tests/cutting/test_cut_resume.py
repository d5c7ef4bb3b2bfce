"""Cut and torn bodies resume like every other run (issue 41, ``io/checkpoints/cuts.py``): a
checkpoint taken while a blade cuts or a body tears holds the cut topology, the blades' and
cracks' progress, and the run resumed from it equals the run that never stopped bit for bit
(positions, velocities, forces, residuals, cut reports, output files), with a cut before the
checkpoint and one after it; a real SIGKILL then ``--resume`` too.

Compared with ipctk and MKL (PARDISO) on one thread: their parallel sums differ in the last
bits between any two runs on several threads, resumed or not."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import tomllib
import xml.etree.ElementTree as ET
from dataclasses import asdict

import meshio
import numpy as np
import pytest
from test_tear_several import two_spans
from test_tearing import STRENGTH

import tissuesim as ts
from tissuesim.cli import example_path, main
from tissuesim.errors import InputError
from tissuesim.scene.loader import build_scene

#: the shipped liver resection, coarser (1,323 DOFs): the blade enters the organ's cells at
#: step 18, cuts through it by step 24 (two pieces), the lobe then falls onto the table
LIVER = example_path("liver_resection").read_text().replace("divisions = 8", "divisions = 6")


@pytest.fixture
def one_thread():
    """ipctk and MKL (PARDISO) on one thread, for runs that must repeat bit for bit."""
    import ipctk
    from threadpoolctl import threadpool_limits

    from tissuesim.solve.linear import _mkl_pardiso, has_pardiso

    if has_pardiso():
        _mkl_pardiso()  # loaded now, so that its threads are limited with the others
    before = ipctk.get_num_threads()
    ipctk.set_num_threads(1)
    with threadpool_limits(1):
        yield
    ipctk.set_num_threads(before)


def _liver(linear_solver: str = "splu", text: str = LIVER) -> ts.Simulation:
    data = tomllib.loads(text)
    data.setdefault("newton", {})["linear_solver"] = linear_solver
    return build_scene(data).simulation


def _key(record) -> tuple:
    """What a step reports that must repeat (not its wall times)."""
    extra = record.extra
    return (record.time, record.residual_norms, record.newton_iterations, extra["forces"],
            extra.get("cuts"), record.min_J, record.energies)  # fmt: skip


def _assert_same(a: ts.Simulation, b: ts.Simulation) -> None:
    assert np.array_equal(a.state.x, b.state.x)
    assert np.array_equal(a.state.v, b.state.v)
    assert [_key(r) for r in a.history] == [_key(r) for r in b.history]
    for name, body in a.bodies.items():
        other = b.bodies[name]
        assert np.array_equal(body.mesh.points, other.mesh.points)
        assert np.array_equal(body.mesh.cells, other.mesh.cells)
        assert np.array_equal(body.model.pattern.indices, other.model.pattern.indices)


def _resumed(make, steps: int, at: int, path) -> ts.Simulation:
    first = make()
    first.run(at, None, progress=False)
    first.save(path)
    again = make().load(path)
    assert np.array_equal(again.state.x, first.state.x)
    again.run(steps - at, None, progress=False)
    return again


@pytest.mark.parametrize("linear_solver", ["splu", "auto"])
def test_a_run_resumed_mid_cut_is_bit_identical(tmp_path, one_thread, linear_solver):
    make = lambda: _liver(linear_solver)  # noqa: E731
    whole = make()
    whole.run(28, None, progress=False)
    cut = [r.extra["cuts"]["scalpel"] for r in whole.history]
    assert cut[17]["cells_cut"] > 0 and cut[16]["area_m2"] == 0.0  # it starts at step 18
    assert cut[23]["pieces"] == 2 and cut[22]["pieces"] == 1  # and parts the lobe at 24
    for at in (20, 25):  # mid-cut (cells cut before and after), and after it parted the lobe
        again = _resumed(make, 28, at, tmp_path / f"at{at}.npz")
        _assert_same(whole, again)
    with np.load(tmp_path / "at20.npz") as data:
        assert "cut.liver.vn.cells" in data.files  # the cut topology is in the checkpoint
        assert len(data["cut.liver.vn.points"]) > whole.bodies["liver"].cut_state.original.n_points


def test_a_torn_body_resumes_between_and_after_its_cracks(tmp_path, one_thread):
    """The bar of test_tear_several tears in its near span at step 16 and in its far span at
    31: resumed right after the first crack and between the two, it tears the second time
    at the same step, along the same plane, and carries the same forces."""

    def make() -> ts.Simulation:
        sim = two_spans()
        sim.set_tearing(body="body", stress=STRENGTH)
        return sim

    whole = make()
    whole.run(34, None, progress=False)
    torn = [k + 1 for k, r in enumerate(whole.history)
            for report in r.extra["cuts"].values() if report["cells_cut"]]  # fmt: skip
    assert torn == [16, 31]
    for at in (16, 24):
        again = _resumed(make, 34, at, tmp_path / f"at{at}.npz")
        _assert_same(whole, again)
        for a, b in zip(whole.organ_tears[0].cracks, again.organ_tears[0].cracks, strict=True):
            assert np.array_equal(a.point, b.point) and np.array_equal(a.corners, b.corners)


def _plate() -> ts.Simulation:
    """A plate hung by its top edge whose crack turns (a prescribed stress field, as in
    test_tear_turning: over the strength left of a front that moves 0.25 per step, its
    direction turned by 45 degrees beyond x = 0.5), then starts more cracks far from it."""
    theta, h = np.radians(45.0), 0.01
    mesh = ts.rectangle((0.0, 0.0), (1.0, 1.0), (20, 20))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), density=1.0,
                        time_step=h, gravity=(0.0, -1.0))  # fmt: skip
    sim.fix(np.flatnonzero(mesh.points[:, 1] > 1 - 1e-9))
    sim.set_tearing(body="body", stress=1.0)

    def measure(body, c):
        front = 0.25 * round(sim.time / h)
        x = c.reshape(-1, 2)[body.mesh.cells].mean(axis=1)
        value = np.where(x[:, 0] < front, 2.0 - 0.1 * x[:, 0] - 0.1 * abs(x[:, 1] - 0.5), 0.0)
        turned = np.array([-np.sin(theta), np.cos(theta)])
        return value, np.where((x[:, 0] < 0.5)[:, None], [0.0, 1.0], turned)

    sim.organ_tears[0].measure = measure
    return sim


def test_a_turned_crack_and_later_cracks_resume(tmp_path):
    whole = _plate()
    whole.run(8, None, progress=False)
    cracks = whole.organ_tears[0].cracks
    assert [c.name for c in cracks] == ["tear", "tear2", "tear3", "tear4"]
    assert len(cracks[0].pieces) == 1  # turned once (at step 3)
    for at in (3, 5):  # after the turn, and with a second crack
        again = _resumed(_plate, 8, at, tmp_path / f"at{at}.npz")
        _assert_same(whole, again)
        for a, b in zip(cracks, again.organ_tears[0].cracks, strict=True):
            assert a.name == b.name and len(a.pieces) == len(b.pieces)
            assert np.array_equal(a.normal, b.normal) and np.array_equal(a.corners, b.corners)
        vn_a, vn_b = (s.bodies["body"].cut_state.vn for s in (whole, again))
        assert np.array_equal(vn_a.level, vn_b.level) and np.array_equal(vn_a.cells, vn_b.cells)


# -- the command line: --resume, and a real kill -------------------------------------------
def _cli(*argv) -> int:
    return main([str(a) for a in argv])


def _frames(out, name: str) -> list:
    root = ET.parse(out / f"{name}.pvd").getroot()
    return [(d.get("timestep"), d.get("file")) for d in root.iter("DataSet")]


def _assert_same_output(a, b, names) -> None:
    for name in names:
        assert _frames(a, name) == _frames(b, name)
        for _, file in _frames(a, name):
            ma, mb = meshio.read(a / file), meshio.read(b / file)
            assert np.array_equal(ma.points, mb.points)
            pairs = zip(ma.cells, mb.cells, strict=True)
            assert all(np.array_equal(x.data, y.data) for x, y in pairs)
            for key, value in ma.point_data.items():
                assert np.array_equal(value, mb.point_data[key]), (file, key)
            for key, value in ma.cell_data.items():
                pairs = zip(value, mb.cell_data[key], strict=True)
                assert all(np.array_equal(x, y) for x, y in pairs), (file, key)
    assert (a / "forces.csv").read_text() == (b / "forces.csv").read_text()
    sa, sb = (json.loads((d / "summary.json").read_text()) for d in (a, b))
    assert sa["status"] == sb["status"] == "completed"
    assert sa["forces"] == sb["forces"]
    assert sa["simulation"] == sb["simulation"]  # the set-up as the run started: the mesh uncut
    for x, y in zip(sa["steps"], sb["steps"], strict=True):
        assert x["residual_norms"] == y["residual_norms"]
        assert x["extra"]["cuts"] == y["extra"]["cuts"]


def test_cli_resume_of_a_tearing_strip(tmp_path, one_thread):
    """The shipped strip_tearing, pulled 4x as fast (it tears at steps 15-16): stopped at step
    15 as the crack starts, resumed to 18, it equals the run that never stopped."""
    text = example_path("strip_tearing").read_text()
    text = text.replace('"0.0005 * t"', '"0.002 * t"').replace("every = 2", "every = 1")
    path = tmp_path / "strip.toml"
    path.write_text(text)
    whole, part = tmp_path / "whole", tmp_path / "part"
    assert _cli("run", path, "--out", whole, "--quiet", "--no-render", "--steps", 18) == 0
    cuts = [s["extra"]["cuts"]["strip.tear"]
            for s in json.loads((whole / "summary.json").read_text())["steps"]]  # fmt: skip
    first = next(k for k, c in enumerate(cuts) if c["cells_cut"]) + 1
    assert first == 15 and cuts[-1]["pieces"] == 2  # torn across the checkpoint
    assert _cli("run", path, "--out", part, "--quiet", "--no-render", "--steps", 15) == 0
    assert (part / "checkpoint.npz").is_file()
    assert _cli("run", path, "--out", part, "--quiet", "--no-render", "--resume",
                "--steps", 18) == 0  # fmt: skip
    _assert_same_output(whole, part, ("strip",))


def test_kill_mid_cut_then_resume(tmp_path, one_thread):
    """A cutting run killed (SIGKILL) after the blade has started cutting, resumed with
    --resume, writes what the run that never stopped writes."""
    text = LIVER.replace("steps = 60", "steps = 40") + '\n[newton]\nlinear_solver = "splu"\n'
    path = tmp_path / "liver.toml"
    path.write_text(text)
    whole, killed = tmp_path / "whole", tmp_path / "killed"
    assert _cli("run", path, "--out", whole, "--quiet", "--no-render") == 0
    env = dict(os.environ, TISSUESIM_CONTACT_THREADS="1", MKL_NUM_THREADS="1")
    proc = subprocess.Popen(
        [sys.executable, "-m", "tissuesim", "run", str(path), "--out", str(killed), "--quiet",
         "--no-render"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
    )  # fmt: skip
    history = killed / "checkpoint_history.jsonl"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if history.is_file() and history.read_text().count("\n") >= 21:
            break
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run ended before the kill"
    assert json.loads((killed / "summary.json").read_text())["status"] == "running"
    with np.load(killed / "checkpoint.npz") as data:
        assert "cut.liver.vn.cells" in data.files  # killed after the cut had started
    assert _cli("run", path, "--out", killed, "--quiet", "--no-render", "--resume") == 0
    _assert_same_output(whole, killed, ("liver", "table"))


# -- formats -------------------------------------------------------------------------------
def _rewrite(path, **changes) -> None:
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays.pop("__meta__")))
    meta.update(changes)
    meta = {k: v for k, v in meta.items() if v is not None}
    np.savez(path, __meta__=np.array(json.dumps(meta)), **arrays)


def test_checkpoint_formats(tmp_path):
    """Format 2 keeps cuts; a format 1 checkpoint (before) still loads where nothing cuts (it
    was never written where something did) and is refused in one line where something does;
    an unknown format is refused in one line naming it."""
    mesh = ts.rectangle((0, 0), (1, 0.2), (6, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)

    def beam() -> ts.Simulation:
        sim = ts.Simulation(mesh, material, density=100, time_step=0.01, gravity=(0, -9.81))
        sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9))
        return sim

    sim = beam()
    sim.run(2, None, progress=False)
    sim.save(tmp_path / "beam.npz")
    _rewrite(tmp_path / "beam.npz", format=1, cuts=None)
    assert np.array_equal(beam().load(tmp_path / "beam.npz").state.x, sim.state.x)
    liver = _liver()
    liver.save(tmp_path / "liver.npz")
    assert np.load(tmp_path / "liver.npz")["blade.scalpel.numbers"].shape == (2,)
    _rewrite(tmp_path / "liver.npz", format=1, cuts=None)
    with pytest.raises(InputError, match="holds no cut state .*format 1") as info:
        _liver().load(tmp_path / "liver.npz")
    assert "\n" not in str(info.value)
    _rewrite(tmp_path / "beam.npz", format=99)
    with pytest.raises(InputError, match="checkpoint of format 99 .*reads formats 1, 2") as info:
        beam().load(tmp_path / "beam.npz")
    assert "\n" not in str(info.value)


def test_a_checkpoint_after_a_cut_is_checked_against_the_original_mesh(tmp_path):
    """A cut body's fingerprint is its set-up mesh: a checkpoint written after the cut loads
    into the scene set up anew, and not into one with another mesh or another blade."""
    sim = _liver()
    sim.run(19, None, progress=False)
    assert sim.bodies["liver"].cut_state.vn is not None
    sim.save(tmp_path / "cut.npz")
    _liver().load(tmp_path / "cut.npz")
    finer = LIVER.replace("divisions = 6", "divisions = 5")
    with pytest.raises(InputError, match="body 'liver': checkpoint"):
        _liver(text=finer).load(tmp_path / "cut.npz")
    slower = LIVER.replace("end = 0.3", "end = 0.4")
    with pytest.raises(InputError, match="cutting: checkpoint"):
        _liver(text=slower).load(tmp_path / "cut.npz")
    assert asdict(sim.history[-1]) == asdict(_liver().load(tmp_path / "cut.npz").history[-1])
