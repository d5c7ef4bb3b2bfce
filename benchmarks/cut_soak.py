"""Random cuts with contact on: does every step converge, does no surface ever pass through
another, and how many Newton iterations do the steps after the cuts take?

The organ of ``benchmarks/cut_cost.py`` at 6 divisions (1,296 tetrahedra: an ellipsoid
120 x 80 x 60 mm, E = 5 kPa, held on its lowest 4 mm, on a table; dhat 0.2 mm) takes two
steps, is cut, then takes 12 more (Backward Euler at h = 0.01 s). Two families, one seed each
case:

- ``through``: one to three oblique planes through about one point near its middle (2-8
  pieces falling onto each other and the table);
- ``thin``: two nearly parallel planes 0.1-3 dhat apart (a slab thinner than the cut faces'
  gap: ``contact/cut/thin_pieces.py``, or a crumb: ``mesh/cutting/crumbs.py``), in 4 of 10 cases a
  third across them.

Per case: the pieces, whether it failed (an error, or a step's exact intersection test), the
iterations of the first step after the cut and the largest of the later ones, any warning.

    python3 benchmarks/cut_soak.py --seeds 20     # writes benchmarks/results/cut_soak.md
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np
from cut_cost import organ

from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

HERE = Path(__file__).resolve().parent
DHAT = 2e-4  # the organ's (cut_cost.organ with contact)


def plane(point: np.ndarray, normal: np.ndarray) -> PlanarCut:
    """The plane through ``point`` with ``normal``, bounded far outside the organ."""
    n = normal / np.linalg.norm(normal)
    u = np.cross(n, [0.3, 0.1, 1.0])
    u /= np.linalg.norm(u)
    w = np.cross(n, u)
    corners = [point + 3 * (a * u + b * w) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return PlanarCut(point, n, np.array(corners))


def cuts(family: str, seed: int) -> list[PlanarCut]:
    rng = np.random.default_rng({"through": 0, "thin": 1000}[family] + seed)
    if family == "through":
        centre = np.array([0.0, 0.0, 0.03]) + rng.normal(0, [0.01, 0.008, 0.005])
        out = []
        for _ in range(rng.integers(1, 4)):
            n = rng.normal(size=3)
            out.append(plane(centre + rng.normal(0, 0.002, 3), n / np.linalg.norm(n)))
        return out
    gap = rng.uniform(0.1, 3.0) * DHAT
    third = rng.random() < 0.4
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    p = np.array([0.0, 0.0, 0.03]) + rng.normal(0, [0.015, 0.01, 0.006])
    n2 = n + rng.normal(0, 0.01, 3)
    out = [plane(p, n), plane(p + gap * n, n2 / np.linalg.norm(n2))]
    if third:
        out.append(plane(p, rng.normal(size=3)))
    return out


def run(family: str, seed: int) -> dict:
    sim = organ(6, contact=True)
    sim.time_step = 0.01
    its, status, pieces = [], "ok", -1
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            for _ in range(2):
                sim.step()
            for k, cut in enumerate(cuts(family, seed)):
                pieces = sim.cut_body(cut, body="organ", name=f"cut{k}")["pieces"]
            for _ in range(12):
                its.append(sim.step().newton_iterations)
                if sim.system.contact.intersecting(sim.state.x):
                    status = "intersecting"
                    break
        except Exception as error:  # a failed case is the benchmark's finding, not its end
            status = f"{type(error).__name__}: {str(error)[:80]}"
    messages = sorted({str(w.message)[:60] for w in caught})
    return {
        "pieces": pieces,
        "status": status,
        "first": its[0] if its else -1,
        "later": max(its[1:]) if len(its) > 1 else -1,
        "seconds": time.perf_counter() - start,
        "warnings": "; ".join(messages),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--out", type=Path, default=HERE / "results" / "cut_soak.md")
    args = parser.parse_args()
    lines = [
        "# Random cuts with contact (benchmarks/cut_soak.py)",
        "",
        f"`python3 benchmarks/cut_soak.py --seeds {args.seeds}`: the organ of cut_cost.py "
        "(1,296 tetrahedra, dhat 0.2 mm, h = 0.01 s) cut after 2 steps, then 12 steps.",
        "",
        "| family | seed | pieces | result | first step after (iterations) "
        "| largest later step | run (s) | warnings |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for family in ("through", "thin"):
        for seed in range(args.seeds):
            r = run(family, seed)
            print(family, seed, r, flush=True)
            lines.append(
                f"| {family} | {seed} | {r['pieces']} | {r['status']} | {r['first']} "
                f"| {r['later']} | {r['seconds']:.1f} | {r['warnings']} |"
            )
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
