"""FEBio's adaptive time steps (issue 42): how many steps a FEBio-style model takes with the
time-step controller (``time/adaptive.py``) against the fixed steps tissuesim took before.

Without arguments it runs a model of its own: the 8-hex block of
``tests/febio/models/uniaxial_neo_hookean.feb`` pulled to a stretch of 1.2 over 1 s, asked
for 1,000 steps of 0.001 s, with FEBio's time stepper (dtmin 0.001, dtmax 0.1, opt_iter 10),
once adaptive and once on the fixed steps; each run in its own process on one thread.

With ``--suite DIR`` (a local checkout of febiosoftware/TestSuite: its decks cannot be
shipped) it also runs ``ma05`` and ``mi35`` adaptively and compares their solution_norm with
FEBio's recorded value (``code/linuxGoldStandards.py``) and their step counts with FEBio's
(the recorded time steps); ``--fixed N`` adds N fixed steps of ma05 for the cost per step.

    python benchmarks/febio_adaptive.py
    python benchmarks/febio_adaptive.py --suite ~/TestSuite --fixed 200
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
BLOCK = ROOT / "tests" / "febio" / "models" / "uniaxial_neo_hookean.feb"
#: FEBio's recorded (time steps, solution_norm) from TestSuite code/linuxGoldStandards.py
FEBIO = {"ma05": (25, 0.004003999996), "mi35": (2, 6.91486650611)}

STEPPER = """<time_steps>1000</time_steps>
    <step_size>0.001</step_size>
    <time_stepper type="default">
      <dtmin>0.001</dtmin>
      <dtmax>0.1</dtmax>
      <max_retries>5</max_retries>
      <opt_iter>10</opt_iter>
    </time_stepper>"""

CHILD = r"""
import json, sys, time, warnings
import numpy as np
from tissuesim.febio import load_febio, read_feb
path, fixed = sys.argv[1], int(sys.argv[2])
start = time.perf_counter()
model = read_feb(path)
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    scene = load_febio(path)
sim = scene.simulation
if fixed:  # the fixed steps tissuesim took before: no controller, step_size steps
    sim.schedule.phases[0] = type(sim.schedule.phases[0])(
        sim.schedule.phases[0].steps, sim.schedule.phases[0].time_step,
        sim.schedule.phases[0].integrator)
    sim._controller = None
loaded = time.perf_counter()
n = 0
limit = fixed or scene.run["steps"]
while n < limit:
    sim.step()
    n += 1
    if sim.finished:
        break
stepped = time.perf_counter()
u = sim.body_positions("body") - model.nodes
free = np.ones(u.shape, dtype=bool)
for nodes, comps, _, _, window in model.dirichlet:
    if window is not None and not window[0] < sim.time <= window[1]:
        continue
    free[np.ix_(model.node_sets[nodes], range(3) if comps is None else comps)] = False
print(json.dumps({"steps": n, "end_time": sim.time, "norm": float(np.linalg.norm(u[free])),
                  "load_s": loaded - start, "steps_s": stepped - loaded,
                  "newton": sum(r.newton_iterations for r in sim.history)}))
"""


def run(path: Path, fixed: int = 0) -> dict:
    env = dict(os.environ)
    for key in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        env[key] = "1"
    out = subprocess.run(
        [sys.executable, "-c", CHILD, str(path), str(fixed)],
        capture_output=True, text=True, check=True, env=env,
    )  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, help="a local febiosoftware/TestSuite checkout")
    parser.add_argument("--fixed", type=int, default=0, help="fixed steps of ma05 to time")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        block = Path(tmp) / "block.feb"
        text = BLOCK.read_text().replace(
            "<time_steps>4</time_steps>\n    <step_size>0.25</step_size>", STEPPER
        )
        block.write_text(text)
        adaptive, fixed = run(block), run(block, fixed=1000)
        rows.append(("block (own), adaptive", adaptive, None))
        rows.append(("block (own), 1000 fixed steps", fixed, None))
    if args.suite is not None:
        for name in ("ma05", "mi35"):
            rows.append((f"{name}, adaptive", run(args.suite / "Verify" / f"{name}.feb"), name))
        if args.fixed:
            ma05 = args.suite / "Verify" / "ma05.feb"
            rows.append((f"ma05, {args.fixed} fixed steps", run(ma05, args.fixed), None))
    print("| model | steps | FEBio's steps | Newton its | end time | steps (s) | load (s) | "
          "solution norm | vs FEBio |")  # fmt: skip
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for label, r, name in rows:
        febio_steps, febio_norm = FEBIO.get(name, ("", None))
        diff = "" if febio_norm is None else f"{r['norm'] / febio_norm - 1:+.1e}"
        print(
            f"| {label} | {r['steps']} | {febio_steps} | {r['newton']} | {r['end_time']:.6g} | "
            f"{r['steps_s']:.2f} | {r['load_s']:.2f} | {r['norm']:.10g} | {diff} |"
        )


if __name__ == "__main__":
    main()
