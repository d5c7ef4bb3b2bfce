"""Where a study's runs go: any ``concurrent.futures.Executor``. tissuesim has no scheduler of
its own:

- the default: a local ``ProcessPoolExecutor`` with one worker per core (the cores this process
  may use) and one thread per worker, its workers started from a clean interpreter ("spawn")
  with the BLAS / OpenMP / numba thread variables set to 1 before they load NumPy; each worker
  imports tissuesim once and keeps numba's compiled code for all its runs;
- Dask: ``distributed.Client(...).get_executor()`` (``executor_from_spec("dask://HOST:PORT")``
  connects a Client to a running scheduler, ``"dask-local"`` starts a ``LocalCluster`` of worker
  processes with one thread each);
- Ray: ``RayExecutor``, a thin ``Executor`` over Ray tasks (Ray has no ``concurrent.futures``
  executor of its own: ``ray.util.multiprocessing.Pool`` is a ``multiprocessing.Pool``, whose
  ``apply_async`` gives no ``Future``); ``executor_from_spec("ray")`` starts or joins a Ray
  cluster;
- others: anything with ``submit(fn, *args)`` returning a ``concurrent.futures.Future``.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, Future, ProcessPoolExecutor, wait
from concurrent.futures import wait as futures_wait
from typing import Any

from tissuesim.errors import InputError
from tissuesim.sweep.runs import THREAD_VARIABLES, prepare_worker

__all__ = [
    "default_workers", "process_pool", "executor_from_spec", "RayExecutor", "dask_local_cluster",
    "dask_worker_config", "warm_dask_workers",
]  # fmt: skip


def default_workers() -> int:
    """The cores this process may run on (its affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # macOS, Windows
        return max(1, os.cpu_count() or 1)


#: removed from the environment the workers start in: a Dask nanny sets its pre-spawn
#: variables in its own process too, so a LocalCluster with Dask's defaults started earlier in
#: this process leaves glibc's trim threshold here (dask_worker_config says what it costs)
UNSET_VARIABLES = ("MALLOC_TRIM_THRESHOLD_",)


@contextlib.contextmanager
def single_thread_environment() -> Iterator[None]:
    """The thread variables set to 1 (and ``UNSET_VARIABLES`` removed) in this process's
    environment while inside, so that the worker processes started inside inherit that;
    restored afterwards."""
    saved = {name: os.environ.get(name) for name in (*THREAD_VARIABLES, *UNSET_VARIABLES)}
    os.environ.update({name: "1" for name in THREAD_VARIABLES})
    for name in UNSET_VARIABLES:
        os.environ.pop(name, None)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _ready() -> int:
    return os.getpid()


def _init_pool_worker(parent: int) -> None:
    """The default pool's worker initializer: leave when the study's process is gone (killed
    with SIGKILL, a pool's workers would wait for work forever), then ``prepare_worker``."""
    import threading
    import time

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="tissuesim-parent-watch", daemon=True).start()
    prepare_worker()


def process_pool(workers: int | None = None) -> ProcessPoolExecutor:
    """The default executor: ``workers`` processes (default: one per core), one thread each,
    all started now (so the start-up, imports included, is paid before the first run)."""
    import multiprocessing

    from tissuesim.validate import integer

    workers = default_workers() if workers is None else integer(workers, "workers", low=1)
    with single_thread_environment():
        pool = ProcessPoolExecutor(
            workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_init_pool_worker,
            initargs=(os.getpid(),),
        )
        # a pool starts a worker per task submitted while none is idle: start them all here,
        # inside the environment, where each runs prepare_worker once
        wait([pool.submit(_ready) for _ in range(workers)])
    return pool


def _ray() -> Any:
    try:
        import ray
    except ImportError:
        raise InputError("the Ray executor needs Ray: pip install 'tissuesim[ray]'") from None
    return ray


def _call(fn: Callable[..., Any], args: tuple, kwargs: dict) -> Any:
    """What a Ray task runs: ``fn(*args, **kwargs)`` (a module's function: Ray sends it to its
    workers by reference)."""
    return fn(*args, **kwargs)


class RayExecutor(Executor):
    """A ``concurrent.futures.Executor`` whose ``submit`` starts a Ray task (``ray.remote``
    with ``num_cpus``, 1 by default, and Ray's other task ``options``; its ``runtime_env``
    gets the thread variables at 1, as the pool's workers, unless given) and returns its
    ``ObjectRef.future()``. Ray reuses its worker processes, so a study's per-worker start-up
    (``prepare_worker``, the caches) is paid once per Ray worker. Ray starts a local cluster at
    the first task unless ``ray.init(...)`` was called (``ray.init(address="auto")`` joins a
    running one). ``shutdown(cancel_futures=True)`` cancels (``ray.cancel``) every task not
    finished, running ones too: a Ray future never says it runs, and its own ``cancel`` cannot
    stop a Ray task; a run stopped so leaves no partial file (its files are written
    atomically). ``ray``: the module, or a stand-in (tests)."""

    def __init__(self, num_cpus: float = 1, ray: Any = None, **options: Any) -> None:
        self._ray = _ray() if ray is None else ray
        # the workers start with one thread each, as the pool's (the BLAS, MKL and the
        # contact library read these when they load, before a run's prepare_worker)
        env = dict(options.pop("runtime_env", None) or {})
        threads = {name: "1" for name in THREAD_VARIABLES}
        env["env_vars"] = {**threads, **dict(env.get("env_vars") or {})}
        self._remote = self._ray.remote(num_cpus=num_cpus, runtime_env=env, **options)(_call)
        self._refs: dict[Any, Future] = {}
        self._lock = threading.Lock()
        self._closed = False

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        with self._lock:
            if self._closed:
                raise RuntimeError("cannot submit to a RayExecutor after shutdown")
            ref = self._remote.remote(fn, args, kwargs)
            future = ref.future()
            self._refs[ref] = future
        future.add_done_callback(lambda _: self._forget(ref))
        return future

    def _forget(self, ref: Any) -> None:
        with self._lock:
            self._refs.pop(ref, None)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        with self._lock:
            self._closed = True
            pending = dict(self._refs)
        if cancel_futures:
            for ref, future in pending.items():
                if not future.done():
                    with contextlib.suppress(Exception):  # finished meanwhile, or gone
                        self._ray.cancel(ref)
                    future.cancel()
        if wait:
            futures_wait(list(pending.values()))


def executor_from_spec(spec: str | None, workers: int | None) -> tuple[Executor, list]:
    """The executor the command line's ``--executor`` names ("local", "dask-local",
    "dask://HOST:PORT", "tcp://HOST:PORT", "ray") and what to close after the study (pool,
    client, cluster, Ray)."""
    if spec is None or spec == "local":
        pool = process_pool(workers)
        return pool, [pool]
    if spec == "ray":
        ray = _ray()
        owned: list = []
        if not ray.is_initialized():
            # RAY_ADDRESS set: joins that cluster (--workers is then the cluster's own);
            # else starts a local one of --workers CPUs (default one per core)
            if os.environ.get("RAY_ADDRESS"):
                ray.init()
            else:
                ray.init(num_cpus=workers or default_workers(), include_dashboard=False)
            owned.append(_RayShutdown(ray))
        executor = RayExecutor(ray=ray)
        return executor, [executor, *owned]
    if spec == "dask-local" or spec.startswith(("dask://", "tcp://", "tls://")):
        try:
            from distributed import Client
        except ImportError:
            raise InputError(
                f"--executor {spec}: needs Dask's distributed: pip install 'tissuesim[sweep]'"
            ) from None
        if spec == "dask-local":
            cluster = dask_local_cluster(workers)
            client = Client(cluster)
            warm_dask_workers(client)
            return client.get_executor(), [client, cluster]
        address = "tcp://" + spec.removeprefix("dask://") if spec.startswith("dask://") else spec
        try:
            client = Client(address)  # waits Dask's distributed.comm.timeouts.connect
        except OSError as exc:
            raise InputError(
                f"--executor {spec}: cannot reach a Dask scheduler at {address} ({exc}); start "
                "one (dask scheduler, dask-jobqueue) or check HOST:PORT"
            ) from None
        warm_dask_workers(client)
        return client.get_executor(), [client]
    raise InputError(
        f"--executor {spec!r}: choose local (a process pool on this machine), dask-local (a "
        "Dask LocalCluster), dask://HOST:PORT (a running Dask scheduler) or ray (a local Ray "
        "cluster, or the one RAY_ADDRESS names)"
    )


def dask_worker_config() -> dict[str, Any]:
    """Dask settings for the workers of the ``LocalCluster`` tissuesim starts, against Dask's
    defaults (``benchmarks/sweep.py`` measures both): the thread variables at 1 (NUMBA's and
    the contact library's too); glibc's ``MALLOC_TRIM_THRESHOLD_`` unset (Dask's nanny sets
    64 KiB, and setting it at all switches off glibc's dynamic mmap threshold, mallopt(3), so
    every array of 128 KiB or more is mapped afresh and faulted in page by page); the event
    loop's tick and the memory and system monitors every second instead of every 20, 100 and
    500 ms; Dask's profiler, which samples the running task's stack every 10 ms, off. Each of
    these takes the GIL or CPU from the run's thread."""
    import dask

    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}) or {})
    # None unsets a variable (distributed's nanny); glibc's dynamic thresholds are its default
    environ["MALLOC_TRIM_THRESHOLD_"] = None
    environ.update({name: 1 for name in THREAD_VARIABLES})
    return {
        "distributed.nanny.pre-spawn-environ": environ,
        "distributed.admin.tick.interval": "1s",
        "distributed.admin.system-monitor.interval": "1s",
        "distributed.worker.memory.monitor-interval": "1s",
        # Dask's statistical profiler samples the running task's stack every 10 ms
        "distributed.worker.profile.enabled": False,
    }


def dask_local_cluster(workers: int | None = None, **options: Any) -> Any:
    """A Dask ``LocalCluster`` of ``workers`` worker processes (default: one per core), one
    thread each, started with ``dask_worker_config()`` (``options``: LocalCluster's own)."""
    import dask
    from distributed import LocalCluster

    from tissuesim.validate import integer

    workers = default_workers() if workers is None else integer(workers, "workers", low=1)
    settings = {"n_workers": workers, "threads_per_worker": 1, "processes": True,
                "dashboard_address": None, **options}  # fmt: skip
    # the nanny reads the configuration when it is made: the workers keep it
    with dask.config.set(dask_worker_config()), single_thread_environment():
        return LocalCluster(**settings)


def warm_dask_workers(client: Any) -> None:
    """``prepare_worker`` on every worker the client's scheduler has now (imports, numba's
    compilation, a warm-up step), so that a study's first runs do not pay it; workers that
    join later prepare at their first run."""
    client.run(prepare_worker)


class _RayShutdown:
    """``close`` of what ``executor_from_spec("ray")`` started: ``ray.shutdown()``."""

    def __init__(self, ray: Any) -> None:
        self._ray = ray

    def close(self) -> None:
        self._ray.shutdown()


def close(resources: list) -> None:
    """Shut down what ``executor_from_spec`` opened, in its order (client, then cluster)."""
    for item in resources:
        if isinstance(item, Executor):
            item.shutdown(wait=True, cancel_futures=True)
        else:
            item.close()
