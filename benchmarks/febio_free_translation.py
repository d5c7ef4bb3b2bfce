"""A FEBio model that leaves a rigid translation free (no condition holds that component on
any node): its answer is defined up to that translation, so FEBio's record holds wherever its
factorisation pinned it (the zero pivot it meets). Runs the model as ``febio_suite.py`` does
and gives tissuesim's solution norm as it ends, and with the translation shifted so that the
lowest or the highest face in that direction stays put (what a pivot on one of their nodes
gives a body that deforms homogeneously through it).

    python3 benchmarks/febio_free_translation.py --suite TestSuite --model ma57 [--febio-solver]
        [--gold linuxGoldStandards.py]

ma57 (a biaxial test of a 0.05-thick plate: x held on two faces, y on the other two, z on
none) gives FEBio's record with either face held at uz = 0.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from febio_suite import read_gold, solution_norm  # noqa: E402

from tissuesim.febio import load_febio, read_feb  # noqa: E402


class Shifted:
    """The simulation with every deformable body moved by ``shift`` (what solution_norm reads)."""

    def __init__(self, sim, shift: np.ndarray) -> None:
        self._sim, self._shift = sim, shift

    def __getattr__(self, name: str):
        return getattr(self._sim, name)

    def body_positions(self, name: str) -> np.ndarray:
        return self._sim.body_positions(name) + self._shift


def free_components(model) -> list[int]:
    """The components no displacement condition of the last step holds on any node."""
    held: set[int] = set()
    for _, comps, *_ in model.dirichlet:
        held |= {0, 1, 2} if comps is None else set(comps)
    return [k for k in range(3) if k not in held]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, required=True, help="TestSuite root or Verify")
    parser.add_argument("--model", default="ma57")
    parser.add_argument("--gold", type=Path, help="linuxGoldStandards.py (default: the suite's)")
    parser.add_argument("--febio-solver", action="store_true")
    args = parser.parse_args()
    root = args.suite
    verify = root / "Verify" if (root / "Verify").is_dir() else root
    gold_path = args.gold or root / "code" / "linuxGoldStandards.py"
    path = verify / f"{args.model}.feb"
    warnings.simplefilter("ignore")
    model = read_feb(path)
    scene = load_febio(path, febio_solver=args.febio_solver)
    sim = scene.simulation
    for _ in range(scene.run["steps"]):
        sim.step()
        if sim.finished:
            break
    free = free_components(model)
    gold = None
    if gold_path.is_file():
        record = read_gold(gold_path).get(args.model)
        gold = float(record[-1]) if record else None
    print(
        f"{args.model}: t = {sim.time:g}; components no condition holds: "
        f"{[('x', 'y', 'z')[k] for k in free] or 'none'}; FEBio's record {gold}"
    )

    def show(label: str, norm: float) -> None:
        error = f" ({norm / gold - 1:+.2e} against FEBio's)" if gold else ""
        print(f"  {label}: norm {norm:.10g}{error}")

    show("as tissuesim ends", solution_norm(model, sim, np)["norm"])
    u = {n: sim.body_positions(n) for n in sim.bodies}
    rest = np.concatenate([sim.bodies[n].mesh.points for n in sim.bodies])
    moved = np.concatenate([u[n] for n in sim.bodies]) - rest
    for k in free:
        for side, face in (("lowest", rest[:, k].min()), ("highest", rest[:, k].max())):
            on = np.isclose(rest[:, k], face, atol=1e-9 * np.ptp(rest))
            shift = np.zeros(3)
            shift[k] = -moved[on, k].mean()
            label = f"{'xyz'[k]} shifted by {shift[k]:+.3e}: the {side} face held"
            show(label, solution_norm(model, Shifted(sim, shift), np)["norm"])


if __name__ == "__main__":
    main()
