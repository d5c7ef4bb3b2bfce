"""``RayExecutor``: a ``concurrent.futures.Executor`` over Ray tasks. Ray is not a test
dependency (CI does not install it): the adapter is tested with an in-process stand-in for
Ray's module (``ray.remote``, ``ObjectRef.future``, ``ray.cancel``); where Ray is installed one
study also runs on a real local Ray cluster of one CPU."""

from __future__ import annotations

import csv
import pickle
import sys
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import tissuesim
from tissuesim.errors import InputError
from tissuesim.sweep.executors import RayExecutor, close, executor_from_spec
from tissuesim.sweep.runs import THREAD_VARIABLES

#: what every Ray task starts with: one thread, as the pool's workers
ONE_THREAD = {"runtime_env": {"env_vars": {name: "1" for name in THREAD_VARIABLES}}}

VARY = {"material.youngs_modulus": [800.0, 1500.0]}
TIMES = ("wall_time_s", "build_time_s", "setup_time_s", "solve_time_s", "fields_write_s")


class _Ref:
    def __init__(self, future):
        self._future = future

    def future(self):
        return self._future


class _Remote:
    def __init__(self, ray, fn):
        self.ray, self.fn = ray, fn

    def remote(self, *args):
        fn = self.fn
        if self.ray.pickled:  # what a Ray task gets is pickled: the run's task must travel
            fn, args = pickle.loads(pickle.dumps((fn, args)))
        return _Ref(self.ray.pool.submit(fn, *args))


class FakeRay:
    """The parts of Ray's module that RayExecutor uses, its tasks run on a thread here."""

    def __init__(self, pickled: bool = True):
        self.pool = ThreadPoolExecutor(1)
        self.pickled = pickled
        self.options, self.cancelled = None, []

    def remote(self, **options):
        self.options = options
        return lambda fn: _Remote(self, fn)

    def cancel(self, ref):
        self.cancelled.append(ref)


def _rows(path):
    with open(path, newline="") as f:
        return [{k: v for k, v in row.items() if k not in TIMES} for row in csv.DictReader(f)]


def _same_study(a, b, out_a, out_b):
    assert [r["status"] for r in a] == ["completed"] * len(a)
    assert [r["forces"] for r in a] == [r["forces"] for r in b]  # bit for bit
    assert _rows(out_a / "runs.csv") == _rows(out_b / "runs.csv")
    da, db = tissuesim.sweep.load_dataset(out_a), tissuesim.sweep.load_dataset(out_b)
    assert np.array_equal(da["body/displacement"], db["body/displacement"])


def test_a_study_through_the_ray_adapter_equals_a_thread_pool_one(bar_scene, tmp_path):
    fake = FakeRay()
    executor = RayExecutor(ray=fake)
    assert fake.options == {"num_cpus": 1, **ONE_THREAD}
    kwargs = {"fields": ["displacement"], "progress": False}
    ray = tissuesim.sweep(bar_scene, VARY, out=tmp_path / "r", executor=executor, **kwargs)
    executor.shutdown()
    with ThreadPoolExecutor(1) as pool:
        threads = tissuesim.sweep(bar_scene, VARY, out=tmp_path / "t", executor=pool, **kwargs)
    _same_study(ray, threads, tmp_path / "r", tmp_path / "t")
    fake.pool.shutdown()


def test_the_ray_adapter_passes_options_and_cancels_at_shutdown():
    fake = FakeRay(pickled=False)  # an Event does not pickle
    env = {"env_vars": {"OMP_NUM_THREADS": "2", "MY_VARIABLE": "x"}}
    executor = RayExecutor(num_cpus=2, ray=fake, max_retries=0, runtime_env=env)
    threads = {**ONE_THREAD["runtime_env"]["env_vars"], "OMP_NUM_THREADS": "2", "MY_VARIABLE": "x"}
    assert fake.options == {"num_cpus": 2, "max_retries": 0, "runtime_env": {"env_vars": threads}}
    release = threading.Event()
    first = executor.submit(release.wait, 10)
    second = executor.submit(pow, 2, 10)  # queued behind the first: one thread
    executor.shutdown(wait=False, cancel_futures=True)
    # both unfinished (a Ray future never says it runs): both ray.cancel-led, the queued one
    # cancelled, the running one left to Ray (a real Ray interrupts it)
    assert len(fake.cancelled) == 2 and second.cancelled()
    release.set()
    assert first.result(timeout=10) is True
    with pytest.raises(RuntimeError, match="after shutdown"):
        executor.submit(pow, 2, 3)
    fake.pool.shutdown()


def test_ray_missing_is_one_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(InputError, match=r"needs Ray: pip install 'tissuesim\[ray\]'"):
        RayExecutor()
    with pytest.raises(InputError, match=r"needs Ray"):
        executor_from_spec("ray", 1)


def test_a_study_on_a_real_local_ray_cluster(bar_scene, tmp_path, monkeypatch):
    """Runs only where Ray is installed (not in CI): ``--executor ray``'s local cluster of one
    CPU runs the study, equal to a thread pool's bit for bit."""
    pytest.importorskip("ray")
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    kwargs = {"fields": ["displacement"], "progress": False}
    executor, resources = executor_from_spec("ray", 1)
    try:
        ray = tissuesim.sweep(bar_scene, VARY, out=tmp_path / "r", executor=executor, **kwargs)
    finally:
        close(resources)
    with ThreadPoolExecutor(1) as pool:
        threads = tissuesim.sweep(bar_scene, VARY, out=tmp_path / "t", executor=pool, **kwargs)
    _same_study(ray, threads, tmp_path / "r", tmp_path / "t")
