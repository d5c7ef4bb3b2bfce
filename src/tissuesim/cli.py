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
import warnings
from importlib import resources
from pathlib import Path

__all__ = ["main"]

DEMO = "course_stretch"


def example_path(name: str) -> Path:
    """Path of a shipped example scene by name (``tissuesim examples`` lists them)."""
    root = resources.files("tissuesim") / "examples"
    return Path(str(root / f"{name}.toml"))


def list_examples() -> list[str]:
    root = resources.files("tissuesim") / "examples"
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


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
            kind = "triangles" if b.dim == 2 else "tetrahedra"
            parts.append(f"{b.name}: {b.mesh.n_points} vertices, {b.mesh.n_cells} {kind}")
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
) -> int:
    import time

    from tissuesim.scene.loader import load_scene

    started = time.perf_counter()
    scene = load_scene(scene_path)
    loaded = time.perf_counter()
    run = dict(scene.run)
    if steps is not None:
        run["steps"] = steps
    run.setdefault("steps", 100)
    if not render:
        run["render"] = False
    if field is not None:
        run["field"] = field
    directory = Path(out) if out else Path("out") / scene.name
    sim = scene.simulation
    if not quiet:
        print(
            f"tissuesim: {scene.name}: {_body(sim)}, {sim.integrator}, "
            f"time_step {sim.time_step:g} s, {run['steps']} steps -> {directory}/",
            file=sys.stderr,
        )
    from tissuesim.io.progress import set_quiet

    set_quiet(quiet)
    history = sim.run(
        output=directory,
        progress=not quiet,
        metadata={"scene": str(scene_path)},
        **run,
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
        "linear_solver": sim.linear_solver_info(),  # describe() would re-describe meshes
    }
    print(json.dumps(report, indent=2))
    return 0


def _play(args) -> int:
    """``tissuesim play``: the live window (render/live.py); off-screen, frames as PNG."""
    from tissuesim.render.live import LiveSession
    from tissuesim.scene.loader import load_scene

    scene = load_scene(_resolve_scene(args.scene))
    sim = scene.simulation
    if sim.integrator not in ("backward_euler", "quasistatic"):
        from tissuesim.errors import InputError

        raise InputError("play needs an implicit scene (contact): integrator = backward_euler")
    off = args.off_screen is not None
    session = LiveSession(sim, args.obstacle, budget_s=args.budget, off_screen=off)
    if off:
        records = session.run_off_screen(args.frames or 10, Path(args.off_screen))
        print(
            json.dumps(
                {
                    "frames": len(records),
                    "obstacle": session.name,
                    "force_N": session.last_force.tolist(),
                    "real_time_factor": session.real_time_factor,
                    "early_stops": session.early_stops,
                    "pictures": args.off_screen,
                },
                indent=2,
            )
        )
        return 0
    session.run_window(args.frames)
    return 0


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a number of seconds > 0, not {text!r}")
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
    from tissuesim import __version__

    parser.add_argument("--version", action="version", version=f"tissuesim {__version__}")
    common = [_options(debug_default=True)]
    sub = parser.add_subparsers(dest="command", required=True)
    p_run = sub.add_parser(
        "run", parents=common, help="run a TOML scene file (or a shipped example by name)"
    )
    p_run.add_argument(
        "scene", help="a scene file (.toml) or a shipped example's name (tissuesim examples)"
    )
    p_run.add_argument("--out", help="output directory (default out/<scene name>)")
    p_run.add_argument("--steps", type=_steps, help="number of time steps (overrides [run] steps)")
    p_run.add_argument("--no-render", action="store_true", help="skip the PNG and GIF")
    p_run.add_argument(
        "--quiet", action="store_true", help="no progress lines (the final report is printed)"
    )
    from tissuesim.render.scene import FIELDS

    fields = tuple(FIELDS)
    p_run.add_argument("--field", choices=fields, help="what colours the pictures (default J)")
    p_demo = sub.add_parser("demo", parents=common, help=f"run the course's example ({DEMO})")
    p_demo.add_argument("--out", default="out/demo", help="output directory (default out/demo)")
    p_demo.add_argument(
        "--steps", type=_steps, help="number of time steps (default the example's 200)"
    )
    p_demo.add_argument("--no-render", action="store_true", help="skip the PNG and GIF")
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
    p_play.add_argument("--frames", type=_steps, help="stop after this many frames")
    p_play.add_argument(
        "--off-screen",
        metavar="DIR",
        help="no window: run --frames frames (default 10) and save them as PNG in DIR",
    )
    p_info = sub.add_parser("info", parents=common, help="describe a mesh file and check it")
    p_info.add_argument("mesh", help="a mesh file (.msh, .vtu, .vtk, .inp, ... as meshio reads)")
    sub.add_parser("examples", parents=common, help="list the shipped example scenes")
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
        )
    if args.command == "demo":
        return _run(
            example_path(DEMO), args.out, args.steps, not args.no_render, args.quiet, args.field
        )
    if args.command == "play":
        return _play(args)
    if args.command == "info":
        from tissuesim.mesh import describe_mesh, read_mesh

        print(json.dumps(describe_mesh(read_mesh(args.mesh)), indent=2))
        return 0
    for name in list_examples():  # "examples"
        print(f"{name}\t{example_path(name)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
