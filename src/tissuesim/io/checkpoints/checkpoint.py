"""Checkpoints: a simulation's whole dynamic state in one file, so a run continues where it
stopped, bit-identical to a run that never stopped.

What is kept (``capture``): the state (time, configuration, velocity), Newton's last gradient
(the reactions), the step history, the contact model's state between steps (the obstacles'
lagged positions, the adaptive barrier stiffness and its history), the sphere probes' touch
points, live-driven obstacle motions, the history of viscoelastic materials
(``material.<body>.H`` and ``.Se``), and the linear solver's state: the matrix the kept
factor was made from (``solve/reuse.py`` uses it as CG preconditioner in later steps), SuperLU's
fill-reducing order and the matrix of a lagged AMG hierarchy, so that on load the factor is made
again from the same matrix with the same ordering (a fresh factor takes other iterates). The
set-up (meshes, materials, supports, motions) is not kept: it is code and data the user
already has. A checkpoint is loaded into a simulation set up the same way, checked by a
``fingerprint`` (integrator, Newton options, each body's mesh / material / density, contact and
obstacles; the command line adds the scene file's hash; ``io/checkpoints/fingerprint.py``).

Cut and torn bodies (issue 41): their current cut mesh and cuts, the vertices their supports
and graspers hold, the blades' progress and the cracks (``io/checkpoints/cuts.py``); on load
each cut body's model, the system, the contact surfaces and the linear solver are made again
on the cut mesh, so a run killed mid-cut resumes bit-identically too.

Files: ``Simulation.save(path)`` writes one ``.npz`` (history included). A run with output keeps
``checkpoint.npz`` in its directory, rewritten atomically after every frame, and the history
in ``checkpoint_history.jsonl``, appended (one JSON line per step) and fsynced before the
``.npz`` that counts its lines is replaced: a kill at any moment leaves a checkpoint consistent
with itself, and with frames up to those it lists (later frames are dropped on resume).

Format: ``FORMAT`` 2 since checkpoints keep cuts; format 1 (before) is read where nothing cuts
or tears (it was never written where something did), any other is refused in one line.

The connective tissue (issue 41): its dissection and its attachments' cells
(``io/checkpoints/tissue.py``), its frame model made again from them on load.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from tissuesim.errors import InputError
from tissuesim.io.atomic import atomic_output, write_text_atomic
from tissuesim.io.checkpoints.cuts import capture_cuts, restore_cuts
from tissuesim.io.checkpoints.fingerprint import FIX as _FIX
from tissuesim.io.checkpoints.fingerprint import check_fingerprint as _check_fingerprint
from tissuesim.io.checkpoints.fingerprint import fingerprint, scene_hash
from tissuesim.io.checkpoints.predictor import capture_predictor, restore_predictor
from tissuesim.io.checkpoints.tissue import capture_tissue, restore_tissue
from tissuesim.io.interrupts import deferred_interrupts

__all__ = [
    "CHECKPOINT",
    "HISTORY",
    "FORMAT",
    "fingerprint",
    "scene_hash",
    "save_simulation",
    "load_simulation",
    "RunCheckpoint",
]

CHECKPOINT = "checkpoint.npz"
HISTORY = "checkpoint_history.jsonl"
#: the checkpoint's layout: 2 keeps cut and torn bodies (1: before, never written for them)
FORMAT = 2
#: the layouts this version reads (``restore_cuts`` refuses a format 1 checkpoint for a run
#: that cuts or tears in one line)
READS = (1, 2)


# -- history: one JSON line per StepRecord ----------------------------------------------------
def _plain(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"cannot keep {type(obj).__name__} in a checkpoint")


def encode_record(record) -> str:
    """One history record as a JSON line (non-finite floats kept: NaN, Infinity)."""
    return json.dumps(asdict(record), default=_plain, allow_nan=True)


def decode_record(line: str):
    from tissuesim.records import StepRecord

    return StepRecord(**json.loads(line))


# -- the linear solvers' state ----------------------------------------------------------------
class _Shape:
    """Stands for a SuperLU factor where only its shape is read (before the next factorize)."""

    def __init__(self, shape) -> None:
        self.shape = tuple(int(n) for n in shape)


def _put_matrix(arrays: dict, key: str, A: sp.csr_matrix) -> None:
    arrays[f"{key}.data"], arrays[f"{key}.indices"] = A.data, A.indices
    arrays[f"{key}.indptr"], arrays[f"{key}.shape"] = A.indptr, np.asarray(A.shape)


def _get_matrix(arrays, key: str) -> sp.csr_matrix:
    shape = tuple(int(n) for n in arrays[f"{key}.shape"])
    parts = (arrays[f"{key}.data"], arrays[f"{key}.indices"], arrays[f"{key}.indptr"])
    return sp.csr_matrix(tuple(np.array(p) for p in parts), shape=shape)


def _solver_state(solver, key: str, arrays: dict) -> dict | None:
    """The state of ``solver`` between steps (descriptor; arrays under ``key``)."""
    from tissuesim.solve.linear import CGSolver, SuperLUSolver
    from tissuesim.solve.reuse import ReusedFactorSolver

    if solver is None:
        return None
    meta: dict[str, Any] = {"type": type(solver).__name__, "name": solver.name}
    if isinstance(solver, ReusedFactorSolver):
        A = getattr(solver, "factored_matrix", None) if solver._factored else None
        meta["factored"] = A is not None
        if A is not None:
            _put_matrix(arrays, f"{key}.factored", A)
            # the factor's columns kept for the contact update (solve/reuse.py): solved again
            # in other batches they could differ in the last bit
            meta["holds_update"] = bool(solver.factor_holds_update)
            meta["excess"] = int(solver.excess)  # when the next factor is taken
            if solver.columns.slot:
                order = sorted(solver.columns.slot, key=solver.columns.slot.get)
                arrays[f"{key}.column_dofs"] = np.asarray(order, dtype=np.int64)
                arrays[f"{key}.columns"] = solver.columns.X
        meta["direct"] = _solver_state(solver.direct, f"{key}.direct", arrays)
    elif isinstance(solver, SuperLUSolver) and solver._lu is not None:
        meta["ordered"] = solver._perm is not None
        if solver._perm is not None:
            arrays[f"{key}.perm"] = solver._perm
            meta["analysed_nnz"] = int(solver._analysed_nnz)
            meta["permuted"] = bool(solver._permuted)
            meta["shape"] = list(solver._lu.shape)
    elif isinstance(solver, CGSolver) and getattr(solver, "amg_matrix", None) is not None:
        _put_matrix(arrays, f"{key}.amg", solver.amg_matrix)
        meta["reference_iterations"] = solver._reference_iterations
    return meta


def _restore_solver(solver, meta: dict, arrays, key: str, A: sp.csr_matrix | None = None) -> None:
    """Make ``solver`` (fresh, of the type saved) what it was; ``A``: refactorise this matrix."""
    from tissuesim.solve.linear import CGSolver, SuperLUSolver
    from tissuesim.solve.reuse import LinearStats, ReusedFactorSolver

    if isinstance(solver, ReusedFactorSolver):
        A = _get_matrix(arrays, f"{key}.factored") if meta["factored"] else None
        _restore_solver(solver.direct, meta["direct"], arrays, f"{key}.direct", A)
        if A is not None:
            solver._A = solver.factored_matrix = A
            solver._factored, solver._fresh = True, False
            solver.factor_holds_update = bool(meta.get("holds_update", False))
            solver.excess = int(meta.get("excess", 0))
            if f"{key}.column_dofs" in arrays:
                dofs = np.array(arrays[f"{key}.column_dofs"]).tolist()
                solver.columns.X = np.array(arrays[f"{key}.columns"], order="F")
                solver.columns.slot = {int(j): k for k, j in enumerate(dofs)}
        solver.stats = LinearStats()
    elif isinstance(solver, SuperLUSolver):
        if meta.get("ordered"):
            solver._perm = np.array(arrays[f"{key}.perm"])
            solver._analysed_nnz = meta["analysed_nnz"]
            solver._permuted = meta["permuted"]
            solver._lu = _Shape(meta["shape"])
            if A is not None:
                if not meta["permuted"]:  # the factor that made the order: make both again
                    solver._perm = None
                solver._factorize(A)
        elif A is not None:
            solver.factorize(A)
    elif isinstance(solver, CGSolver):
        if f"{key}.amg.data" in arrays:
            solver._A = _get_matrix(arrays, f"{key}.amg")
            solver._build_amg()
            solver._reference_iterations = meta["reference_iterations"]
        solver.stats = type(solver.stats)()
    elif A is not None:  # PARDISO, CHOLMOD: the analysis depends on the pattern only
        solver.factorize(A)


def _same_solver(solver, meta: dict | None) -> bool:
    if meta is None or solver is None:
        return meta is None and solver is None
    if type(solver).__name__ != meta["type"] or solver.name != meta["name"]:
        return False
    direct = getattr(solver, "direct", None)
    return direct is None or _same_solver(direct, meta.get("direct"))


# -- capture and restore ----------------------------------------------------------------------
def _stateful_materials(sim) -> list[tuple[str, Any]]:
    """(body name, material) of the FEM bodies whose law keeps a history per point."""
    s = sim.system
    return [
        (name, s.bodies[j].material)
        for j, name in enumerate(s.names)
        if hasattr(getattr(s.bodies[j], "material", None), "state_arrays")
    ]


def capture(sim) -> tuple[dict, dict[str, np.ndarray]]:
    """(meta, arrays): everything of ``sim`` that changes from step to step, history aside."""
    from tissuesim.contact.obstacles import DrivenMotion

    s, state = sim.system, sim.state
    arrays: dict[str, np.ndarray] = {"x": state.x, "v": state.v, "time": np.float64(state.time)}
    if state.a is not None:  # Newmark's accelerations
        arrays["a"] = state.a
    meta: dict[str, Any] = {"time": float(state.time), "steps": len(sim.history)}
    if sim._last_gradient is not None:
        arrays["last_gradient"] = sim._last_gradient
    meta["solver"] = _solver_state(sim._solver, "solver", arrays)
    for name, material in _stateful_materials(sim):  # a viscoelastic law's history
        for key, value in material.state_arrays().items():
            arrays[f"material.{name}.{key}"] = value
    contact = s.contact
    if contact is not None:
        meta["kappa"] = contact.kappa
        meta["adaptive"] = None if contact.adaptive is None else asdict(contact.adaptive)
        if contact.obstacle_state is not None:
            arrays["contact.obstacle_state"] = contact.obstacle_state
        meta["predictor"] = capture_predictor(contact, sim._solver, arrays)
        cached = contact.augmented_cache.get("solver")
        if cached is not None:
            meta["augmented_solver"] = [cached[0], _solver_state(cached[1], "augmented", arrays)]
    tracker = sim._indentation
    meta["indentation"] = {"free": {}, "touch": {}}
    for kind, table in (("free", tracker._free), ("touch", tracker._touch)):
        for name, items in table.items():
            meta["indentation"][kind][name] = len(items)
            for i, item in enumerate(items):
                arrays[f"indentation.{kind}.{name}.{i}"] = np.asarray(item)
    driven = {}
    for ob in sim.obstacles:
        for which in ("translation", "rotation"):
            motion = getattr(ob, which)
            if isinstance(motion, DrivenMotion):
                driven[f"{ob.name}.{which}"] = [motion.start_time, motion.end_time]
                arrays[f"driven.{ob.name}.{which}.start"] = motion.start
                arrays[f"driven.{ob.name}.{which}.target"] = motion.target
    meta["driven"] = driven
    meta["cuts"] = capture_cuts(sim, arrays)  # cut and torn bodies, blades, cracks
    meta["tissue"] = capture_tissue(sim, arrays)  # its dissection, attachments' cells
    c = getattr(sim, "_controller", None)  # adaptive steps: the next step's length, ...
    meta["stepper"] = None if c is None else {"start": c.start, "end": c.end, **c.state()}
    return meta, arrays


def restore(sim, meta: dict, arrays, history: list, path: Path) -> None:
    """Put a captured state into ``sim`` (set up the same way, not stepped yet)."""
    import warnings

    from tissuesim.contact.barrier.stiffness import AdaptiveStiffness
    from tissuesim.contact.obstacles import DrivenMotion
    from tissuesim.time.state import State

    sim.history[:] = history
    if history:  # graspers let go at the last step's start (as step() did), then the system
        start = history[-2].time if len(history) >= 2 else sim.start_time
        for body in sim.bodies.values():
            if body.kind == "fem":
                body.release_graspers(start + 1e-9 * sim.time_step)
    restore_cuts(sim, meta.get("cuts"), arrays, path, _FIX)  # before the system is built
    restore_tissue(sim, meta.get("tissue"), arrays, path, _FIX)  # on the cut organs
    s = sim.system
    x, v = np.array(arrays["x"]), np.array(arrays["v"])
    if x.shape != sim.state.x.shape or v.shape != sim.state.v.shape:
        raise InputError(f"{path} holds a state of another size; {_FIX}")
    a = np.array(arrays["a"]) if "a" in arrays else None
    sim._state = State(float(arrays["time"]), x, v, a)
    sim._last_gradient = np.array(arrays["last_gradient"]) if "last_gradient" in arrays else None
    sim._controller, sim._pending_stepper = None, meta.get("stepper")  # adaptive steps
    for name, material in _stateful_materials(sim):
        keys = [k for k in arrays if k.startswith(f"material.{name}.")]
        if not keys:
            raise InputError(f"{path} holds no material history for body {name!r}; {_FIX}")
        material.set_state_arrays({k.rsplit(".", 1)[1]: np.array(arrays[k]) for k in keys})
    if meta["solver"] is not None and not sim.explicit:
        solver = sim._linear_solver()
        if _same_solver(solver, meta["solver"]):
            _restore_solver(solver, meta["solver"], arrays, "solver")
        else:
            warnings.warn(
                f"{path} was written with the linear solver {meta['solver']['name']}, this run "
                f"uses {solver.name}: it continues, but not bit-identical to an uninterrupted "
                "run (set newton linear_solver to pin one)",
                UserWarning,
                stacklevel=3,
            )
    contact = s.contact
    if contact is not None:
        contact.time = sim._state.time  # as a step leaves it (and a rebuild carries it over)
        contact.set_stiffness(meta["kappa"])
        if meta["adaptive"] is not None and contact.adaptive is not None:
            contact.adaptive = AdaptiveStiffness(**meta["adaptive"])
        if "contact.obstacle_state" in arrays:
            contact.obstacle_state = np.array(arrays["contact.obstacle_state"])
        restore_predictor(contact, sim._solver, meta.get("predictor"), arrays)
        if meta.get("augmented_solver"):
            from tissuesim.solve.linear import make_linear_solver

            n, saved = meta["augmented_solver"]
            made, _ = make_linear_solver(sim.newton.linear_solver, n, 3, None)
            if _same_solver(made, saved):
                _restore_solver(made, saved, arrays, "augmented")
                contact.augmented_cache["solver"] = (n, made)
    tracker = sim._indentation
    for kind, table in (("free", tracker._free), ("touch", tracker._touch)):
        for name, count in meta["indentation"][kind].items():
            items = [np.array(arrays[f"indentation.{kind}.{name}.{i}"]) for i in range(count)]
            table[name] = tuple(float(a) if a.ndim == 0 else a for a in items)
    for key, (t0, t1) in meta["driven"].items():
        name, which = key.rsplit(".", 1)
        k, ob = next((k, o) for k, o in enumerate(sim.obstacles) if o.name == name)
        motion = getattr(ob, which)
        if not isinstance(motion, DrivenMotion):  # driven during the run, not at set-up
            motion = DrivenMotion(np.zeros(3))
            sim.obstacles[k] = ob = replace(ob, **{which: motion})
            if s.contact is not None:
                s.contact.obstacles[k] = ob
        motion.start = np.array(arrays[f"driven.{key}.start"])
        motion.target = np.array(arrays[f"driven.{key}.target"])
        motion.start_time, motion.end_time = t0, t1


# -- files ----------------------------------------------------------------------------------
def _write_npz(path: Path, meta: dict, arrays: dict) -> None:
    text = json.dumps(meta, allow_nan=True, default=_plain)
    # a Ctrl-C waits for the file: raised inside savez, the zip's own cleanup replaced it by a
    # ValueError ("an open writing handle"), and the run ended as an internal error
    with deferred_interrupts(), atomic_output(path) as tmp, open(tmp, "wb") as f:
        np.savez(f, __meta__=np.array(text), **arrays)
        f.flush()


def _read_npz(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    if not path.is_file():
        raise InputError(
            f"no checkpoint {path} (the run was stopped before its first frame, was run by a "
            "version without checkpoints, or the file was removed); run without --resume to "
            "start afresh"
        )
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
        meta = json.loads(str(arrays.pop("__meta__")))
        if not isinstance(meta, dict) or "format" not in meta:
            raise ValueError("no format")
    except Exception as exc:  # zip, npy or JSON errors: a torn or foreign file
        raise InputError(
            f"{path} is not a readable tissuesim checkpoint ({type(exc).__name__}); it may be "
            "damaged: run without --resume to start afresh"
        ) from None
    if meta["format"] not in READS:
        raise InputError(
            f"{path} is a checkpoint of format {meta['format']!r} (tissuesim "
            f"{meta.get('tissuesim_version', '?')}); this tissuesim reads formats "
            f"{', '.join(map(str, READS))}: run without --resume to start afresh, or resume "
            "with the version that wrote it"
        )
    return meta, arrays


def save_simulation(sim, path: str | os.PathLike[str]) -> Path:
    """``Simulation.save``: the state and history of ``sim`` into one .npz, atomically."""
    from tissuesim._version import __version__

    path = Path(path)
    meta, arrays = capture(sim)
    meta.update(format=FORMAT, tissuesim_version=__version__, fingerprint=fingerprint(sim))
    arrays["history"] = np.array([encode_record(r) for r in sim.history], dtype=str)
    _write_npz(path, meta, arrays)
    return path


def load_simulation(sim, path: str | os.PathLike[str]) -> None:
    """``Simulation.load``: restore a ``save``-d state into ``sim``, set up the same way."""
    path = Path(path)
    if sim.history:
        raise InputError(
            "Simulation.load needs a simulation that has not stepped yet: set it up again the "
            "same way, then load"
        )
    meta, arrays = _read_npz(path)
    _check_fingerprint(meta["fingerprint"], fingerprint(sim), path)
    if "history" not in arrays:
        raise InputError(f"{path} is a run's checkpoint: resume it with run(..., resume=True)")
    history = [decode_record(line) for line in arrays["history"].tolist()]
    restore(sim, meta, arrays, history, path)


class RunCheckpoint:
    """The checkpoint of a run with output (``checkpoint.npz`` + ``checkpoint_history.jsonl``
    in ``directory``); see the module docstring. ``scene``: the scene file's hash."""

    def __init__(self, directory: Path, scene: str | None = None) -> None:
        self.path, self.history_path = directory / CHECKPOINT, directory / HISTORY
        self.scene = scene
        self._logged = 0  # history lines in the file
        self._fingerprint: dict | None = None
        self.meta: dict = {}

    def read(self, sim) -> tuple[dict, dict, list]:
        """(meta, arrays, history) of the directory's checkpoint; an InputError if there is
        none, it is damaged, or it was written for another set-up than ``sim``'s. Reads only."""
        meta, arrays = _read_npz(self.path)
        self._fingerprint = fingerprint(sim, self.scene)
        _check_fingerprint(meta["fingerprint"], self._fingerprint, self.path)
        n = meta["steps"]
        try:
            with open(self.history_path, encoding="utf-8") as f:
                lines = [f.readline() for _ in range(n)]
            history = [decode_record(line) for line in lines]
        except (OSError, ValueError, TypeError) as exc:
            raise InputError(
                f"{self.history_path} does not hold the {n} steps {self.path} counts "
                f"({type(exc).__name__}); it may be damaged: run without --resume to start afresh"
            ) from None
        for name, frames in meta["series"].items():
            for _, file in frames:
                if not (self.path.parent / file).is_file():
                    raise InputError(
                        f"{self.path.parent / file} (frame of the series {name!r} the checkpoint "
                        "lists) is missing; run without --resume to start afresh"
                    )
        self.meta = meta
        self._lines = lines
        return meta, arrays, history

    def resumed(self) -> None:
        """Drop history lines after the checkpoint's (a step logged before a kill)."""
        write_text_atomic(self.history_path, "".join(self._lines))
        self._logged = len(self._lines)

    def write(self, sim, series: dict[str, list], run: dict) -> None:
        """Append the new history lines (fsynced), then replace checkpoint.npz atomically."""
        from tissuesim._version import __version__

        if self._fingerprint is None:
            self._fingerprint = fingerprint(sim, self.scene)
        mode = "a" if self._logged else "w"  # the first write starts the file afresh
        with open(self.history_path, mode, encoding="utf-8") as f:
            for record in sim.history[self._logged :]:
                f.write(encode_record(record) + "\n")
            f.flush()
            os.fsync(f.fileno())
        self._logged = len(sim.history)
        meta, arrays = capture(sim)
        meta.update(
            format=FORMAT,
            tissuesim_version=__version__,
            fingerprint=self._fingerprint,
            series=series,
            run=run,
        )
        _write_npz(self.path, meta, arrays)


def completed_steps(directory: str | os.PathLike[str]) -> int | None:
    """The steps of the run in ``directory`` if it completed (its summary says so and its
    checkpoint is there), else None; reads only."""
    d = Path(directory)
    try:
        status = json.loads((d / "summary.json").read_text(encoding="utf-8")).get("status")
        meta, _ = _read_npz(d / CHECKPOINT)
        return meta["steps"] - meta["run"]["first_step"] if status == "completed" else None
    except (OSError, ValueError, AttributeError, KeyError, InputError):
        return None
