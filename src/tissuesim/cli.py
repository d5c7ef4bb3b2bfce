"""Simulate soft tissue from the command line: run a TOML scene (or a shipped example by
name), the demo, a live window; describe a mesh; list the examples. Each subcommand has its
own --help."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import sys
import textwrap
import warnings
from pathlib import Path

from tissuesim.cli_identify import add_identify_parser, identify_command
from tissuesim.cli_mesh import add_mesh_parser, mesh_command
from tissuesim.cli_sweep import add_sweep_parser, sweep_command
from tissuesim.scene.examples import example_path, list_examples
from tissuesim.verification.check import FAMILIES as VERIFY_FAMILIES

__all__ = ["main", "example_path", "list_examples"]

DEMO = "course_stretch"


def _resolve_scene(scene: str) -> Path:
    path = Path(scene)
    if path.exists():
        return path  # load_scene says what is wrong with it (a directory, a FIFO)
    if scene in list_examples():
        return example_path(scene)
    from tissuesim.errors import InputError
    from tissuesim.validate import short

    raise InputError(
        f"no scene file {short(scene)} and no shipped example of that name; "
        f"examples: {', '.join(list_examples())}"
    )


def _body(sim) -> str:
    """What the scene is made of, for the run banner: each body, and the cuts."""
    parts = []
    for b in sim.bodies.values():
        if b.kind == "fem":
            parts.append(
                f"{b.name}: {b.mesh.n_points} vertices, {b.mesh.n_cells} {b.mesh.cell_kind}"
            )
        elif b.kind == "frames":
            m = b.model
            parts.append(f"{b.name}: {m.n_frames} {m.frame_type.name} frames, {m.samples.n} points")
        else:
            parts.append(f"{b.name}: {b.samples.n} points / {len(b.frames)} frames")
    text = "; ".join(parts)
    if sim.tissue is not None:
        cuts = len(sim.tissue.cuts)
        text += f"; {cuts} cut{'s' * (cuts != 1)}"
    return text


def _run(
    scene_path: Path,
    out: str | None,
    steps: int | None,
    render: bool,
    quiet: bool,
    field: str | None = None,
    resume: bool = False,
    febio_solver: bool = False,
    model: str | None = None,
    gradients: str = "sensitivities",
) -> int:
    import time

    from tissuesim.cli_optimize import is_optimisation_file, optimize_command
    from tissuesim.io.checkpoints.checkpoint import completed_steps
    from tissuesim.scene.loader import load_scene

    started = time.perf_counter()
    if scene_path.suffix.lower() == ".feb" and is_optimisation_file(scene_path):
        return optimize_command(scene_path, model, out, quiet, gradients, febio_solver)
    if model is not None:
        from tissuesim.errors import InputError

        raise InputError(f"{scene_path}: --model is for FEBio optimisation files "
                         "(<febio_optimize>)")  # fmt: skip
    if scene_path.suffix.lower() == ".feb":  # a FEBio model, run as its converted scene
        from tissuesim.febio import load_febio

        scene = load_febio(scene_path, febio_solver=febio_solver)
    elif febio_solver:
        from tissuesim.errors import InputError

        raise InputError(f"{scene_path}: --febio-solver is for FEBio models (.feb)")
    else:
        scene = load_scene(scene_path)
    loaded = time.perf_counter()
    run = dict(scene.run)
    if steps is not None:
        run["steps"] = steps
    schedule = scene.simulation.schedule  # a run in phases runs them all by default
    run.setdefault("steps", 100 if schedule is None else schedule.steps)
    if not render:
        run["render"] = False
    if field is not None:
        run["field"] = field
    directory = Path(out) if out else Path("out") / scene.name
    sim = scene.simulation
    if not quiet:
        end = sim.adaptive_end()
        steps = (f"{run['steps']} steps" if end is None else  # FEBio's adaptive steps
                 f"adaptive steps to t = {end:g} s (at most {run['steps']})")  # fmt: skip
        print(
            f"tissuesim: {scene.name}: {_body(sim)}, {sim.integrator}, "
            f"time_step {sim.time_step:g} s, {steps} -> {directory}/"
            + (" (resuming)" if resume else ""),
            file=sys.stderr,
        )
    from tissuesim.io.progress import set_quiet

    set_quiet(quiet)
    complete = resume and completed_steps(directory) == run["steps"]
    history = sim.run(
        output=directory,
        progress=not quiet,
        metadata={"scene": str(scene_path), "scene_sha256": _scene_hash(scene_path)},
        resume=resume,
        **run,
    )
    if complete:
        print(
            f"tissuesim: {directory}: the run is already complete ({run['steps']} steps); "
            f"nothing was written (give --steps above {run['steps']} to continue it)",
            file=sys.stderr,
        )
    iters = [r.newton_iterations for r in history]
    report = {
        "output": str(directory),
        "steps": len(history),
        "end_time": sim.time,
        "min_J": min((r.min_J for r in history), default=None),
        "newton_iterations_per_step": {
            "mean": sum(iters) / len(iters) if iters else 0,
            "max": max(iters, default=0),
        },
        # the real elapsed time and where it went; solver_s: the steps' own solver time
        "wall_time_s": time.perf_counter() - started,
        "time_split_s": {
            "load_scene": loaded - started,
            **{k.removesuffix("_s"): v for k, v in sim.run_time_split.items()},
            "solver": sum(r.wall_time_s for r in history),
        },
        "forces": history[-1].extra.get("forces", {}) if history else {},
        # newton method "febio": the (sub)steps tissuesim's Newton solved where FEBio's gave up
        **_fallbacks(history),
        "linear_solver": sim.linear_solver_info(),  # describe() would re-describe meshes
    }
    print(json.dumps(report, indent=2))
    return 0


def _scene_hash(path: Path) -> str:
    """The scene's fingerprint for resume: its tables (TOML), or a FEBio model's bytes."""
    if path.suffix.lower() == ".feb":
        import hashlib

        return hashlib.sha256(path.read_bytes()).hexdigest()[:16]
    from tissuesim.io.checkpoints.checkpoint import scene_hash

    return scene_hash(path)


def _play(args) -> int:
    """``tissuesim play``: the live window (render/live.py); off-screen, frames as PNG."""
    from tissuesim.render.live import LiveSession
    from tissuesim.scene.loader import load_scene

    scene = load_scene(_resolve_scene(args.scene))
    sim = scene.simulation
    if sim.integrator not in ("backward_euler", "quasistatic", "newmark", "generalized_alpha"):
        from tissuesim.errors import InputError

        raise InputError("play needs an implicit scene (contact): integrator = backward_euler")
    off = args.off_screen is not None
    path = None
    if args.path is not None:
        from tissuesim.io.device_path import read_device_path

        path = read_device_path(args.path)
    if not off:
        _check_display()
    session = LiveSession(sim, args.obstacle, budget_s=args.budget, off_screen=off, path=path)
    if off:
        session.run_off_screen(args.frames or 10, Path(args.off_screen))
        print(json.dumps({**session.report(), "pictures": args.off_screen}, indent=2))
        return 0
    session.run_window(args.frames)
    print(json.dumps(session.report(), indent=2))
    return 0


def _check_display() -> None:
    """A window needs a display: without one (a server, CI) say how to run off screen, not
    VTK's MismatchedInteractorError."""
    import os
    import sys

    from tissuesim.errors import InputError

    if sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    ):
        raise InputError(
            "play: no display to open a window on (DISPLAY is not set); run off screen with "
            "--off-screen DIR (frames saved as PNG there), e.g. tissuesim play SCENE "
            "--off-screen out/play --frames 30"
        )


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a number of seconds > 0, not {text!r}")
    return value


def _frames(text: str) -> int:
    value = _steps(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, not {text!r}")
    return value


def _steps(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, not {text!r}")
    return value


def _options(debug_default=False) -> argparse.ArgumentParser:
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        "--debug",
        action="store_true",
        default=argparse.SUPPRESS if debug_default else False,
        help="show the Python traceback of an error",
    )
    return common


def main(argv: list[str] | None = None) -> int:
    """The command line. Exit codes: 0 done, 1 the run failed (Newton, instability, an
    internal error), 2 bad input (scene, mesh, arguments, output directory), 130 interrupted."""
    parser = argparse.ArgumentParser(
        prog="tissuesim", description=__doc__, parents=[_options()], epilog=EXIT_CODES
    )
    from tissuesim._version import __version__

    parser.add_argument("--version", action="version", version=f"tissuesim {__version__}")
    common = [_options(debug_default=True)]
    sub = parser.add_subparsers(dest="command", required=True)
    p_run = sub.add_parser(
        "run",
        parents=common,
        help="run a TOML scene file, a FEBio model (.feb) or a shipped example by name",
    )
    p_run.add_argument(
        "scene",
        help="a scene file (.toml), a FEBio 3/4 model (.feb) or a shipped example's name "
        "(tissuesim examples)",
    )
    p_run.add_argument("--out", help="output directory (default out/<scene name>)")
    p_run.add_argument("--steps", type=_steps, help="number of time steps (overrides [run] steps)")
    p_run.add_argument(
        "--no-render", action="store_true", help="draw no picture (forces.png, final.png, run.gif)"
    )
    p_run.add_argument(
        "--quiet", action="store_true", help="no progress lines (the final report is printed)"
    )
    p_run.add_argument(
        "--resume",
        action="store_true",
        help="continue the run in --out from its checkpoint (killed or finished: give a larger "
        "--steps, which counts the whole run), bit-identical to an uninterrupted run",
    )
    p_run.add_argument(
        "--febio-solver",
        action="store_true",
        help="a FEBio model's steps solved by FEBio's quasi-Newton with its <solver> settings, "
        "to FEBio's stopping point (default: tissuesim's Newton, converged tightly)",
    )
    p_run.add_argument(
        "--model",
        help="the FEBio model a FEBio optimisation file (<febio_optimize>) runs on (FEBio's -i)",
    )
    p_run.add_argument(
        "--gradients",
        choices=("sensitivities", "differences"),
        default="sensitivities",
        help="an optimisation's Jacobian: the run's sensitivities (default: one run per "
        "iteration) or FEBio's forward differences (one more run per parameter)",
    )
    from tissuesim.render.scene import FIELDS

    fields = tuple(FIELDS)
    p_run.add_argument("--field", choices=fields, help="what colours the pictures (default J)")
    p_demo = sub.add_parser("demo", parents=common, help=f"run the course's example ({DEMO})")
    p_demo.add_argument("--out", default="out/demo", help="output directory (default out/demo)")
    p_demo.add_argument(
        "--steps", type=_steps, help="number of time steps (default the example's 200)"
    )
    p_demo.add_argument(
        "--no-render", action="store_true", help="draw no picture (forces.png, final.png, run.gif)"
    )
    p_demo.add_argument(
        "--quiet", action="store_true", help="no progress lines (the final report is printed)"
    )
    p_demo.add_argument("--field", choices=fields, help="what colours the pictures (default J)")
    p_play = sub.add_parser(
        "play",
        parents=common,
        help="run a scene live in a window, an instrument driven by the keys or the mouse",
    )
    p_play.add_argument(
        "scene", help="a scene file (.toml) or a shipped example's name, with an obstacle"
    )
    p_play.add_argument("--obstacle", help="the obstacle to drive (default the first)")
    p_play.add_argument("--budget", type=_seconds, help="wall-clock budget per step (s)")
    p_play.add_argument("--frames", type=_frames, help="stop after this many frames (>= 1)")
    p_play.add_argument(
        "--path",
        metavar="CSV",
        help="a recorded device path for the instrument: rows of time_s,x_m,y_m,z_m "
        "(optionally rx,ry,rz rad); off screen the default is the scene's own motion",
    )
    p_play.add_argument(
        "--off-screen",
        metavar="DIR",
        help="no window: run --frames frames (default 10) and save them as PNG in DIR",
    )
    p_convert = sub.add_parser(
        "convert",
        parents=common,
        help="write the tissuesim scene (and its mesh files) equivalent to a FEBio model",
    )
    p_convert.add_argument("model", help="a FEBio 3.0 / 4.0 model (.feb)")
    p_convert.add_argument("scene", help="the scene to write (.toml); meshes go next to it")
    p_convert.add_argument("--force", action="store_true", help="overwrite existing files")
    p_convert.add_argument(
        "--febio-solver",
        action="store_true",
        help="write [newton] method 'febio' with the model's <solver> settings (FEBio's "
        "quasi-Newton, to FEBio's stopping point)",
    )
    p_info = sub.add_parser("info", parents=common, help="describe a mesh file and check it")
    p_info.add_argument("mesh", help="a mesh file (.msh, .vtu, .vtk, .inp, ... as meshio reads)")
    add_mesh_parser(sub, common)
    p_examples = sub.add_parser(
        "examples",
        parents=common,
        help="list the shipped example scenes: what each shows, needs and takes",
    )
    p_examples.add_argument(
        "--json", action="store_true", help="print the list as JSON (for scripts)"
    )
    p_verify = sub.add_parser(
        "verify",
        parents=common,
        help="run the shipped verification problems and print their table (exit 1 if one fails)",
    )
    p_verify.add_argument("--json", action="store_true", help="print the checks as JSON")
    p_verify.add_argument(
        "--only",
        action="append",
        choices=VERIFY_FAMILIES,
        help="run only this family (repeatable)",
    )
    add_sweep_parser(sub, common, _frames, _steps)
    add_identify_parser(sub, common)
    args = parser.parse_args(argv)
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        try:
            code = _dispatch(args)
            sys.stdout.flush()  # here, so a closed pipe is caught below, not at exit
            return code
        except BrokenPipeError:
            # the reader stopped reading (`tissuesim info mesh | head`): end quietly, as Unix
            # tools do; stdout goes to devnull so the interpreter's last flush cannot fail
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 0
        except KeyboardInterrupt:
            if args.debug:
                raise
            with contextlib.suppress(ValueError):  # not the main thread: no signals here
                signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C: we are leaving
            print("tissuesim: interrupted", file=sys.stderr)
            return 130
        except BaseException as exc:
            if args.debug or isinstance(exc, SystemExit):
                raise
            code, message = error_message(exc)
            print(f"tissuesim: error: {message}", file=sys.stderr)
            return code


EXIT_CODES = (
    "exit codes: 0 done; 1 the run failed (Newton did not converge, explicit steps blew up, an "
    "internal error); 2 bad input (scene, mesh, argument, output directory); 130 interrupted"
)
MAX_MESSAGE = 1000  # characters of one error line


def error_message(exc: BaseException) -> tuple[int, str]:
    """(exit code, one line) for an exception that ends a command."""
    from tissuesim.errors import InputError, RunError, TissueSimError

    if isinstance(exc, RunError):
        code, text = 1, str(exc)
    elif isinstance(exc, InputError | TissueSimError):
        code, text = 2, str(exc)
    elif isinstance(exc, MemoryError):
        code, text = 1, f"out of memory ({exc}); use a coarser mesh or fewer frames/points"
    elif isinstance(exc, OSError):
        name = exc.filename if exc.filename is not None else ""
        code = 1
        text = f"{name}: {exc.strerror or exc}" if name else f"{exc.strerror or exc}"
        text += " (a file tissuesim had to read or write)"
    else:
        code = 1
        text = (
            f"internal error ({type(exc).__name__}: {exc}); this is a bug in tissuesim: rerun "
            "with --debug for the traceback and report it"
        )
    text = " ".join(text.split())
    if len(text) > MAX_MESSAGE:
        text = text[: MAX_MESSAGE - 20] + f" ... ({len(text)} characters)"
    return code, text


def _fallbacks(history) -> dict:
    n = sum(r.extra.get("newton_fallback", 0) for r in history)
    return {"febio_solver_fallbacks": n} if n else {}


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"tissuesim: warning: {' '.join(str(message).split())}", file=sys.stderr)


def _dispatch(args) -> int:
    if args.command == "run":
        return _run(
            _resolve_scene(args.scene),
            args.out,
            args.steps,
            not args.no_render,
            args.quiet,
            args.field,
            args.resume,
            args.febio_solver,
            args.model,
            args.gradients,
        )
    if args.command == "demo":
        return _run(
            example_path(DEMO), args.out, args.steps, not args.no_render, args.quiet, args.field
        )
    if args.command == "play":
        return _play(args)
    if args.command == "mesh":
        return mesh_command(args)
    if args.command == "convert":
        from tissuesim.febio import convert_febio

        written = convert_febio(
            args.model, args.scene, force=args.force, febio_solver=args.febio_solver
        )
        print(json.dumps({"written": [str(p) for p in written]}, indent=2))
        return 0
    if args.command == "info":
        from tissuesim.mesh import describe_mesh, read_mesh

        print(json.dumps(describe_mesh(read_mesh(args.mesh)), indent=2))
        return 0
    if args.command == "verify":
        return _verify(args.json, args.only)
    if args.command in ("sweep", "identify"):
        return {"sweep": sweep_command, "identify": identify_command}[args.command](args)
    return _examples(args.json)


def _verify(as_json: bool, only: list[str] | None) -> int:
    """``tissuesim verify``: the table (or JSON) of the verification problems; 0 if all pass."""
    from tissuesim.verification import run, table

    checks = run(tuple(only) if only else None)
    ok = all(c.passed for c in checks)
    if as_json:
        print(json.dumps({"passed": ok, "checks": [c.as_dict() for c in checks]}, indent=2))
    else:
        print(table(checks))
    return 0 if ok else 1


def _examples(as_json: bool) -> int:
    from tissuesim.scene.examples import RUNTIME_NOTE, describe_example

    described = [describe_example(name) for name in list_examples()]
    if as_json:
        print(json.dumps(described, indent=2))
        return 0
    print(f"# {RUNTIME_NOTE}")
    for e in described:
        runtime = f"; about {e['runtime']}" if e["runtime"] else ""
        print(f"{e['name']}  ({e['made_of']}{runtime})")
        print(textwrap.fill(e["shows"], 96, initial_indent="    ", subsequent_indent="    "))
        for need in e["needs"]:
            print(f"    {need}")
        print(f"    tissuesim run {e['name']}    # {e['path']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
