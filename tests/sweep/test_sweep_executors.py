"""The default executor: a spawn process pool, one thread per worker, its workers gone when the
study's process is killed (SIGKILL leaves no orphan waiting for work)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from tissuesim.sweep.executors import process_pool


def _thread_variables() -> dict:
    from threadpoolctl import threadpool_info

    return {
        "env": {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")},
        "blas": sorted({i["num_threads"] for i in threadpool_info()}),
        "pid": os.getpid(),
    }


def test_the_pool_has_one_thread_per_worker_started_at_once():
    pytest.importorskip("threadpoolctl")
    before = {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")}
    with process_pool(2) as pool:
        seen = [pool.submit(_thread_variables).result() for _ in range(4)]
    for s in seen:
        assert s["env"] == {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
        assert s["blas"] in ([1], [])
    assert len({s["pid"] for s in seen}) <= 2
    # this process's environment is left as it was
    assert {k: os.environ.get(k) for k in before} == before


@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc")
def test_the_workers_leave_when_the_study_process_is_killed(tmp_path):
    script = textwrap.dedent(
        """
        import sys, time
        from tissuesim.sweep.executors import process_pool, _ready
        if __name__ == "__main__":
            pool = process_pool(1)
            print(pool.submit(_ready).result(), flush=True)
            time.sleep(60)
        """
    )
    path = tmp_path / "study.py"
    path.write_text(script)
    proc = subprocess.Popen([sys.executable, str(path)], stdout=subprocess.PIPE, text=True)
    worker = int(proc.stdout.readline())
    assert os.path.exists(f"/proc/{worker}")
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    deadline = time.monotonic() + 10
    while os.path.exists(f"/proc/{worker}") and time.monotonic() < deadline:
        time.sleep(0.2)
    gone = not os.path.exists(f"/proc/{worker}")
    if not gone:
        os.kill(worker, signal.SIGKILL)
    assert gone, "the pool's worker outlived the killed study process"
