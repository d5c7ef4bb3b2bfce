"""What a cut event costs on an organ: the virtual node cut (topology, fractions, duplicated
nodes), the body's rebuild and the next step's new sparsity analysis and factorisation, against
an ordinary implicit step of the same organ.

The organ of ``benchmarks/palpation.py`` (ellipsoid 120 x 80 x 60 mm, E = 5 kPa, nu = 0.45,
fixed on its lowest 4 mm, gravity, Backward Euler at h = 1/30 s) at ``--divisions`` (12: 10,368
tetrahedra), cut by a plane across it (x = 11 mm, through the whole body: two pieces) after a
few steps. Per repeat (a fresh simulation each): the median of the steps before the cut, the
cut itself (``Simulation.cut_body``), the rebuild of the system it triggers (timed on its own:
the cut body's kinematics and sparsity pattern, and with contact its contact surface), the
first step after it (which re-analyses the pattern) and the median of the steps after; the cut
event's cost is the cut and the rebuild plus the first step's excess over the later ones, and
(cut + rebuild) / step the fixed part alone (with contact the first step's excess is Newton's:
the fresh faces pressed together take more iterations). Medians over ``--repeats``.

    python3 benchmarks/cut_cost.py                   # 10,368 tetrahedra, 3 repeats
    python3 benchmarks/cut_cost.py --divisions 8 12 17
    python3 benchmarks/cut_cost.py --contact --out benchmarks/results/cut_cost_contact.md

``--second``: then a second cut, the plane y = 3 mm across the first (the cells along the
line where they cross are split into four parts), timed the same way, with the number of
cells both cuts cross.

    python3 benchmarks/cut_cost.py --second --out benchmarks/results/cut_cost_second.md
    python3 benchmarks/cut_cost.py --second --contact \
        --out benchmarks/results/cut_cost_second_contact.md
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import tissuesim as ts
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

HERE = Path(__file__).resolve().parent


def organ(divisions: int, contact: bool = False) -> ts.Simulation:
    """The organ; with ``contact``, on a table (a plane obstacle just under it, contact on:
    the cut then also rebuilds the organ's contact surface)."""
    mesh = ts.ellipsoid((0.0, 0.0, 0.03), (0.06, 0.04, 0.03), divisions)
    material = ts.make_material("neo_hookean", youngs_modulus=5e3, poisson_ratio=0.45)
    sim = ts.Simulation(integrator="backward_euler", time_step=1 / 30, gravity=(0, 0, -9.81))
    sim.add_body("organ", mesh, material, density=1000.0)
    sim.fix(np.flatnonzero(mesh.points[:, 2] < 0.004), body="organ", name="support")
    if contact:
        from tissuesim.contact.obstacles import plane

        sim.set_contact(dhat=2e-4)
        sim.add_obstacle("table", plane((0.0, 0.0, -5e-4), (0.0, 0.0, 1.0), 0.3))
    return sim


def plane_cut(point: tuple, normal: tuple) -> PlanarCut:
    """The plane through ``point`` with ``normal`` (along an axis) across the whole organ."""
    p, n = np.array(point, dtype=float), np.array(normal, dtype=float)
    axis = int(np.argmax(np.abs(n)))
    corners = []
    for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        c = p.copy()
        u, w = [i for i in range(3) if i != axis]
        c[u], c[w] = a, b
        corners.append(c)
    return PlanarCut(p, n, np.array(corners))


def timed_steps(sim: ts.Simulation, n: int) -> list[float]:
    """The wall times (s) of ``n`` steps of ``sim``."""
    walls = []
    for _ in range(n):
        start = time.perf_counter()
        sim.step()
        walls.append(time.perf_counter() - start)
    return walls


def once(
    divisions: int, before: int = 4, after: int = 4, contact: bool = False, second: bool = False
) -> dict:
    sim = organ(divisions, contact)
    walls = timed_steps(sim, before)
    blade = plane_cut((0.011, 0.0, 0.0), (1.0, 0.0, 0.0))
    if second:  # the first cut, and steps after it, untimed: the second is the event
        sim.cut_body(blade, body="organ")
        walls = timed_steps(sim, before)
        blade = plane_cut((0.0, 0.003, 0.0), (0.0, 1.0, 0.0))
    start = time.perf_counter()
    report = sim.cut_body(blade, body="organ", name="second" if second else "cut")
    cut_s = time.perf_counter() - start
    start = time.perf_counter()
    _ = sim.system  # the cut body's rebuild: kinematics, sparsity pattern, contact surface
    rebuild_s = time.perf_counter() - start
    after_walls = timed_steps(sim, after)
    step_after = statistics.median(after_walls[1:])
    vn = sim.bodies["organ"].cut_state.vn
    meet = 0 if vn.extra is None else len(np.unique(vn.parent[vn.extra.copy]))
    return {
        "cells_both": meet,
        "tetrahedra": int(organ(divisions).bodies["organ"].mesh.n_cells),
        "cells_cut": report["cells_cut"],
        "pieces": report["pieces"],
        "step_s": statistics.median(walls[1:]),
        "cut_s": cut_s,
        "rebuild_s": rebuild_s,
        "first_step_after_s": after_walls[0],
        "step_after_s": step_after,
        "event_s": cut_s + rebuild_s + max(after_walls[0] - step_after, 0.0),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--divisions", type=int, nargs="+", default=[12])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--contact", action="store_true", help="the organ on a table, contact on")
    parser.add_argument("--second", action="store_true", help="time a second cut across it")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "cut_cost.md")
    args = parser.parse_args()
    lines = [
        "# Cost of a cut event (benchmarks/cut_cost.py)",
        "",
        f"`python3 benchmarks/cut_cost.py --divisions {' '.join(map(str, args.divisions))}"
        f"{' --contact' if args.contact else ''}{' --second' if args.second else ''}`; "
        f"medians of {args.repeats} repeats, each a fresh simulation; this machine, one process.",
        "",
        "| tetrahedra | cells cut | cells both cuts cross | pieces | step (s) | cut (s) "
        "| rebuild (s) | first step after (s) | step after (s) | cut event (s) | event / step "
        "| (cut + rebuild) / step |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for divisions in args.divisions:
        runs = [
            once(divisions, contact=args.contact, second=args.second) for _ in range(args.repeats)
        ]
        med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
        lines.append(
            f"| {med['tetrahedra']:,} | {med['cells_cut']} | {med['cells_both']} | {med['pieces']} "
            f"| {med['step_s']:.3f} | {med['cut_s']:.3f} | {med['rebuild_s']:.3f} "
            f"| {med['first_step_after_s']:.3f} | {med['step_after_s']:.3f} | {med['event_s']:.3f} "
            f"| {med['event_s'] / med['step_s']:.2f} "
            f"| {(med['cut_s'] + med['rebuild_s']) / med['step_s']:.2f} |"
        )
        print(lines[-1], flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
