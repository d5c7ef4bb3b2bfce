"""Command line: ``tissuesim run SCENE``, ``tissuesim demo``, ``tissuesim info MESH``,
``tissuesim examples``. Thin: everything it does is one call into the library."""

from __future__ import annotations

import argparse
import json
import sys
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
    if path.is_file():
        return path
    if scene in list_examples():
        return example_path(scene)
    raise SystemExit(
        f"tissuesim: no scene file {scene!r} and no shipped example of that name; "
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
    from tissuesim.scene.loader import load_scene

    scene = load_scene(scene_path)
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
        "wall_time_s": sum(r.wall_time_s for r in history),
        "forces": history[-1].extra.get("forces", {}) if history else {},
        "linear_solver": sim.linear_solver_info(),  # describe() would re-describe meshes
    }
    print(json.dumps(report, indent=2))
    return 0


def _steps(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, not {text!r}")
    return value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="tissuesim", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    p_run = sub.add_parser("run", help="run a TOML scene file (or a shipped example by name)")
    p_run.add_argument("scene")
    p_run.add_argument("--out", help="output directory (default out/<scene name>)")
    p_run.add_argument("--steps", type=_steps, help="number of time steps (overrides [run] steps)")
    p_run.add_argument("--no-render", action="store_true", help="skip the PNG and GIF")
    p_run.add_argument("--quiet", action="store_true", help="no progress bar")
    from tissuesim.render.scene import FIELDS

    fields = tuple(FIELDS)
    p_run.add_argument("--field", choices=fields, help="what colours the pictures (default J)")
    p_demo = sub.add_parser("demo", help=f"run the course's example problem ({DEMO})")
    p_demo.add_argument("--out", default="out/demo")
    p_demo.add_argument("--steps", type=_steps)
    p_demo.add_argument("--no-render", action="store_true", help="skip the PNG and GIF")
    p_demo.add_argument("--quiet", action="store_true")
    p_demo.add_argument("--field", choices=fields, help="what colours the pictures (default J)")
    p_info = sub.add_parser("info", help="describe a mesh file and check it")
    p_info.add_argument("mesh")
    sub.add_parser("examples", help="list the shipped example scenes")
    args = parser.parse_args(argv)

    from tissuesim.errors import TissueSimError

    try:
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
        if args.command == "info":
            from tissuesim.mesh import describe_mesh, read_mesh

            print(json.dumps(describe_mesh(read_mesh(args.mesh)), indent=2))
            return 0
        if args.command == "examples":
            for name in list_examples():
                print(f"{name}\t{example_path(name)}")
            return 0
    except TissueSimError as exc:
        print(f"tissuesim: error: {exc}", file=sys.stderr)
        return 2
    return 1


if __name__ == "__main__":
    sys.exit(main())
