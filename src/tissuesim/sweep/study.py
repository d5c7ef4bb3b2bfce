"""A study: a scene, the parameters that vary, their samples, each sample run on an executor,
every result collected into one table. ``sweep`` is the entry (``tissuesim.sweep(...)`` and
``tissuesim sweep``)."""

from __future__ import annotations

import hashlib
import json
import sys
import time
import tomllib
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor, Future, as_completed
from pathlib import Path
from typing import Any

from tissuesim.errors import InputError, OutputError, SceneError
from tissuesim.sweep.runs import RunTask, execute_run, run_id
from tissuesim.sweep.samples import make_samples, parameters

__all__ = ["sweep", "read_scene_data", "STUDY_FILE"]

STUDY_FILE = "study.json"


def read_scene_data(scene: str | Path) -> tuple[dict, Path]:
    """A scene file's tables (parsed TOML) and its path; a shipped example by name too."""
    from tissuesim.scene.examples import example_path, list_examples
    from tissuesim.validate import regular_file, short

    path = Path(scene)
    if not path.exists() and str(scene) in list_examples():
        path = example_path(str(scene))
    if path.suffix.lower() == ".feb":
        raise InputError(
            f"{path}: a study varies a scene's TOML keys: convert the FEBio model first "
            f"(tissuesim convert {path} scene.toml) and sweep the scene"
        )
    if not path.exists():
        raise InputError(
            f"no scene file {short(str(scene))} and no shipped example of that name; "
            f"examples: {', '.join(list_examples())}"
        )
    path = regular_file(path, "scene file")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8")), path
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from None


def sweep(
    scene: str | Path | Callable[..., Any],
    vary: Mapping[str, Any] | Sequence[str],
    *,
    out: str | Path,
    samples: int | None = None,
    sampler: str | None = None,
    seed: int = 0,
    steps: int | None = None,
    executor: Executor | None = None,
    workers: int | None = None,
    fields: Sequence[str] = (),
    every: int | None = None,
    dataset_format: str = "hdf5",
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Run a parameter study of a scene file and return one result dict per run, in the
    order of the samples (docs/guide/sweeps.md).

    scene: a scene file (.toml) or a shipped example's name; or a function of keyword
    arguments that builds the ``Simulation`` (or returns a ``Scene``), varied by its
    arguments' names, ``steps`` then required (a module's function, so that a worker process
    can import it).

    vary: {key path: values} (a list of values, an ``Interval(low, high)`` or a string as on
    the command line: ``"1e3:5e3:5"`` five values, ``"1e3:5e3"`` an interval, ``"1,2,3"``) or
    ["KEY=VALUES", ...]; lists make a grid (their product), intervals are filled by
    ``sampler`` ("sobol", "lhs", "random"; default "sobol" where there is an interval, else
    "grid") with ``samples`` points for the same ``seed``.
    out: the study's directory: ``study.json``, ``runs/<run_id>.json`` (each run's result,
    written by the worker that ran it), ``runs.csv`` and ``runs.parquet``, and with ``fields``
    (("displacement",)) ``fields/`` (``load_dataset``). Runs whose result file is there are not
    run again: a killed study resumes where it stopped.
    executor: any ``concurrent.futures.Executor`` (a Dask ``Client.get_executor()``, ...);
    default a process pool of ``workers`` processes (one per core), one thread each.
    steps: the runs' step count (default the scene's ``[run] steps``).
    every: with ``fields``, save them at the start, every ``every``-th step and the last (a
    leading axis of saved times, and ``times``); default only the end.
    dataset_format: with ``fields``, "hdf5" (``fields/<run_id>.h5``, h5py) or "zarr"
    (``fields/<run_id>.zarr``, zarr 3); ``load_dataset`` reads either.

    A run's result: run_id, index, status ("completed" or "failed"), error (one line),
    wall_time_s, build_time_s (build_scene), setup_time_s (the model set up), solve_time_s (its
    steps' own time), steps, newton_iterations (summed), params
    ({key path: value}), forces ({name: [fx, fy, fz]} at the end, ``Simulation.forces()``)."""
    from tissuesim.sweep.dataset import FIELDS, FORMATS, check_format
    from tissuesim.sweep.results import read_results, table_rows, write_table
    from tissuesim.validate import integer

    builder = None
    if callable(scene):
        builder, data, path = scene, {}, None
        params = parameters(vary, None)
        if steps is None:
            raise InputError("a study of a function needs steps= (it has no [run] table)")
        name = f"{getattr(scene, '__module__', '?')}.{getattr(scene, '__qualname__', scene)}"
    else:
        data, path = read_scene_data(scene)
        params = parameters(vary, data, path.parent)
        name = str(path)
    seed = integer(seed, "seed", low=0)
    if samples is not None:
        samples = integer(samples, "samples", low=1)
    if steps is not None:
        steps = integer(steps, "steps", low=0)
    fields = tuple(fields)
    if every is not None:
        every = integer(every, "every", low=1)
        if not fields:
            raise InputError("--every N saves fields at the saved times: give --fields too")
    for field_name in fields:
        if field_name not in FIELDS:
            raise InputError(f"--fields {field_name!r}: choose from {', '.join(FIELDS)}")
    if fields or dataset_format not in FORMATS:
        check_format(dataset_format)  # a known format, its library importable
    if dataset_format != "hdf5" and not fields:
        raise InputError(
            f"--dataset-format {dataset_format} is the format of the fields: give --fields too"
        )
    if sampler is None:
        sampler = "sobol" if any(p.interval is not None for p in params) else "grid"
    values = make_samples(params, samples, sampler, seed)
    directory = Path(out)
    study = {
        "scene": name,
        "scene_sha256": hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest(),
        "vary": [p.key for p in params],
        "sampler": sampler,
        "samples": samples,
        "seed": seed,
        "steps": steps,
        "fields": list(fields),
        "every": every,
        "runs": values,
    }
    if dataset_format != "hdf5":  # only then: an HDF5 study's study.json is as before
        study["dataset_format"] = dataset_format
    _open_directory(directory, study)
    base = (
        (".", name, getattr(builder, "__name__", "study"))
        if path is None
        else (str(path.parent), name, path.stem)
    )
    extra = {"every": every, "dataset_format": dataset_format}
    tasks = [
        RunTask(i, data, v, *base, steps, str(directory), fields, extra, builder)
        for i, v in enumerate(values)
    ]
    done = {r["index"]: r for r in read_results(directory)}
    todo = [t for t in tasks if t.index not in done]
    results = dict(done)
    try:
        _run_all(todo, executor, workers, results, progress, len(tasks))
    finally:  # the files on disk (runs a worker finished after an interrupt too), then the
        # runs the executor lost, which have none
        results.update({r["index"]: r for r in read_results(directory)})
        rows = [results[i] for i in sorted(results)]
        write_table(directory, table_rows(rows, [p.key for p in params]))
    return [results[t.index] for t in tasks]


def _open_directory(directory: Path, study: dict) -> None:
    """Create the study's directory, or check that the study in it is this one (resume)."""
    from tissuesim.io.atomic import write_json_atomic

    if directory.exists() and not directory.is_dir():
        raise OutputError(f"--out {directory}: a file, not a directory")
    file = directory / STUDY_FILE
    if file.exists():
        before = json.loads(file.read_text(encoding="utf-8"))
        # the scene by its tables (scene_sha256), not its path: a resume from another folder,
        # or of a moved scene, is the same study
        differs = [
            k
            for k in {**before, **study}
            if k != "scene" and before.get(k) != json.loads(json.dumps(study.get(k)))
        ]
        if differs:
            raise OutputError(
                f"--out {directory}: holds another study (its {', '.join(differs)} differ); "
                "give a new --out, or delete the directory to start again"
            )
        return
    if directory.exists() and any(directory.iterdir()):
        raise OutputError(
            f"--out {directory}: not empty and no {STUDY_FILE}; give an empty or new directory"
        )
    (directory / "runs").mkdir(parents=True, exist_ok=True)
    write_json_atomic(file, study)


def _run_all(
    tasks: list[RunTask],
    executor: Executor | None,
    workers: int | None,
    results: dict[int, dict],
    progress: bool,
    total: int,
) -> None:
    """Submit the tasks, collect their results as they finish (a task the executor lost, a
    worker that died, is recorded as failed but not written: a resume runs it again)."""
    if not tasks:
        return
    from tissuesim.sweep.executors import close, default_workers, process_pool

    owned = []
    if executor is None:
        executor = process_pool(min(workers or default_workers(), len(tasks)))
        owned.append(executor)
    bar = _Progress(len(tasks), total - len(tasks), progress)
    futures: dict[Future, RunTask] = {}
    try:
        for task in tasks:
            futures[executor.submit(execute_run, task)] = task
        for future in as_completed(futures):
            task = futures[future]
            try:
                result = future.result()
            except Exception as exc:  # the executor's failure, not the run's
                result = {
                    "run_id": run_id(task.index),
                    "index": task.index,
                    "status": "failed",
                    "error": f"the executor lost the run ({type(exc).__name__}: {exc})",
                    "params": dict(task.values),
                    "forces": {},
                }
            results[task.index] = result
            bar.update(result)
    except BaseException:
        for future in futures:
            future.cancel()
        raise
    finally:
        bar.close()
        close(owned)


class _Progress:
    """Runs done, failed and the time left on stderr: tqdm's bar on a terminal (tqdm
    installed), else a line about every tenth of the study or every 30 s."""

    def __init__(self, total: int, skipped: int, enabled: bool) -> None:
        self.total, self.done, self.failed = total, 0, 0
        self.start = self.last = time.perf_counter()
        self.enabled = enabled
        self.bar = None
        if not enabled:
            return
        if skipped:
            print(f"tissuesim: {skipped} runs already done (resumed)", file=sys.stderr)
        if sys.stderr.isatty():
            try:
                from tqdm import tqdm

                self.bar = tqdm(total=total, file=sys.stderr, unit="run")
            except ImportError:
                pass

    def update(self, result: dict) -> None:
        self.done += 1
        self.failed += result.get("status") != "completed"
        now = time.perf_counter()
        left = (now - self.start) / self.done * (self.total - self.done)
        if self.bar is not None:
            self.bar.set_postfix(failed=self.failed, left=f"{left:.0f}s")
            self.bar.update(1)
        elif self.enabled and (
            self.done % max(1, self.total // 10) == 0
            or self.done == self.total
            or now - self.last >= 30.0
        ):
            self.last = now
            print(
                f"tissuesim: run {self.done}/{self.total} done, {self.failed} failed, "
                f"{now - self.start:.1f} s, about {left:.0f} s left",
                file=sys.stderr,
                flush=True,
            )

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
