"""Issue 41: one run at a time per output directory (io/lock.py). A run into the folder of a
run in progress (another process) refuses in one line naming the folder and what to do, and
writes nothing; a lock left by a killed run never blocks the next one."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

import tissuesim as ts
from tissuesim.errors import OutputError
from tissuesim.io.lock import LOCK_FILE, run_lock

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="signals and fork-free timing")

# a real run whose steps are slowed (after the first) so the second process meets it running
SLOW_RUN = textwrap.dedent(
    """
    import sys, time
    import tissuesim as ts

    out, started = sys.argv[1], sys.argv[2]
    sim = ts.Simulation(integrator="quasistatic", time_step=0.1)
    body = sim.add_body(
        "body", ts.rectangle((0, 0), (1, 0.2), (4, 1)),
        ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3),
    )
    sim.fix("body", ts.select.vertices_on_plane(body.mesh, axis=0, value=0.0), name="wall")
    step = sim.step

    def slow_step():
        record = step()
        open(started, "w").close()
        time.sleep(float(sys.argv[3]))
        return record

    sim.step = slow_step
    sim.run(3, output=out, progress=False, render=False)
    """
)


def wait_for(path, process, timeout=60.0):
    end = time.monotonic() + timeout
    while not os.path.exists(path):
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < end, "the first run did not start"
        time.sleep(0.05)


def test_a_second_run_into_the_folder_of_a_run_in_progress_refuses(tmp_path):
    out, started = tmp_path / "out", tmp_path / "started"
    first = subprocess.Popen(
        [sys.executable, "-c", SLOW_RUN, str(out), str(started), "1.0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        wait_for(started, first)
        second = subprocess.run(
            [
                sys.executable,
                "-m",
                "tissuesim",
                "run",
                "course_stretch",
                "--out",
                str(out),
                "--quiet",
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        _, err = first.communicate(timeout=120)
    assert second.returncode == 2
    lines = second.stderr.strip().splitlines()
    assert len(lines) == 1, second.stderr
    assert str(out) in lines[0] and "in use by another run" in lines[0]
    assert f"pid {first.pid}" in lines[0] and "--out" in lines[0]
    assert "Traceback" not in second.stderr
    # the first run is whole and alone: its own 3 steps, its one body, completed
    assert first.returncode == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["totals"]["steps"] == 3
    assert sorted(summary["simulation"]["bodies"]) == ["body"]
    assert not (out / LOCK_FILE).exists()  # removed when the run ended


def test_a_lock_left_by_a_killed_run_does_not_block(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time, pathlib\n"
            "from tissuesim.io.lock import run_lock\n"
            "with run_lock(pathlib.Path(sys.argv[1])):\n"
            "    print('locked', flush=True); time.sleep(600)\n",
            str(out),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(OutputError, match="in use by another run"):
            with run_lock(out):
                pass
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait(timeout=30)
    assert (out / LOCK_FILE).exists()  # a kill -9 leaves the file, not the lock
    sim = ts.Simulation(integrator="quasistatic", time_step=0.1)
    body = sim.add_body(
        "body",
        ts.rectangle((0, 0), (1, 0.2), (4, 1)),
        ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3),
    )
    sim.fix("body", ts.select.vertices_on_plane(body.mesh, axis=0, value=0.0), name="wall")
    sim.run(1, output=out, progress=False, render=False)
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"
    assert not (out / LOCK_FILE).exists()


def test_the_same_process_cannot_run_twice_into_one_folder(tmp_path):
    with run_lock(tmp_path):
        with pytest.raises(OutputError, match=f"pid {os.getpid()}"):
            with run_lock(tmp_path):
                pass
    with run_lock(tmp_path):  # released: free again
        pass
