"""One run of a study, as a worker runs it: the scene's data with the sample's values put in,
built by ``build_scene``, stepped to its ``[run]`` steps without output or pictures; its result
a plain dict, written atomically to ``runs/<run_id>.json`` (and, where asked, its final fields
to ``fields/<run_id>.h5``) by the worker itself. A run whose result file exists is not run again
(a resumed study, or an executor that ran a task twice). Its meshes come through the worker's
mesh cache (cache.py): a mesh file or surface is read once per worker."""

from __future__ import annotations

import copy
import json
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["RunTask", "execute_run", "prepare_worker", "THREAD_VARIABLES", "run_id"]

#: set to 1 in every worker: one thread per worker, the workers are the parallelism
THREAD_VARIABLES = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "BLIS_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "NUMBA_NUM_THREADS",
    # ipctk's TBB threads (contact/model.py): also bit for bit reproducible contact runs
    "TISSUESIM_CONTACT_THREADS",
)
_prepared = False


def run_id(index: int) -> str:
    """The run's name in the output: r00000, r00001, ..."""
    return f"r{index:05d}"


@dataclass(frozen=True)
class RunTask:
    """What a worker needs for one run (plain data: it travels to a worker process)."""

    index: int
    data: dict  # the scene's tables, this run's values not yet put in
    values: dict[str, Any]  # key path -> value
    base_dir: str  # the scene's folder: mesh files are relative to it
    source: str
    name: str
    steps: int | None
    out: str | None  # the study's directory; None: nothing written
    fields: tuple[str, ...] = ()
    extra: dict[str, Any] = field(default_factory=dict)
    #: a study of a function: ``builder(**values)`` returns the Simulation (or a Scene) to
    #: run ``steps`` steps; importable by name (a module's function) to reach a worker
    builder: Callable[..., Any] | None = None

    @property
    def run_id(self) -> str:
        return run_id(self.index)


def prepare_worker() -> None:
    """Once per process: one thread (BLAS, OpenMP, numba), tissuesim's notes silenced, and a
    warm-up step (imports and first calls). The default pool also sets the thread variables
    before its workers start (executors.py), since a BLAS reads them when it loads; here they
    reach what loads later (numba) and, through threadpoolctl where installed, a BLAS already
    loaded. In the caller's own process (a ThreadPoolExecutor) this limits its threads too."""
    global _prepared
    if _prepared:
        return
    for name in THREAD_VARIABLES:
        os.environ[name] = "1"
    try:
        from threadpoolctl import threadpool_limits

        threadpool_limits(1)
    except ImportError:
        pass
    import sys

    if "numba" in sys.modules:
        import numba

        numba.set_num_threads(1)
    from tissuesim.io.progress import set_quiet
    from tissuesim.sweep import cache

    cache.install()  # the runs' mesh files and surfaces read once per worker (cache.py)
    set_quiet(True)  # a worker's notes (numba compiling) would interleave on the terminal
    _prepared = True
    _warm_up()


#: a one-tetrahedron-box quasistatic step: the imports and first calls of the solve path
#: (about 0.4 s on one core, once per worker; it halved a small scene's first run)
_WARM_UP = {
    "mesh": {"generator": "box", "lower": [0, 0, 0], "upper": [1, 1, 1], "divisions": [1, 1, 1]},
    "material": {"model": "neo_hookean", "youngs_modulus": 1.0, "poisson_ratio": 0.3},
    "simulation": {"integrator": "quasistatic", "time_step": 1.0},
    "dirichlet": [
        {"vertices": {"on_plane": {"axis": 0, "value": 0.0}}},
        {"vertices": {"on_plane": {"axis": 0, "value": 1.0}}, "displacement": ["0.1*t", "0", "0"]},
    ],
}


def _warm_up() -> None:
    from tissuesim.scene.loader import build_scene

    try:
        sim = build_scene(copy.deepcopy(_WARM_UP), source="<warm-up>").simulation
        sim.run(1, progress=False, render=False)
    except Exception:  # only a warm-up: the runs report their own errors
        pass


def execute_run(task: RunTask) -> dict[str, Any]:
    """Run one sample and return its result (the keys: ``tissuesim.sweep.sweep``); never
    raises for a failed run: its status is "failed" and ``error`` the one-line reason."""
    prepare_worker()
    out = Path(task.out) if task.out is not None else None
    if out is not None:
        done = out / "runs" / f"{task.run_id}.json"
        if done.exists():
            return json.loads(done.read_text(encoding="utf-8"))
    from tissuesim.errors import InputError, RunError
    from tissuesim.sweep import cache
    from tissuesim.sweep.samples import coerce

    start = time.perf_counter()
    result: dict[str, Any] = {
        "run_id": task.run_id,
        "index": task.index,
        "status": "completed",
        "error": "",
        "wall_time_s": 0.0,
        "build_time_s": 0.0,
        "setup_time_s": 0.0,
        "solve_time_s": 0.0,
        "steps": 0,
        "newton_iterations": 0,
        "params": dict(task.values),
        "forces": {},
    }
    sim, frames = None, []
    try:
        with cache.enabled():
            sim, run_table = _build(task, coerce)
        result["build_time_s"] = time.perf_counter() - start
        steps = task.steps
        if steps is None:
            schedule = sim.schedule
            steps = run_table.get("steps", 100 if schedule is None else schedule.steps)
        history, frames = _step(sim, steps, task, result)
        result["steps"] = len(history)
        result["newton_iterations"] = int(sum(r.newton_iterations for r in history))
        result["solve_time_s"] = float(sum(r.wall_time_s for r in history))
        result["forces"] = {k: [float(c) for c in v] for k, v in sim.forces().items()}
    except (InputError, RunError) as exc:
        result.update(status="failed", error=_one_line(exc))
    except Exception as exc:  # a bug: recorded, the study goes on
        result.update(status="failed", error=_one_line(exc, internal=True))
    if sim is not None:
        result["steps"] = result["steps"] or len(sim.history)
    result["wall_time_s"] = time.perf_counter() - start
    if out is not None:
        if task.fields and result["status"] == "completed":
            from tissuesim.sweep.dataset import write_run_fields

            write_run_fields(out, task, sim, result, frames)
        from tissuesim.io.atomic import write_json_atomic

        write_json_atomic(out / "runs" / f"{task.run_id}.json", result, indent=None)
    return result


def _build(task: RunTask, coerce: Callable[[Any, Any], Any]) -> tuple[Any, dict]:
    """The run's Simulation and its scene's ``[run]`` table: the builder's, or the scene's
    tables with the sample's values put in, built."""
    if task.builder is not None:
        built = task.builder(**task.values)
        scene = built if hasattr(built, "simulation") else None  # a Scene, or a Simulation
        sim = built if scene is None else scene.simulation
        return sim, {} if scene is None else scene.run
    from tissuesim.scene.loader import build_scene
    from tissuesim.sweep.keypaths import parse_key_path

    data = copy.deepcopy(task.data)
    for key, value in task.values.items():
        path = parse_key_path(key)
        path.set(data, coerce(value, path.get(data)))
    scene = build_scene(data, base_dir=Path(task.base_dir), source=task.source, name=task.name)
    return scene.simulation, scene.run


def _step(sim: Any, steps: int, task: RunTask, result: dict) -> tuple[list, list]:
    """``steps`` steps as ``Simulation.run`` takes them without output (the same ``step``
    calls: the same numbers), the set-up timed apart; with ``task.extra["every"]`` the fields
    at every ``every``-th step and the last: [(time, {body: {field: array}})]."""
    from tissuesim.sweep.dataset import frame_fields
    from tissuesim.time.grid import check_time_resolution
    from tissuesim.validate import integer

    steps = integer(steps, "steps", low=0)
    start = time.perf_counter()
    sim.build()
    result["setup_time_s"] = time.perf_counter() - start
    check_time_resolution(sim.time + steps * sim.time_step, sim.time_step, "the end time")
    every = task.extra.get("every") if task.fields else None
    history, frames = [], []
    if every:
        frames.append((sim.time, frame_fields(sim, task.fields)))
    for k in range(steps):
        history.append(sim.step())
        last = k + 1 == steps or sim.finished
        if every and (last or (k + 1) % every == 0):
            frames.append((sim.time, frame_fields(sim, task.fields)))
        if last:
            break
    return history, frames


def _one_line(exc: BaseException, internal: bool = False) -> str:
    text = f"{type(exc).__name__}: {exc}" if internal else str(exc)
    text = " ".join(text.split())
    return text if len(text) <= 500 else text[:480] + f" ... ({len(text)} characters)"
