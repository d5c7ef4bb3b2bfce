"""A haptic device loop at 1 kHz against an organ stepped at 30 Hz (issue 40), and the example
of how to write one: ``Simulation.haptic_contact(name)`` after each step gives the step's
contact problem; a device thread calls its ``force(d)`` for the instrument's displacement d
since the step, every millisecond, while the main thread takes the next step.

Part 1, the re-solve alone (one thread, nothing else running): the palpation of
``benchmarks/palpation.py`` (probe pressing 20 mm/s, then stroking 30 mm/s, friction 0.2) in
contact mode "interactive"; after each step with contact, ``force(d)`` for 33 displacements
along the probe's path to the next step (one per device millisecond); its time (median, 99th
percentile), and its force at the next step's displacement against that step's reported force
(a full step to the same place).

Part 2, the loop: a device thread at 1 kHz and the main thread stepping as fast as it can,
the probe driven to the device's place at each step's start (``drive_obstacle``). The
simulated device follows the same path at the pace the simulation keeps (during a step it
moves through the path's next h of time over that step's wall time, as a hand does that the
rendered force slows): a device on the wall clock would run ahead of a simulation slower
than real time and drive the probe centimetres in a step. Reported: the forces the device
rendered, the loop's achieved rate and its late ticks. Writes
``results/haptic_loop_forces.csv`` (device time s, force N) with part 2's forces.

    python3 benchmarks/haptic_loop.py                 # 1e4 tetrahedra
    python3 benchmarks/haptic_loop.py --divisions 8   # 3e3
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import threading
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def path(t: float):
    """The probe's translation at time t (m): palpation.py's press then stroke."""
    return (0.03 * max(t - 0.35, 0.0), 0.0, -0.02 * min(t, 0.35))


def scene(divisions: int):
    from palpation import organ

    import tissuesim as ts
    from tissuesim.contact.obstacles import sphere

    sim = organ(divisions, ts.NewtonOptions())
    sim.set_contact(dhat=1e-4, friction=0.2, mode="interactive")
    sim.add_obstacle("probe", sphere((0.002, 0.003, 0.071), 0.01, refinement=4))
    return sim


def part1(divisions: int, steps: int = 26) -> dict:
    import numpy as np

    sim = scene(divisions)
    h = sim.time_step
    times, errors = [], []
    haptic = None
    for k in range(steps):
        target = np.array(path((k + 1) * h))
        if haptic is not None:
            here = np.array(path(k * h))
            for j in range(1, 34):
                d = np.array(path(k * h + j * 1e-3)) - here
                haptic.force(d)
                times.append(haptic.last_solve_s)
            predicted = haptic.force(target - here)
        sim.drive_obstacle("probe", translation=tuple(target))
        record = sim.step()
        reported = np.asarray(record.extra["forces"]["probe"])
        if haptic is not None and np.linalg.norm(reported) > 0.02:
            errors.append(float(np.linalg.norm(predicted - reported) / np.linalg.norm(reported)))
        try:
            haptic = sim.haptic_contact("probe")
        except Exception:  # a step that fell back to the barrier: no snapshot
            haptic = None
        if haptic is not None and not haptic.n_pairs:
            haptic = None
    times_ms = sorted(1e3 * t for t in times)
    return {
        "tetrahedra": int(sim.bodies["organ"].mesh.n_cells),
        "solves": len(times_ms),
        "median_ms": statistics.median(times_ms),
        "p99_ms": times_ms[int(0.99 * (len(times_ms) - 1))],
        "max_ms": times_ms[-1],
        "force_vs_step_median": statistics.median(errors) if errors else float("nan"),
        "force_vs_step_max": max(errors, default=float("nan")),
    }


def part2(divisions: int, seconds: float = 3.0) -> dict:
    import numpy as np

    sim = scene(divisions)
    h = sim.time_step
    # the device's clock: the simulated time of the step in progress, its wall start, the wall
    # time the last step took
    state = {"haptic": None, "step_place": np.zeros(3), "stop": False}
    state.update(t_sim=0.0, wall_start=time.perf_counter(), step_wall=0.05)
    rendered, late = [], 0
    start = time.perf_counter()

    def device_time() -> float:
        fraction = (time.perf_counter() - state["wall_start"]) / state["step_wall"]
        return state["t_sim"] + h * min(fraction, 1.0)

    def device():
        nonlocal late
        tick = 0
        while not state["stop"]:
            tick += 1
            due = start + tick * 1e-3
            now = time.perf_counter()
            if now < due:
                time.sleep(due - now)
            elif now - due > 1e-3:
                late += 1
            t = device_time()
            haptic = state["haptic"]  # one reference read: the snapshot of the last step
            if haptic is None:
                rendered.append((t, 0.0, 0.0, 0.0))
                continue
            f = haptic.force(np.array(path(t)) - state["step_place"])
            rendered.append((t, *(-f)))  # the device renders the force on the instrument

    thread = threading.Thread(target=device, daemon=True)
    thread.start()
    steps = 0
    while time.perf_counter() - start < seconds:
        place = np.array(path(sim.time + h))
        sim.drive_obstacle("probe", translation=tuple(place))
        state["t_sim"], state["wall_start"] = sim.time, time.perf_counter()
        sim.step()
        state["step_wall"] = max(time.perf_counter() - state["wall_start"], 1e-3)
        steps += 1
        try:
            haptic = sim.haptic_contact("probe")
        except Exception:
            haptic = None
        state["step_place"] = place
        state["haptic"] = haptic
    state["stop"] = True
    thread.join()
    wall = time.perf_counter() - start
    out = HERE / "results" / "haptic_loop_forces.csv"
    with open(out, "w") as f:
        f.write("device_time_s,force_x_N,force_y_N,force_z_N\n")
        for row in rendered:
            f.write(",".join(f"{v:.6g}" for v in row) + "\n")
    return {
        "steps_per_s": steps / wall,
        "loop_hz": len(rendered) / wall,
        "late_ticks": late,
        "ticks": len(rendered),
        "largest_force_N": float(np.max(np.linalg.norm(np.array(rendered)[:, 1:], axis=1))),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--divisions", type=int, default=12)
    parser.add_argument("--seconds", type=float, default=3.0)
    args = parser.parse_args()
    one = part1(args.divisions)
    two = part2(args.divisions, args.seconds)
    text = (
        "# Haptic loop (benchmarks/haptic_loop.py)\n\n"
        f"`python3 benchmarks/haptic_loop.py --divisions {args.divisions}`, one thread each.\n\n"
        f"Re-solve alone, {one['tetrahedra']:,} tetrahedra, {one['solves']} solves: median "
        f"{one['median_ms']:.3f} ms, 99th percentile {one['p99_ms']:.3f} ms, largest "
        f"{one['max_ms']:.3f} ms; its force at the next step's displacement against that "
        f"step's: median {one['force_vs_step_median']:.1%}, largest "
        f"{one['force_vs_step_max']:.1%}.\n\n"
        f"Loop: {two['loop_hz']:.0f} Hz achieved ({two['late_ticks']} of {two['ticks']} ticks "
        f"more than 1 ms late) beside {two['steps_per_s']:.1f} steps/s; largest force "
        f"rendered {two['largest_force_N']:.3f} N (results/haptic_loop_forces.csv).\n"
    )
    (HERE / "results" / f"haptic_loop_{one['tetrahedra']}.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
