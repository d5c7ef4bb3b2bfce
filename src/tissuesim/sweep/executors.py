"""Where a study's runs go: any ``concurrent.futures.Executor``. tissuesim has no scheduler of
its own:

- the default: a local ``ProcessPoolExecutor`` with one worker per core (the cores this process
  may use) and one thread per worker, its workers started from a clean interpreter ("spawn")
  with the BLAS / OpenMP / numba thread variables set to 1 before they load NumPy; each worker
  imports tissuesim once and keeps numba's compiled code for all its runs;
- Dask: ``distributed.Client(...).get_executor()`` (``executor_from_spec("dask://HOST:PORT")``
  connects a Client to a running scheduler, ``"dask-local"`` starts a ``LocalCluster`` of worker
  processes with one thread each);
- Ray and others: anything with ``submit(fn, *args)`` returning a ``concurrent.futures.Future``
  (docs/guide/sweeps.md has a Ray adapter).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor, wait

from tissuesim.errors import InputError
from tissuesim.sweep.runs import THREAD_VARIABLES, prepare_worker

__all__ = ["default_workers", "process_pool", "executor_from_spec"]


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


def executor_from_spec(spec: str | None, workers: int | None) -> tuple[Executor, list]:
    """The executor the command line's ``--executor`` names ("local", "dask-local",
    "dask://HOST:PORT", "tcp://HOST:PORT") and what to close after the study (pool, client,
    cluster)."""
    if spec is None or spec == "local":
        pool = process_pool(workers)
        return pool, [pool]
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
        "Dask LocalCluster) or dask://HOST:PORT (a running Dask scheduler)"
    )


def close(resources: list) -> None:
    """Shut down what ``executor_from_spec`` opened, in its order (client, then cluster)."""
    for item in resources:
        if isinstance(item, Executor):
            item.shutdown(wait=True, cancel_futures=True)
        else:
            item.close()
