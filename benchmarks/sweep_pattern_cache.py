"""What the worker's sparsity pattern cache saves a study's runs (``sweep/cache.py``, issue 43).

    python3 benchmarks/sweep_pattern_cache.py [--divisions 20] [--runs 6] [--repeat 3]
                                              [--write benchmarks/results/sweep_pattern_cache.md]

A study of ``--runs`` quasistatic runs (two steps each) of a generated box organ
(divisions^3 x 6 tetrahedra: 4.8e4 at 20), its top pressed 5 % down, its Young's modulus
varied, in one worker process (a thread pool of one, so the cache is this process's), with
the pattern cache on and off (``MAX_PATTERNS`` 0: every run analyses its own pattern; the
mesh cache stays on in both) in interleaved rounds. Per run (median of the runs, then the
median round): the scene's build (mesh, model, the pattern), the solve, and the whole run.
Results equal bit for bit either way (checked here too).
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

SCENE = """
[simulation]
integrator = "quasistatic"
time_step = 0.5

[mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.1, 0.1, 0.1]
divisions = [{d}, {d}, {d}]

[material]
model = "neo_hookean"
youngs_modulus = 5000.0
poisson_ratio = 0.45

[[dirichlet]]
vertices = {{ on_plane = {{ axis = 2, value = 0.0 }} }}

[[dirichlet]]
name = "press"
vertices = {{ on_plane = {{ axis = 2, value = 0.1 }} }}
displacement = ["0", "0", "-0.005*t"]
"""


def study(scene: Path, runs: int, out: Path) -> list[dict]:
    import tissuesim

    vary = {"material.youngs_modulus": f"3e3:8e3:{runs}"}
    with ThreadPoolExecutor(1) as pool:
        return tissuesim.sweep(scene, vary, out=out, executor=pool, steps=2, progress=False)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--divisions", type=int, default=20)
    parser.add_argument("--runs", type=int, default=6)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--write", help="write the markdown table to this file")
    args = parser.parse_args()

    from tissuesim.sweep import cache
    from tissuesim.sweep.runs import prepare_worker

    prepare_worker()
    rounds: dict[str, list[dict]] = {"on": [], "off": []}
    forces: dict[str, list] = {}
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "box.toml"
        scene.write_text(SCENE.format(d=args.divisions))
        for r in range(args.repeat):
            for mode in ("off", "on"):
                cache.clear()
                keep = cache.MAX_PATTERNS
                cache.MAX_PATTERNS = keep if mode == "on" else 0
                try:
                    results = study(scene, args.runs, Path(tmp) / f"{mode}{r}")
                finally:
                    cache.MAX_PATTERNS = keep
                bad = [x["error"] for x in results if x["status"] != "completed"]
                if bad:
                    raise SystemExit(f"a run failed: {bad[0]}")
                forces.setdefault(mode, [x["forces"] for x in results])
                rounds[mode].append(
                    {
                        k: statistics.median(x[k] for x in results)
                        for k in ("build_time_s", "solve_time_s", "wall_time_s")
                    }  # fmt: skip
                )
                print(mode, r, rounds[mode][-1], "load", os.getloadavg()[0], flush=True)
    same = forces["on"] == forces["off"]
    median = {
        mode: {k: statistics.median(x[k] for x in rows) for k in rows[0]}
        for mode, rows in rounds.items()
    }
    cells = 6 * args.divisions**3
    lines = [
        f"{args.runs} runs of a {cells}-tetrahedron box, two quasistatic steps each, one worker; "
        f"median of {args.repeat} interleaved rounds (per run: the median run). Forces equal bit "
        f"for bit with and without the pattern cache: {same}.",
        "",
        "| pattern cache | build (s) | solve (s) | run (s) |",
        "| --- | --- | --- | --- |",
    ]
    for mode in ("off", "on"):
        m = median[mode]
        lines.append(f"| {mode} | {m['build_time_s']:.3f} | {m['solve_time_s']:.3f} | "
                     f"{m['wall_time_s']:.3f} |")  # fmt: skip
    saved = median["off"]["wall_time_s"] - median["on"]["wall_time_s"]
    lines += ["", f"Saved per run: {saved:.3f} s ({saved / median['off']['wall_time_s']:.1%} of "
              "the run without it)."]  # fmt: skip
    text = "\n".join(lines) + "\n"
    print(text)
    if args.write:
        Path(args.write).write_text("# Sparsity pattern cache\n\n" + text, encoding="utf-8")
    if not same:
        raise SystemExit("results differ with the pattern cache")


if __name__ == "__main__":
    main()
