"""Where contact's collision sets and CCD sweeps take their candidate pairs from.

A step's candidate set (``contact/barrier/candidates.py``) is built with the surface primitives'
boxes inflated by dhat / 2 + a margin and reused by every evaluation (and CCD sweep) whose vertices
stay within the margin; a vertex that leaves it rebuilds the set. A larger margin means fewer
rebuilds but more pairs, and every collision-set build and narrow phase pays for each pair.
A CCD sweep can instead take the pairs of ipctk's broad phase over its own boxes.

Variants, each scene run in all of them in the same process (alternating, a fresh simulation
per run):
- ``motion, set``: the earlier defaults: margin 1.5 x the step's expected vertex motion (h v
  and the obstacles' move in the step), at least dhat, at most a quarter of the median
  surface edge; sweeps from the step's set;
- ``dhat, set``: margin dhat, sweeps from the step's set;
- ``dhat, default``: margin dhat, sweeps from the step's set unless it holds more than
  ``SWEEP_PAIRS_PER_VERTEX`` pairs per surface vertex (the defaults).

Scenes: ``cut organ`` (the organ of ``benchmarks/cut_cost.py`` on a table, 10,368
tetrahedra, cut through after 4 steps: its fresh cut faces 2 dhat apart over a whole section;
4 steps after the first one after the cut), ``palpation`` and ``grasp`` (``benchmarks/
palpation.py`` at 12 divisions, all their steps), the examples ``liver_instrument`` (30 steps),
``organs_rest_after_cut`` (40) and ``self_contact_fold`` (20), and ``pressed boxes``
(``benchmarks/contact_cost.py`` at 12 divisions, 3 steps).

Per scene and variant: the median over ``--repeats`` of the wall time of the timed steps, and
of the run's CCD and candidates (broad phase + collision sets) seconds; and the Newton
iterations of the first repeat (they may differ by a few between runs: ipctk's threads).

    python3 benchmarks/contact_candidates.py     # writes benchmarks/results/contact_candidates.md
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from tissuesim.contact.barrier import ccd_queries
from tissuesim.contact.barrier.candidates import StepCandidates
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut
from tissuesim.scene.loader import build_scene

HERE = Path(__file__).resolve().parent
EXAMPLES = HERE.parent / "src" / "tissuesim" / "examples"
sys.path.insert(0, str(HERE))


def cut_organ():
    from cut_cost import organ

    sim = organ(12, contact=True)
    for _ in range(4):
        sim.step()
    x = 0.011
    polygon = np.array([[x, -1, -1], [x, 1, -1], [x, 1, 1], [x, -1, 1]], dtype=float)
    sim.cut_body(PlanarCut(np.array([x, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), polygon))
    sim.step()  # the first step after the cut (not timed)
    return sim, 4


def palpation():
    from palpation import palpation as probe

    return probe(12)[0], 26


def grasp():
    from palpation import grasp as jaws

    return jaws(12)[0], 16


def pressed_boxes():
    from contact_cost import scene

    sim = scene(12, True)
    sim.step()
    return sim, 3


def example(name: str, steps: int):
    def make():
        path = EXAMPLES / f"{name}.toml"
        data = tomllib.loads(path.read_text())
        return build_scene(data, base_dir=path.parent, source=str(path)).simulation, steps

    return make


SCENES = {
    "cut organ": cut_organ,
    "palpation": palpation,
    "grasp": grasp,
    "liver_instrument": example("liver_instrument", 30),
    "organs_rest_after_cut": example("organs_rest_after_cut", 40),
    "self_contact_fold": example("self_contact_fold", 20),
    "pressed boxes": pressed_boxes,
}
DEFAULT_PAIRS = ccd_queries.SWEEP_PAIRS_PER_VERTEX
VARIANTS = {
    "motion, set": ("motion", float("inf")),
    "dhat, set": ("dhat", float("inf")),
    "dhat, default": ("dhat", DEFAULT_PAIRS),
}
_begin = StepCandidates.begin


def run(make, margin: str, pairs_per_vertex: float) -> dict:
    ccd_queries.SWEEP_PAIRS_PER_VERTEX = pairs_per_vertex
    sim, steps = make()
    contact = sim.system.contact
    if margin == "edge":
        E = contact.mesh.edges
        E = E[E.max(axis=1) < contact.n_deformable]
        edge = float(
            np.median(np.linalg.norm(contact.rest[E[:, 0]] - contact.rest[E[:, 1]], axis=1))
        )
        StepCandidates.begin = lambda self, m: _begin(self, max(self.dhat, 0.25 * edge))
    else:
        StepCandidates.begin = _begin
    wall, ccd, candidates, iterations = 0.0, 0.0, 0.0, 0
    for _ in range(steps):
        start = time.perf_counter()
        record = sim.step()
        wall += time.perf_counter() - start
        stats = record.extra["contact"]
        ccd += stats["ccd_s"]
        candidates += stats["candidates_s"]
        iterations += record.newton_iterations
    StepCandidates.begin = _begin
    ccd_queries.SWEEP_PAIRS_PER_VERTEX = DEFAULT_PAIRS
    return {"wall": wall, "ccd": ccd, "candidates": candidates, "iterations": iterations}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--only", nargs="*", default=list(SCENES))
    parser.add_argument("--out", default=str(HERE / "results" / "contact_candidates.md"))
    args = parser.parse_args()
    rows = []
    for name in args.only:
        got = {v: [] for v in VARIANTS}
        for _ in range(args.repeats):
            for v, (margin, pairs) in VARIANTS.items():
                got[v].append(run(SCENES[name], margin, pairs))
        cells = []
        for v in VARIANTS:
            med = {
                k: statistics.median(r[k] for r in got[v]) for k in ("wall", "ccd", "candidates")
            }
            cells.append(
                f"{med['wall']:.2f} ({med['ccd']:.2f} / {med['candidates']:.2f}), "
                f"{got[v][0]['iterations']}"
            )
        old = statistics.median(r["wall"] for r in got["motion, set"])
        new = statistics.median(r["wall"] for r in got["dhat, default"])
        rows.append(f"| {name} | {' | '.join(cells)} | {old / new:.2f} |")
        print(rows[-1], flush=True)
    head = (
        "# Contact candidate sets (benchmarks/contact_candidates.py)\n\n"
        f"`python3 benchmarks/contact_candidates.py`; per scene and variant: seconds of the "
        f"timed steps (of which CCD / candidates), medians of {args.repeats} repeats (a fresh "
        "simulation each, the variants alternating), and the Newton iterations of the first "
        "repeat; this machine, one process. The last column: motion, set (the earlier "
        "defaults) over dhat, default (the speed-up of the defaults).\n\n"
        "| scene | motion, set | dhat, set | dhat, default | speed-up |\n"
        "| --- | --- | --- | --- | --- |\n"
    )
    Path(args.out).write_text(head + "\n".join(rows) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
