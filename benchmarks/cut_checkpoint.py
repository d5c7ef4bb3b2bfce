"""What a checkpoint of a cut organ costs (issue 41): its size, the time to write it (what a run
pays after every frame) and to load it (a fresh scene set up, then the cut mesh, model, system,
contact surface and kept factor made again), against one step of the same run; and whether the
run resumed from it is bit-identical to the run that never stopped.

The shipped ``liver_resection`` at ``--divisions`` (12: 10,368 tetrahedra; the shipped one is
8), its blade going down through the right lobe, contact with the table and friction on; the
checkpoint is taken ``--at`` steps in (at 12 divisions step 22: the blade has cut 26 of the
34 cm^2 it will; the organ sags, so the blade meets it late), and the comparison runs
``--more`` steps on. One thread for ipctk and the BLAS / MKL libraries
(their parallel sums differ in the last bits between any two runs otherwise). The uncut
checkpoint (before the blade reaches the organ) is measured alongside.

    python3 benchmarks/cut_checkpoint.py        # writes benchmarks/results/cut_checkpoint.md
    python3 benchmarks/cut_checkpoint.py --divisions 8 --at 18 --out /tmp/cut_checkpoint.md
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

from tissuesim.scene.loader import build_scene

HERE = Path(__file__).resolve().parent
EXAMPLE = HERE.parent / "src" / "tissuesim" / "examples" / "liver_resection.toml"


def liver(divisions: int):
    text = EXAMPLE.read_text().replace("divisions = 8", f"divisions = {divisions}")
    return build_scene(tomllib.loads(text), base_dir=EXAMPLE.parent).simulation


def measure(divisions: int, at: int, more: int, repeats: int, directory: Path) -> list[dict]:
    """Checkpoints before the cut (step 5) and at step ``at``: size, write and load times."""
    rows = []
    sim = liver(divisions)
    steps = []
    for k in range(at):
        start = time.perf_counter()
        sim.step()
        steps.append(time.perf_counter() - start)
        if k + 1 in (5, at):
            path = directory / f"step{k + 1}.npz"
            writes = []
            for _ in range(repeats):
                start = time.perf_counter()
                sim.save(path)
                writes.append(time.perf_counter() - start)
            loads = []
            for _ in range(repeats):
                fresh = liver(divisions)
                start = time.perf_counter()
                fresh.load(path)
                loads.append(time.perf_counter() - start)
            state = sim.bodies["liver"].cut_state
            with np.load(path) as data:
                cut = sum(data[k].nbytes for k in data.files if k.startswith("cut."))
            rows.append({
                "step": k + 1,
                "cells": sim.bodies["liver"].mesh.n_cells,
                "points": sim.bodies["liver"].mesh.n_points,
                "cut_area_cm2": 0.0 if state is None else 1e4 * state.area("scalpel"),
                "file_mb": path.stat().st_size / 1e6,
                "cut_mb": cut / 1e6,
                "write_s": statistics.median(writes),
                "load_s": statistics.median(loads),
                "step_s": statistics.median(steps[-5:]),
                "resumed": fresh,
            })  # fmt: skip
    for _ in range(more):
        sim.step()
    again = rows[-1].pop("resumed")
    rows[0].pop("resumed")
    for _ in range(more):
        again.step()
    same = np.array_equal(sim.state.x, again.state.x) and np.array_equal(sim.state.v, again.state.v)
    same &= [r.extra["forces"] for r in sim.history] == [r.extra["forces"] for r in again.history]
    rows[-1]["bit_identical_after"] = f"{more} steps: {same}"
    return rows


def main() -> None:
    import ipctk
    from threadpoolctl import threadpool_limits

    from tissuesim.solve.linear import _mkl_pardiso, has_pardiso

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--divisions", type=int, default=12)
    parser.add_argument("--at", type=int, default=22, help="the checkpoint's step (mid-cut)")
    parser.add_argument("--more", type=int, default=6, help="steps compared after it")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=HERE / "results" / "cut_checkpoint.md")
    args = parser.parse_args()
    if has_pardiso():
        _mkl_pardiso()
    ipctk.set_num_threads(1)
    with threadpool_limits(1), tempfile.TemporaryDirectory() as tmp:
        rows = measure(args.divisions, args.at, args.more, args.repeats, Path(tmp))
    keys = list(rows[-1])
    lines = [
        "# A cut organ's checkpoint (benchmarks/cut_checkpoint.py)",
        "",
        f"`python3 benchmarks/cut_checkpoint.py --divisions {args.divisions} --at {args.at}`; "
        f"liver_resection at {args.divisions} divisions, medians of {args.repeats}, one thread, "
        "this machine.",
        "",
        "| " + " | ".join(keys) + " |",
        "| " + " | ".join("---" for _ in keys) + " |",
    ]
    for row in rows:
        cells = [row.get(k, "") for k in keys]
        lines.append("| " + " | ".join(f"{c:.4g}" if isinstance(c, float) else str(c)
                                       for c in cells) + " |")  # fmt: skip
    text = "\n".join(lines) + "\n"
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
