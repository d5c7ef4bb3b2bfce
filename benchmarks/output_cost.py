"""What writing a run's output costs against the solve, at 10, 100 and 1,000 steps.

    python3 benchmarks/output_cost.py [--steps 10 100 1000] [--repeats 3] [--every 1]

The shipped ``course_literal`` scene (near rest: the same work every step), run through
``Simulation.run`` without an output directory and with one (every frame's VTU, summary.json,
forces.csv, manifest; no pictures, which are drawn once at the end), in the same process, one
thread. Per run length: the median over repeats of the wall time per step without and with
output, and their ratio. summary.json and forces.csv are rewritten once 20 times their last
write's cost has passed (``io/run_output.py``); rewriting them after every step made a run of
n steps cost O(n^2). Results: ``results/output_cost_last_run.md``.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402


def one_run(steps: int, output: Path | None, every: int, ratio: float | None = None) -> float:
    """Wall time per step; ``ratio`` overrides SUMMARY_COST_RATIO (0: the summary after every
    step, as before)."""
    from tissuesim.cli import example_path
    from tissuesim.io import run_output
    from tissuesim.scene.loader import load_scene

    kept = run_output.SUMMARY_COST_RATIO
    if ratio is not None:
        run_output.SUMMARY_COST_RATIO = ratio

    sim = load_scene(example_path("course_literal")).simulation
    sim.build()
    start = time.perf_counter()
    try:
        sim.run(steps, output, every=every, progress=False, render=False)
    finally:
        run_output.SUMMARY_COST_RATIO = kept
    return (time.perf_counter() - start) / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, nargs="+", default=[10, 100, 1000])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--every", type=int, default=1, help="write a frame every n steps")
    args = parser.parse_args()
    one_run(2, None, 1)  # imports, kernels
    rows = []
    for steps in args.steps:
        plain, written, every_step = [], [], []
        for _ in range(args.repeats):
            plain.append(one_run(steps, None, args.every))
            for times, ratio in ((written, None), (every_step, 0.0)):
                directory = Path(tempfile.mkdtemp(prefix="tissuesim-output-cost-"))
                try:
                    times.append(one_run(steps, directory, args.every, ratio))
                finally:
                    shutil.rmtree(directory)
        a, b, c = (1e3 * statistics.median(t) for t in (plain, written, every_step))
        rows.append((steps, a, b, b / a, c, c / a))
        print(
            f"{steps:6d} steps: {a:7.2f} ms/step alone, {b:7.2f} with output (x{b / a:.2f}), "
            f"{c:7.2f} with the summary after every step (x{c / a:.2f})",
            flush=True,
        )
    lines = [
        "# Output cost (benchmarks/output_cost.py, course_literal, 1 thread)",
        "",
        f"repeats {args.repeats} (medians), a frame every {args.every} step(s), no pictures",
        "",
        "| steps | ms/step, no output | with output | ratio | summary after every step (before) "
        "| ratio |",
        "| --- | --- | --- | --- | --- | --- |",
        *(
            f"| {s} | {a:.2f} | {b:.2f} | {r:.2f} | {c:.2f} | {q:.2f} |"
            for s, a, b, r, c, q in rows
        ),
    ]
    out = Path(__file__).parent / "results" / "output_cost_last_run.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
