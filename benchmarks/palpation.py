"""Interactive contact (issue 21): an organ palpated by a probe and grasped by capsule jaws, at
the default settings, against the same organ without an instrument and against the same run
with every tolerance 100 times tighter.

The organ: the ellipsoid of ``examples/palpation.toml`` (120 x 80 x 60 mm, E = 5 kPa,
nu = 0.45, fixed on its lowest 4 mm, gravity, Backward Euler at h = 1/30 s) at ``divisions``
8 / 12 / 17 (3,072 / 10,368 / 29,478 tetrahedra). Palpation: a sphere (R = 10 mm) 1 mm
above (2 mm and 3 mm off the crest: centred, it balances on a saddle of the discrete problem),
down 7 mm at 20 mm/s, then 15 mm sideways at 30 mm/s, friction 0.2, dhat 0.1 mm.
Grasp: two capsule jaws (R = 4 mm) close 3 mm each on the organ's end (x = 52 mm) from above
and below in 0.2 s, then lift 10 mm at 30 mm/s, friction 0.5.

Per run: Newton iterations per contact step (mean, max, first touching step), halved steps,
the time per step with the instrument against the organ alone (the same steps), steps per
second and the real-time factor (h / wall time per step), the haptic linearisation's time
(``Simulation.instrument_linearization`` after each step), factorisations / back-solves / CG
iterations per step, and the split of a step (contact candidates + barrier, CCD, the rest);
accuracy: the largest position difference / the largest displacement and the instrument's
force difference / its force, against the 100x tighter run. Threads: each count in its own
process (set before NumPy loads).

    python3 benchmarks/palpation.py                          # 3e3, 1e4, 3e4; 1 and 2 threads
    python3 benchmarks/palpation.py --divisions 12 --threads 1
    PALPATION_CRITERION=auto python3 benchmarks/palpation.py   # the physical criterion
    PALPATION_FRICTION_ITERATIONS=1 python3 benchmarks/palpation.py
    PALPATION_GRADIENT_TOLERANCE=1e-5 python3 benchmarks/palpation.py   # a looser Newton
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

HERE = Path(__file__).resolve().parent
FRICTION_ITERATIONS = int(os.environ.get("PALPATION_FRICTION_ITERATIONS", "2"))
#: Newton's stopping criterion ("relative", the default; "auto": the experimental physical one
#: in contact steps), from the environment so the per-thread children see it
CRITERION = os.environ.get("PALPATION_CRITERION", "relative")
#: Newton's relative gradient tolerance (empty: the default)
GRADIENT_TOLERANCE = os.environ.get("PALPATION_GRADIENT_TOLERANCE", "")


def organ(divisions: int, newton=None):
    import numpy as np

    import tissuesim as ts

    mesh = ts.ellipsoid((0.0, 0.0, 0.03), (0.06, 0.04, 0.03), divisions)
    material = ts.make_material("neo_hookean", youngs_modulus=5e3, poisson_ratio=0.45)
    sim = ts.Simulation(
        integrator="backward_euler", time_step=1 / 30, gravity=(0, 0, -9.81), newton=newton
    )
    sim.add_body("organ", mesh, material, density=1000.0)
    sim.fix("organ", np.flatnonzero(mesh.points[:, 2] < 0.004), name="table")
    return sim


def palpation(divisions: int, newton=None):
    from tissuesim.contact.obstacles import sphere

    sim = organ(divisions, newton)
    sim.set_contact(dhat=1e-4, friction=0.2, friction_iterations=FRICTION_ITERATIONS)
    sim.add_obstacle(
        "probe",
        sphere((0.002, 0.003, 0.071), 0.01, refinement=4),
        translation=lambda t: (0.03 * max(t - 0.35, 0.0), 0.0, -0.02 * min(t, 0.35)),
    )
    return sim, "probe", 26


def grasp(divisions: int, newton=None):
    from tissuesim.contact.obstacles import capsule

    sim = organ(divisions, newton)
    sim.set_contact(dhat=1e-4, friction=0.5, friction_iterations=FRICTION_ITERATIONS)
    x, r = 0.052, 0.004
    for name, z, sign in (("upper", 0.045 + r + 5e-4, -1.0), ("lower", 0.015 - r - 5e-4, 1.0)):
        sim.add_obstacle(
            name,
            capsule((x, -0.03, z), (x, 0.03, z), r),
            translation=lambda t, s=sign: (
                0.0,
                0.0,
                s * 0.003 * min(t / 0.2, 1.0) + 0.03 * max(t - 0.2, 0.0),
            ),
        )
    return sim, "upper", 16


SCENES = {"palpation": palpation, "grasp": grasp}


def run(scene: str, divisions: int, tight: bool) -> dict:
    import numpy as np

    import tissuesim as ts

    newton = ts.NewtonOptions(criterion=CRITERION)
    if GRADIENT_TOLERANCE:
        newton = replace(newton, gradient_tolerance=float(GRADIENT_TOLERANCE))
    newton = newton.tighter(100.0) if tight else newton
    sim, instrument, steps = SCENES[scene](divisions, newton)
    alone = organ(divisions)
    rows = []
    for _ in range(steps):
        start = time.perf_counter()
        record = sim.step()
        wall = time.perf_counter() - start
        start = time.perf_counter()
        sim.instrument_linearization(instrument)  # what a haptic loop asks between steps
        linearization = time.perf_counter() - start
        start = time.perf_counter()
        alone_record = alone.step()
        wall_alone = time.perf_counter() - start
        contact = record.extra["contact"]
        linear = record.extra.get("linear", {})
        rows.append(
            {
                "wall_s": wall,
                "wall_alone_s": wall_alone,
                "linearization_s": linearization,
                "iterations": record.newton_iterations,
                "iterations_alone": alone_record.newton_iterations,
                "substeps": record.substeps,
                "active_pairs": contact["active_pairs"],
                "candidates_and_barrier_s": contact["candidates_and_barrier_s"],
                "ccd_s": contact["ccd_s"],
                "force": np.asarray(record.extra["forces"][instrument]).tolist(),
                "linear": linear,
                "linear_alone": alone_record.extra.get("linear", {}),
            }
        )
    rest = sim.system.bodies[0].rest_config()
    return {
        "scene": scene,
        "tetrahedra": int(sim.bodies["organ"].mesh.n_cells),
        "threads": int(os.environ.get("OMP_NUM_THREADS", "0")),
        "tight": tight,
        "linear_solver": sim.linear_solver_info()["name"],
        "rows": rows,
        "x": sim.state.x.tolist(),
        "largest_displacement": float(
            np.max(np.linalg.norm((sim.state.x - rest).reshape(-1, 3), axis=1))
        ),
    }


def summarise(default: dict, tight: dict | None) -> dict:
    import numpy as np

    rows = default["rows"]
    touching = [r for r in rows if r["active_pairs"]]
    first = touching[0] if touching else None
    walls = [r["wall_s"] for r in touching[1:]] or [0.0]  # the first touch: reported apart
    alone = [r["wall_alone_s"] for r in rows[1:]]
    lin = [r["linear"] for r in touching]
    out = {
        "scene": default["scene"],
        "tetrahedra": default["tetrahedra"],
        "threads": default["threads"],
        "solver": default["linear_solver"],
        "contact_steps": len(touching),
        "iterations_mean": statistics.mean(r["iterations"] for r in touching) if touching else 0,
        "iterations_max": max((r["iterations"] for r in touching), default=0),
        "iterations_first_touch": first["iterations"] if first else 0,
        "halved_steps": sum(r["substeps"] > 1 for r in rows),
        "step_s_median": statistics.median(walls),
        "alone_step_s_median": statistics.median(alone),
        "ratio": statistics.median(walls) / statistics.median(alone),
        "steps_per_s": 1.0 / statistics.median(walls),
        "linearization_ms_median": 1e3
        * statistics.median(r["linearization_s"] for r in touching[1:] or rows),
        "real_time_factor": (1 / 30) / statistics.median(walls),
        "alone_iterations_mean": statistics.mean(r["iterations_alone"] for r in rows[1:]),
        "factorizations_per_step": statistics.mean(x.get("factorizations", 0) for x in lin),
        "back_solves_per_step": statistics.mean(x.get("back_solves", 0) for x in lin),
        "cg_per_step": statistics.mean(x.get("cg_iterations", 0) for x in lin),
        "alone_factorizations_per_step": statistics.mean(
            r["linear_alone"].get("factorizations", 0) for r in rows[1:]
        ),
        "candidates_barrier_share": sum(r["candidates_and_barrier_s"] for r in touching)
        / max(sum(r["wall_s"] for r in touching), 1e-12),
        "ccd_share": sum(r["ccd_s"] for r in touching)
        / max(sum(r["wall_s"] for r in touching), 1e-12),
    }
    if tight is not None:
        dx = np.asarray(default["x"]) - np.asarray(tight["x"])
        err = float(np.max(np.linalg.norm(dx.reshape(-1, 3), axis=1)))
        out["position_error"] = err / tight["largest_displacement"]
        f_errors = []
        for a, b in zip(rows, tight["rows"], strict=True):
            fb = np.linalg.norm(b["force"])
            if fb > 0.01 * max(np.linalg.norm(r["force"]) for r in tight["rows"]):
                f_errors.append(np.linalg.norm(np.subtract(a["force"], b["force"])) / fb)
        out["force_error_max"] = max(f_errors, default=0.0)
        out["tight_iterations_mean"] = statistics.mean(
            r["iterations"] for r in tight["rows"] if r["active_pairs"]
        )
    return out


def child(args) -> None:
    results = []
    for divisions in args.divisions:
        for scene in args.scenes:
            default = run(scene, divisions, False)
            tight = run(scene, divisions, True) if args.accuracy else None
            results.append(summarise(default, tight))
            print(json.dumps(results[-1]), file=sys.stderr, flush=True)
    print(json.dumps(results))


COLUMNS = [
    ("scene", "scene", "{}"),
    ("tetrahedra", "tetrahedra", "{:,}"),
    ("threads", "threads", "{}"),
    ("iterations_mean", "its / contact step", "{:.2f}"),
    ("iterations_first_touch", "first touch", "{}"),
    ("iterations_max", "max", "{}"),
    ("halved_steps", "halved", "{}"),
    ("step_s_median", "s / step", "{:.3f}"),
    ("alone_step_s_median", "s / step alone", "{:.3f}"),
    ("ratio", "ratio", "{:.2f}"),
    ("steps_per_s", "steps / s", "{:.1f}"),
    ("real_time_factor", "real-time factor", "{:.2f}"),
    ("linearization_ms_median", "haptic linearisation ms", "{:.1f}"),
    ("factorizations_per_step", "factorisations / step", "{:.2f}"),
    ("back_solves_per_step", "back-solves / step", "{:.1f}"),
    ("cg_per_step", "CG / step", "{:.1f}"),
    ("candidates_barrier_share", "candidates + barrier", "{:.0%}"),
    ("ccd_share", "CCD", "{:.0%}"),
    ("position_error", "position error", "{:.1e}"),
    ("force_error_max", "force error", "{:.2%}"),
]


def table(results: list[dict]) -> str:
    lines = [
        "| " + " | ".join(title for _, title, _ in COLUMNS) + " |",
        "|" + " --- |" * len(COLUMNS),
    ]
    for r in results:
        cells = [fmt.format(r[key]) if key in r else "" for key, _, fmt in COLUMNS]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--divisions", type=int, nargs="+", default=[8, 12, 17])
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    parser.add_argument("--no-accuracy", dest="accuracy", action="store_false")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--out", default=str(HERE / "results" / "palpation_last_run.md"))
    args = parser.parse_args()
    if args.child:
        child(args)
        return
    results = []
    for threads in args.threads:
        env = dict(os.environ)
        for key in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            env[key] = str(threads)
        env["NUMBA_NUM_THREADS"] = str(threads)
        command = [sys.executable, __file__, "--child", "--divisions"]
        command += [str(d) for d in args.divisions] + ["--scenes", *args.scenes]
        if not args.accuracy or threads != args.threads[0]:
            command.append("--no-accuracy")
        done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
        if done.returncode != 0:
            sys.exit(done.stderr)
        results += json.loads(done.stdout.strip().splitlines()[-1])
    text = (
        "# Palpation and grasp at the default settings (benchmarks/palpation.py)\n\n"
        f"`python3 {' '.join(['benchmarks/palpation.py', *sys.argv[1:]])}`; medians over the "
        "contact steps after the first touch; 'alone': the same organ without the instrument, "
        "stepped in the same run; errors against the same run with tolerances 100x tighter "
        "(first thread count only).\n\n" + table(results) + "\n"
    )
    Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
