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

__all__ = ["default_workers", "process_pool", "executor_from_spec", "RayExecutor"]


def default_workers() -> int:
    """The cores this process may run on (its affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # macOS, Windows
        return max(1, os.cpu_count() or 1)


@contextlib.contextmanager
def single_thread_environment() -> Iterator[None]:
    """The thread variables set to 1 in this process's environment while inside, so that the
    worker processes started inside inherit them; restored afterwards."""
    saved = {name: os.environ.get(name) for name in THREAD_VARIABLES}
    os.environ.update({name: "1" for name in THREAD_VARIABLES})
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
        raise InputError(
            "the Ray executor needs Ray: pip install ray (not in tissuesim's extras)"
        ) from None
    return ray


def _call(fn: Callable[..., Any], args: tuple, kwargs: dict) -> Any:
    """What a Ray task runs: ``fn(*args, **kwargs)`` (a module's function: Ray sends it to its
    workers by reference)."""
    return fn(*args, **kwargs)


class RayExecutor(Executor):
    """A ``concurrent.futures.Executor`` whose ``submit`` starts a Ray task (``ray.remote``
    with ``num_cpus``, 1 by default, and Ray's other task ``options``) and returns its
    ``ObjectRef.future()``. Ray reuses its worker processes, so a study's per-worker start-up
    (``prepare_worker``, the caches) is paid once per Ray worker. Ray starts a local cluster at
    the first task unless ``ray.init(...)`` was called (``ray.init(address="auto")`` joins a
    running one). ``shutdown(cancel_futures=True)`` cancels (``ray.cancel``) every task not
    finished, running ones too: a Ray future never says it runs, and its own ``cancel`` cannot
    stop a Ray task; a run stopped so leaves no partial file (its files are written
    atomically). ``ray``: the module, or a stand-in (tests)."""

    def __init__(self, num_cpus: float = 1, ray: Any = None, **options: Any) -> None:
        self._ray = _ray() if ray is None else ray
        self._remote = self._ray.remote(num_cpus=num_cpus, **options)(_call)
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
            from distributed import Client, LocalCluster
        except ImportError:
            raise InputError(
                f"--executor {spec}: needs Dask's distributed: pip install 'tissuesim[sweep]'"
            ) from None
        if spec == "dask-local":
            with single_thread_environment():
                cluster = LocalCluster(
                    n_workers=workers or default_workers(),
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                )
            client = Client(cluster)
            return client.get_executor(), [client, cluster]
        address = "tcp://" + spec.removeprefix("dask://") if spec.startswith("dask://") else spec
        try:
            client = Client(address)  # waits Dask's distributed.comm.timeouts.connect
        except OSError as exc:
            raise InputError(
                f"--executor {spec}: cannot reach a Dask scheduler at {address} ({exc}); start "
                "one (dask scheduler, dask-jobqueue) or check HOST:PORT"
            ) from None
        return client.get_executor(), [client]
    raise InputError(
        f"--executor {spec!r}: choose local (a process pool on this machine), dask-local (a "
        "Dask LocalCluster), dask://HOST:PORT (a running Dask scheduler) or ray (a local Ray "
        "cluster, or the one RAY_ADDRESS names)"
    )


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
