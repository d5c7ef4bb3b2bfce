"""The shipped retraction-and-dissection scene (examples/organs_retraction_cut.toml), measured:
time per step, Newton iterations per step, the grasper's force curve, the cost of the cut steps,
and, as a reference measured in the same run, the same organs and grasper without the tissue.

    python benchmarks/coupled_retraction.py            # 3 runs of the full scene (~5 min, 2 cores)
    python benchmarks/coupled_retraction.py --quick    # first 6 steps, no reference run
    python benchmarks/coupled_retraction.py --out DIR  # write DIR/coupled_retraction.{json,md}

Times are wall-clock seconds of ``Simulation.step`` (assembly, Newton, reactions, cuts and
rebuilds), without output or pictures; per phase, the median over the steps of a run, then the
median over ``--repeats`` runs (the reference likewise).
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from tissuesim.cli import example_path
from tissuesim.scene.loader import load_scene

SCENE = "organs_retraction_cut"


def run_scene(steps: int | None, tissue: bool = True) -> tuple[list, float, object]:
    scene = load_scene(example_path(SCENE))
    sim = scene.simulation
    if not tissue:  # the reference: organs, support and grasper only
        sim.remove_body("tissue")
    steps = steps or int(scene.run.get("steps", 120))
    start = time.perf_counter()
    sim.build()
    setup = time.perf_counter() - start
    records = [sim.step() for _ in range(steps)]
    return records, setup, sim


def phase(records, lo: float, hi: float) -> list:
    return [r for r in records if lo < r.time <= hi + 1e-12]


def summarise(records, label: str) -> dict:
    times = [r.wall_time_s for r in records]
    its = [r.newton_iterations for r in records]
    per_iteration = [r.wall_time_s / r.newton_iterations for r in records if r.newton_iterations]
    return {
        "median_s_per_newton_iteration": statistics.median(per_iteration)
        if per_iteration
        else None,
        "phase": label,
        "steps": len(records),
        "median_step_s": statistics.median(times) if times else None,
        "max_step_s": max(times, default=None),
        "newton_mean": float(np.mean(its)) if its else None,
        "newton_median": statistics.median(its) if its else None,
        "newton_max": max(its, default=None),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=str(Path(__file__).parent / "results"))
    parser.add_argument("--repeats", type=int, default=3, help="whole-scene runs (timing medians)")
    args = parser.parse_args()
    steps = 6 if args.quick else None
    repeats = 1 if args.quick else max(1, args.repeats)
    runs = [run_scene(steps) for _ in range(repeats)]
    records, setup, sim = runs[0]  # the physics is deterministic: curve and counts from run 1
    cut = sim.tissue.cuts[0] if sim.tissue is not None and sim.tissue.cuts else None
    c0, c1 = (cut.start, cut.end) if cut else (np.inf, np.inf)
    bounds = [
        (-1, c0, f"retraction and hold (t <= {c0:g} s)"),
        (c0, c1 + sim.time_step, f"cutting ({c0:g} < t <= {c1:g} s)"),
        (c1 + sim.time_step, np.inf, f"after the cut (t > {c1:g} s)"),
        (-1, np.inf, "all steps"),
    ]
    phases = []
    for lo, hi, label in bounds:
        each = [summarise(phase(r[0], lo, hi), label) for r in runs]
        row = dict(each[0])
        for key in ("median_step_s", "max_step_s", "median_s_per_newton_iteration"):
            values = [e[key] for e in each if e[key] is not None]
            row[key] = statistics.median(values) if values else None
        row["runs"] = len(each)
        phases.append(row)
    setup = statistics.median(r[1] for r in runs)
    grasper = sim.graspers[0].name
    curve = [
        {
            "time": r.time,
            "force": r.extra["forces"][grasper],
            "magnitude": float(np.linalg.norm(r.extra["forces"][grasper])),
            "newton_iterations": r.newton_iterations,
            "wall_time_s": r.wall_time_s,
            "tissue_points": r.extra["tissue_points"],
            "attachments": r.extra["attachments"],
            "attachment_gap_m": r.extra["attachment_gap"],
            "events": [
                e["kind"]
                if e["kind"] != "cut"
                else f"cut ({e.get('severed_pairs', 0)} pairs severed, "
                f"{e.get('removed_points', 0)} points removed)"
                for e in r.extra["events"]
            ],
        }
        for r in records
    ]
    weight = None
    if sim.gravity:
        m = sim.bodies[sim.graspers[0].body].model
        weight = float(m.mass.lumped.sum() / 3 * np.linalg.norm(sim.gravity[0]))
    reference = None
    if not args.quick:
        refs = [summarise(run_scene(len(records), tissue=False)[0], "") for _ in range(repeats)]
        ref = {
            key: statistics.median(r[key] for r in refs)
            for key in ("median_step_s", "median_s_per_newton_iteration", "newton_mean")
        }
        reference = {
            "organs_only_median_step_s": ref["median_step_s"],
            "organs_only_s_per_newton_iteration": ref["median_s_per_newton_iteration"],
            "organs_only_newton_mean": ref["newton_mean"],
            "ratio_per_iteration": phases[0]["median_s_per_newton_iteration"]
            / ref["median_s_per_newton_iteration"],
        }
    result = {
        "scene": SCENE,
        "machine": f"{platform.processor() or platform.machine()}, {platform.system()}",
        "setup_s": setup,
        "dofs": sim.system.n_dofs if sim.system else None,
        "description": sim.describe(),
        "phases": phases,
        "reference": reference,
        "grasped_organ_weight_N": weight,
        "curve": curve,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = "coupled_retraction_quick" if args.quick else "coupled_retraction"
    (out / f"{name}.json").write_text(json.dumps(result, indent=1, default=str))
    lines = [
        f"# {SCENE}: time per step, Newton iterations, grasper force",
        "",
        f"Command: `python benchmarks/coupled_retraction.py{' --quick' if args.quick else ''}`; "
        f"{repeats} run(s) of the whole scene, times are medians over the runs of each run's "
        f"per-phase median (max: median of the runs' maxima); set-up (meshes, tissue sampling, "
        f"attachments, patterns) {setup:.2f} s.",
        "",
        "| phase | steps | median s/step | max s/step | median s/Newton iteration "
        "| Newton its mean / median / max |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for p in phases:
        if p["steps"]:
            lines.append(
                f"| {p['phase']} | {p['steps']} | {p['median_step_s']:.3f} | "
                f"{p['max_step_s']:.3f} | {p['median_s_per_newton_iteration'] or 0:.3f} | "
                f"{p['newton_mean']:.2f} / {p['newton_median']} / {p['newton_max']} |"
            )
    if reference:
        lines += [
            "",
            f"Reference in the same run: organs, support and grasper without the tissue "
            f"(the gallbladder only translates, {reference['organs_only_newton_mean']:.2f} "
            f"Newton iterations per step): {reference['organs_only_median_step_s']:.3f} s/step, "
            f"{reference['organs_only_s_per_newton_iteration']:.3f} s per Newton iteration; "
            f"a Newton iteration of the coupled scene (retraction phase) costs "
            f"{reference['ratio_per_iteration']:.1f}x that.",
        ]
    if weight is not None:
        lines += ["", f"Weight of the grasped organ alone: {weight:.4f} N."]
    lines += [
        "",
        "| t (s) | grasper force z (N) | abs (N) | Newton its | s/step | tissue points | events |",
    ]
    lines += ["| --- | --- | --- | --- | --- | --- | --- |"]
    every = max(1, len(curve) // 30)
    for i, c in enumerate(curve):
        if i % every == 0 or c["events"] or i == len(curve) - 1:
            lines.append(
                f"| {c['time']:.3f} | {c['force'][2]:.4f} | {c['magnitude']:.4f} | "
                f"{c['newton_iterations']} | {c['wall_time_s']:.3f} | {c['tissue_points']} | "
                f"{', '.join(c['events'])} |"
            )
    (out / f"{name}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:14]))


if __name__ == "__main__":
    main()
