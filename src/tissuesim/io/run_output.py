"""Running a Simulation with output, the same for every scene: per body a VTU series + PVD on rest
positions (``io/series/bodies.py``), per visual surface one, the cut surface, summary.json,
forces.csv and forces.png, FEBio's log tables (``io/logfiles.py``), a progress bar and the
pictures (``render/scene.py``).

The directory is checked before anything is written (``io/manifest.py``). summary.json is
written the moment the run starts (before the model is assembled), rewritten atomically after a
step once 20 times its last write's cost has passed (a rewrite costs O(steps): after every
step, long runs spent most of their time writing) and when the run ends however it ends, so a
run stopped at any point (a crash, a ConvergenceError, Ctrl-C, SIGTERM) leaves a valid summary
whose "status" says how it ended (a SIGKILL: the steps up to its last write), and every frame
listed in a .pvd exists and is complete. What an earlier run into the same directory wrote (its
manifest.json) is removed when the new run starts, so nothing stale sits beside the new output.
Interrupts (one Ctrl-C or several, SIGTERM) end the run with status "interrupted" and skip the
pictures; while the final summary is written further interrupts wait.

After every frame the checkpoint (``io/checkpoints/checkpoint.py``) is written; ``resume``
continues the run in the directory from it: its series, summary.json and forces.csv go on with the
whole history.
"""

from __future__ import annotations

import os
import sys
import time
from contextlib import ExitStack
from dataclasses import asdict
from typing import Any

import numpy as np

from tissuesim.errors import InputError, TissueSimError
from tissuesim.io.atomic import remove_leftovers, write_json_atomic
from tissuesim.io.checkpoints.checkpoint import CHECKPOINT, HISTORY, RunCheckpoint, restore
from tissuesim.io.interrupts import deferred_interrupts, interrupts_as_keyboard_interrupt
from tissuesim.io.lock import run_lock
from tissuesim.io.manifest import MANIFEST, Manifest, prepare_directory
from tissuesim.io.series.bodies import VisualSeries, series_for

__all__ = ["RunOutput", "OBSTACLES"]

#: the key of a frame's data under which the obstacles' (positions, triangles) are kept
OBSTACLES = "__obstacles__"
#: summary.json is rewritten once this many times its last write's cost has passed
SUMMARY_COST_RATIO = 20.0


class RunOutput:
    """Runs a Simulation's steps and writes its output into ``directory`` (None: nothing).

    every: write a frame every this many steps (and the last). render: draw forces.png,
    final.png and run.gif, coloured by ``field`` ("J", "von_mises", "displacement",
    "green_strain"); False draws no picture at all (forces.csv is still written).
    """

    def __init__(
        self,
        sim: Any,
        directory: str | os.PathLike[str] | None,
        *,
        every: int = 1,
        render: bool = True,
        field: str = "J",
        metadata: dict | None = None,
        resume: bool = False,
    ) -> None:
        from tissuesim.render.scene import field_label
        from tissuesim.validate import integer, short

        every = integer(every, "every", low=1)
        if not isinstance(render, bool):
            raise InputError(f"render must be true or false, not {short(render)}")
        field_label(field)  # an unknown field fails before the run
        self.sim = sim
        self.every = every
        self.render = render
        self.field = field
        self.metadata = dict(metadata or {})
        self.frames: list[tuple[Any, ...]] = []  # what the pictures draw, one per written frame
        self.cut_series = None
        self.obstacle_series: list = []  # (Obstacle, VTUSeriesWriter), opened with the series
        self.visual_series: list = []  # io/series/bodies.py VisualSeries, one per visual surface
        self.logs: list = []  # io/logfiles.py LogTable, one per Simulation.add_logfile request
        self.status = "running"
        self.error = None
        self.pictures = "not rendered" if render else "not asked for (render = false)"
        self.render_time = 0.0  # s spent drawing final.png and run.gif
        self.description = None
        self.directory = None if directory is None else prepare_directory(directory)
        # one run at a time per directory (io/lock.py): a second run refuses here, before it
        # touches anything; the caller releases it when the run ends (``with writer.lock``)
        self.lock = ExitStack()
        if self.directory is not None:
            self.lock.enter_context(run_lock(self.directory))
        try:
            self._start(sim, resume)
        except BaseException:
            self.lock.close()
            raise

    def _start(self, sim: Any, resume: bool) -> None:
        self.resume = bool(resume)
        if self.resume and self.directory is None:
            raise InputError("resume needs the output directory of the run to continue")
        self.checkpoint = None
        self._kept_series: dict | None = None  # resume: series name -> its frames so far
        self._first_step = len(sim.history)  # the run's steps count from here
        self._previous_status = None  # resume: the status the summary.json found says
        self._last_write = (0.0, 0.0)  # (perf_counter at the summary's last write, its cost)
        self._created = time.perf_counter()
        # where the run's wall time went (s): assembling the model, the steps, writing the
        # frames and summaries, drawing forces.png / final.png / run.gif
        self.time_split = {"setup_s": 0.0, "steps_s": 0.0, "output_s": 0.0, "pictures_s": 0.0}
        if self.directory is not None:
            self.manifest = Manifest(self.directory)
            self.checkpoint = RunCheckpoint(self.directory, self.metadata.get("scene_sha256"))
        if self.directory is not None and not self.resume:
            if not (self.directory / MANIFEST).exists():
                self.manifest.write()  # a manifest exists whenever a summary does
            self._write_summary()  # replaces the previous run's summary first
            self.manifest.remove_previous()
            (self.directory / CHECKPOINT).unlink(missing_ok=True)  # never another run's
            self.manifest.add(file="summary.json")
        try:
            sim.build()
            self.series = [series_for(b) for b in sim.bodies.values()]
            self.visual_series = [  # surfaces carried by FEM bodies, written beside them
                VisualSeries(sim.bodies[v.body], v) for v in sim.visual_surfaces.values()
            ]
            # once (~1 s for meshes of 1e5 cells), of the set-up as the run started: a resumed
            # run's is its uninterrupted run's (a cut body's mesh as set up, no solver yet)
            self.description = sim.describe()
            if self.resume:
                self._restore()  # reads and checks the checkpoint; writes nothing
        except BaseException as exc:
            if not self.resume:  # a resume that fails here leaves the directory as it was
                self._fail(exc)
            raise
        self.time_split["setup_s"] = time.perf_counter() - self._created

    # -- resuming -----------------------------------------------------------------------------
    def _restore(self) -> None:
        """Load the directory's checkpoint into the simulation (InputError, the directory
        untouched, if it is missing, damaged or of another set-up)."""
        import json

        meta, arrays, history = self.checkpoint.read(self.sim)
        self._first_step = meta["run"]["first_step"]
        self._kept_series = meta["series"]
        try:
            text = (self.directory / "summary.json").read_text(encoding="utf-8")
            self._previous_status = json.loads(text).get("status")
        except (OSError, ValueError, AttributeError):
            self._previous_status = None
        restore(self.sim, meta, arrays, history, self.checkpoint.path)
        self.metadata["resumed_at_step"] = len(history) - self._first_step

    def _start_resumed(self) -> None:
        """Go on writing into the resumed run's directory: its files stay listed, the
        temporaries the kill left (if it landed mid-write) are removed."""
        remove_leftovers(self.directory)
        self.checkpoint.resumed()
        self.manifest.files = list(self.manifest.previous["files"])
        self.manifest.series = list(self.manifest.previous["series"])
        self.manifest.add(file="summary.json")

    # -- series -------------------------------------------------------------------------------
    def _open_series(self) -> None:
        from tissuesim.io.series.vtu import VTUSeriesWriter, remove_series

        keep = self._kept_series
        for s in self.series + self.visual_series:
            s.open(self.directory, keep)
        for ob in self.sim.obstacles:  # rest surface + displacement, like the bodies
            writer = VTUSeriesWriter(
                self.directory,
                None,
                ob.name,
                cells=("triangle", ob.triangles),
                n_points=len(ob.rest),
                keep=None if keep is None else keep.get(ob.name),
            )
            self.obstacle_series.append((ob, writer))
        self._open_logs()
        tissue = self.sim.tissue
        if tissue is not None and tissue.cuts:
            self.cut_series = VTUSeriesWriter(
                self.directory,
                None,
                "cut",
                cells=("triangle", np.zeros((1, 3), int)),
                n_points=3,
                keep=None if keep is None else keep.get("cut"),
            )
        else:
            remove_series(self.directory, "cut")
        if not self.resume:
            for stale in ("final.png", "run.gif", "forces.png", "forces.csv"):
                (self.directory / stale).unlink(missing_ok=True)  # from a run without a manifest

    def _open_logs(self) -> None:
        """The log tables (``io/logfiles.py``): new ones, or a resumed run's cut back to the
        lines its checkpoint counts."""
        from tissuesim.io.logfiles import LogTable, check_uncut

        counts = None
        if self.resume:
            counts = self.checkpoint.meta.get("run", {}).get("logfiles", {})
        self.logs = []
        for request in self.sim.logfiles:
            check_uncut(self.sim, request)
            table = LogTable(request)
            table.open(self.directory, None if counts is None else counts.get(request.file))
            self.manifest.add(file=request.file)
            self.logs.append(table)

    def _write_frame(self) -> None:
        sim = self.sim
        t = sim.time
        for log in self.logs:  # before the checkpoint that counts their lines
            log.write(sim, t)
        data = {}
        for s in self.series:
            if s.body.model is not None or s.body.kind == "tissue":
                data[s.body.name] = s.write(sim, t)
        for s in self.visual_series:  # the pictures carry them from the bodies' positions
            s.write(sim, t)
        obstacles = {}
        for ob in sim.obstacles:
            obstacles[ob.name] = (ob.positions(t), ob.triangles)
        for ob, writer in self.obstacle_series:
            writer.write(t, ob.rest, point_data={"displacement": obstacles[ob.name][0] - ob.rest})
        if obstacles:
            data[OBSTACLES] = obstacles  # drawn by render/scene.py
        cut = sim.tissue.cut_surface if sim.tissue is not None else np.zeros((0, 3, 3))
        if self.cut_series is not None and len(cut):
            self.cut_series.write(
                t, cut.reshape(-1, 3), cells=("triangle", np.arange(3 * len(cut)).reshape(-1, 3))
            )
        self._record_series()
        suffix = ""
        graspers = [g.name for g in sim.graspers]
        if graspers and sim.history:
            force = np.linalg.norm(sim.history[-1].extra["forces"][graspers[0]])
            suffix = f"   {graspers[0]} force {force:.3g} N"
        self.frames.append((t, data, cut.copy(), suffix))

    def _writers(self) -> list:
        writers = [w for s in self.series + self.visual_series for w in s.writers]
        writers += [w for _, w in self.obstacle_series]
        return writers + ([self.cut_series] if self.cut_series is not None else [])

    def _record_series(self) -> None:
        """List in the manifest every series that has written its index (a series opened but
        not yet written, e.g. the cut before the blade starts, is not listed)."""
        if self.directory is None:
            return
        for w in self._writers():
            if w.pvd_path.is_file():
                self.manifest.add(series=w.name)

    def _write_checkpoint(self, steps: int) -> None:
        """After a frame: the checkpoint of the state it shows (io/checkpoints/checkpoint.py)."""
        if self.checkpoint is None:
            return
        self.manifest.add(file=CHECKPOINT)  # listed before it exists: the next run removes it
        self.manifest.add(file=HISTORY)
        series = {w.name: [[t, p.name] for t, p in w.frames] for w in self._writers() if w.frames}
        run = {"first_step": self._first_step, "steps": steps, "every": self.every}
        if self.logs:
            run["logfiles"] = {log.request.file: log.lines for log in self.logs}
        self.checkpoint.write(self.sim, series, run)

    def window(self) -> list:
        """The records of this run's steps: steps taken before it (``Simulation.step`` by hand)
        are not in its output, whose series starts at the state the run started from; a
        resumed run's window is the whole run, the steps before the kill included."""
        return self.sim.history[self._first_step :]

    # -- summary ------------------------------------------------------------------------------
    def _summary(self) -> dict:
        from tissuesim._version import __version__

        history = self.window()
        steps = [_promote_contact(asdict(r)) for r in history]
        iters = [r.newton_iterations for r in history]
        return {
            "tissuesim_version": __version__,
            "status": self.status,
            "error": self.error,
            **self.metadata,
            "simulation": self.description,  # None until the model is assembled
            "totals": {
                "steps": len(steps),
                "end_time": float(self.sim.time),
                "newton_iterations": int(sum(iters)),
                "max_newton_iterations_per_step": int(max(iters, default=0)),
                "min_J": float(min((r.min_J for r in history), default=np.nan)),
                "wall_time_s": float(sum(r.wall_time_s for r in history)),
                "render_wall_time_s": self.render_time,
                "elapsed_s": time.perf_counter() - self._created,
                "time_split_s": dict(self.time_split),
            },
            "forces": [{"time": r.time, **r.extra.get("forces", {})} for r in history],
            "pictures": self.pictures,
            "steps": steps,
        }

    def _write_summary(self) -> None:
        if self.directory is None:
            return
        from tissuesim.io.forces import write_forces_csv

        start = time.perf_counter()
        write_json_atomic(self.directory / "summary.json", self._summary())
        history = self.window()
        if history and history[-1].extra.get("forces"):
            write_forces_csv(self.directory / "forces.csv", history)
            self.manifest.add(file="forces.csv")
        now = time.perf_counter()
        self._last_write = (now, now - start)

    def _write_summary_after_a_step(self) -> None:
        """Rewrite summary.json and forces.csv once the time since their last write is
        SUMMARY_COST_RATIO times what that write cost: a rewrite costs O(steps), and after
        every step a long run spent most of its time writing (O(steps^2)); so writing stays
        under 1 / SUMMARY_COST_RATIO of the run at any length, and a kill loses at most the
        steps since the last write (the frames are written as before)."""
        at, cost = self._last_write
        if time.perf_counter() - at >= SUMMARY_COST_RATIO * cost:
            self._write_summary()

    def _fail(self, exc: BaseException) -> None:
        """Record how the run ended in the summary (any exception; an interrupt included)."""
        if isinstance(exc, KeyboardInterrupt):
            self.status, self.error = "interrupted", str(exc) or "KeyboardInterrupt"
        elif isinstance(exc, TissueSimError):
            self.status, self.error = "failed", " ".join(str(exc).split())
        else:
            self.status, self.error = "failed", f"{type(exc).__name__}: {exc}"
        with deferred_interrupts():  # a Ctrl-C now waits until the summary says how it ended
            self._write_summary()

    # -- the run --------------------------------------------------------------------------------
    def run(self, steps: int, progress: bool = True) -> list:
        """Step ``steps`` times, writing every ``every``-th frame, the last, and the summary;
        return the run's records (``window``). The summary's status records how it ended."""
        from tissuesim.io.progress import progress_bar
        from tissuesim.time.grid import check_time_resolution
        from tissuesim.validate import integer

        steps = integer(steps, "steps", low=0)
        done = len(self.sim.history) - self._first_step  # resumed: the steps already run
        if self.resume:
            if done > steps:
                raise InputError(
                    f"{self.directory} holds a run of {done} steps, more than the {steps} asked "
                    f"for; when resuming, steps counts the whole run: ask for {done} or more"
                )
            finished = self.sim.finished  # an adaptive run that reached its end
            if (done == steps or finished) and self._previous_status == "completed":
                self.status = "completed"  # nothing to do: the directory is left as it is
                return self.window()
            self._start_resumed()
        remaining = steps - done if self.resume else steps
        end = done + remaining  # frames: every ``every``-th step of the run, and the last
        try:
            h = self.sim.time_step
            check_time_resolution(self.sim.time + remaining * h, h, "the end time")
            start = time.perf_counter()
            if self.directory is not None:
                self._open_series()
                self._write_summary()
            if not self.resume:  # a resumed run's frames so far are there
                self._write_frame()
                self._write_checkpoint(end)
            self.time_split["output_s"] += time.perf_counter() - start
        except BaseException as exc:
            self._fail(exc)
            raise
        bar = progress_bar(remaining, progress)
        with interrupts_as_keyboard_interrupt():  # one interrupt stops; more are ignored
            try:
                split = self.time_split
                for k in range(remaining):
                    start = time.perf_counter()
                    record = self.sim.step()
                    stepped = time.perf_counter()
                    n = done + k + 1
                    last = n == end or self.sim.finished  # an adaptive run ends at its end
                    if last or (n % self.every == 0 and _frame_due(self.sim, record)):
                        self._write_frame()
                        self._write_checkpoint(end)
                    self._write_summary_after_a_step()
                    split["steps_s"] += stepped - start
                    split["output_s"] += time.perf_counter() - stepped
                    bar.set_postfix(
                        t=f"{record.time:.4g}",
                        newton=record.newton_iterations,
                        minJ=f"{record.min_J:.3g}",
                    )
                    bar.update(1)
                    if last:
                        break
            except BaseException as exc:  # the summary must not still say "running"
                self._fail(exc)
                bar.close()
                if self.directory is not None and isinstance(exc, Exception):
                    self._pictures_of_a_failed_run(progress)  # they show where it went wrong
                raise
            bar.close()
            self.status = "completed"
            with deferred_interrupts():
                self._write_summary()
            if self.directory is not None:
                try:
                    self._pictures(progress)
                except KeyboardInterrupt:  # the run is complete: only the pictures are skipped
                    self.pictures = "skipped (interrupted while drawing)"
                    self._write_summary()
                    raise
        return self.window()

    def _pictures_of_a_failed_run(self, progress: bool) -> None:
        try:
            self._pictures(progress)
        except KeyboardInterrupt:
            self.pictures = "skipped (interrupted while drawing)"
            self._write_summary()

    def _pictures(self, progress: bool) -> None:
        start = time.perf_counter()
        try:
            self._draw(progress)
        finally:
            self.time_split["pictures_s"] += time.perf_counter() - start
        self._write_summary()

    def _draw(self, progress: bool) -> None:
        from tissuesim.io.forces import render_forces_png

        # render=False / --no-render: no picture at all, forces.png included (matplotlib's
        # import and drawing were half of a short run's time)
        if self.render:
            render_forces_png(self.directory / "forces.png", self.window())  # none: no file
        if self.render and self.frames:
            from tissuesim.render.scene import MAX_GIF_FRAMES, gif_frames_3d, render_run

            if progress:
                flat = all(b.dim == 2 for b in self.sim.bodies.values())
                wall = sum(r.wall_time_s for r in self.window())
                n = min(len(self.frames), MAX_GIF_FRAMES if flat else gif_frames_3d(wall))
                print(
                    f"tissuesim: drawing final.png and run.gif ({n} frames, coloured by "
                    f"{self.field}) ...",
                    file=sys.stderr,
                )
            start = time.perf_counter()
            self.pictures = render_run(self.sim, self.frames, self.directory, self.field)
            self.render_time = time.perf_counter() - start
        for name in ("forces.png", "final.png", "run.gif"):
            if (self.directory / name).is_file():
                self.manifest.add(file=name)


def _frame_due(sim, record) -> bool:
    """Whether a step's frame is written: every step's, except where adaptive steps write the
    must points only (FEBio's plot_level PLOT_MUST_POINTS)."""
    c = getattr(sim, "_controller", None)
    if c is None or c.settings.frames != "must_points":
        return True
    return bool(record.extra.get("adaptive", {}).get("must_point"))


def _promote_contact(step: dict) -> dict:
    """A contact step's headline figures at the step's top level (summary.json "steps"):
    min_distance (m), active_pairs and indentation_depth (obstacle -> m); the time split stays
    under extra.contact."""
    contact = step.get("extra", {}).get("contact")
    if contact:
        for key in ("min_distance", "active_pairs", "indentation_depth"):
            if key in contact:
                step[key] = contact[key]
    return step
