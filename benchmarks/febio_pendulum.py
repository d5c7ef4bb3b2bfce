"""Why FEBio's ``ri09`` (a rigid quad4 shell swinging about a given centre of mass under a
body force) ends 32 % off FEBio's recorded norm (issue 42): the model's own pendulum, the
exact one, and FEBio's rigid-body scheme in one degree of freedom.

ri09: a 1 x 1 plate (x in [0, 1], thickness 0.01, density 1) held at its given centre of mass
(0, 0, 0), its rotations free, under a body force of 9.81 along z; released horizontal, it
swings through 180 degrees and back. At t = 2 s it is 0.07 s past its return, so its
rotation (FEBio's norm over the three rotation DOFs) is a few hundredths of a radian and
sensitive to everything that shifts the period. This script prints

- tissuesim's run (``--suite DIR``: a local TestSuite checkout; its decks are not shipped) at
  h = 0.01 and h = 0.0025 (converged in h: the difference is not the time step);
- the pendulum theta'' = -(g / k^2)(d cos theta + e sin theta) integrated to 1e-12 (SciPy),
  d = 0.5, k^2 = 1/3 + t^2 / 12: e = 0 puts the mass on the plate's nodes (FEBio's rigid
  shell: ``FERigidShellDomain`` integrates its mass, moment of inertia and body force at the
  nodes' positions r0), e = t / 2 puts it through the thickness behind the nodes (tissuesim's
  shell is a solid from X to X - D);
- FEBio's rigid-body Newmark (``FERigidSolverNew``: the trapezoidal rule on the Cayley vector
  2 tan(dtheta / 2) of each step's rotation) with h = 0.01, solved exactly per step, once
  from the initial angular acceleration M / J and once from FEBio's: ``InitAccelerations``
  solves with ``RigidMassMatrix``, whose rotational block at t = 0 is still J / (beta h^2)
  (only the translational one is set to the mass there), so the body starts with an angular
  acceleration beta h^2 = 2.5e-5 times the true one: in effect at rest.

    python benchmarks/febio_pendulum.py [--suite ~/TestSuite]
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import tempfile
from pathlib import Path

from scipy.integrate import solve_ivp
from scipy.optimize import brentq

HERE = Path(__file__).resolve().parent
#: FEBio's recorded solution_norm of ri09 (TestSuite code/linuxGoldStandards.py)
FEBIO_NORM = 0.0280778026331
G, ARM, THICKNESS, END = 9.81, 0.5, 0.01, 2.0
K2 = 1.0 / 3.0 + THICKNESS**2 / 12.0  # the plate's radius of gyration squared about its edge

CHILD = r"""
import sys, warnings
import numpy as np
sys.path.insert(0, sys.argv[2])
import febio_suite as fs
from tissuesim.febio import load_febio, read_feb
warnings.simplefilter("ignore")
model, scene = read_feb(sys.argv[1]), load_febio(sys.argv[1], febio_solver=True)
sim, turns = scene.simulation, {}
for _ in range(scene.run["steps"]):
    sim.step(); fs.follow_rotations(sim, turns)
print(fs.solution_norm(model, sim, np, turns)["norm"])
"""


def exact(offset: float) -> float:
    """|theta(END)| of the continuous pendulum with its mass `offset` off the nodes' plane."""
    run = solve_ivp(
        lambda t, y: [y[1], -(G / K2) * (ARM * math.cos(y[0]) + offset * math.sin(y[0]))],
        (0.0, END),
        [0.0, 0.0],
        rtol=1e-12,
        atol=1e-12,
    )
    return abs(float(run.y[0, -1]))


def febio_scheme(h: float, start_at_rest: bool) -> float:
    """|theta(END)| by FEBio's rigid Newmark (beta 1/4, gamma 1/2) on the Cayley vector."""
    theta, w = 0.0, 0.0
    alpha = 0.0 if start_at_rest else -G * ARM / K2
    for _ in range(round(END / h)):

        def residual(step: float, theta=theta, w=w, alpha=alpha) -> float:
            cayley = 2.0 * math.tan(step / 2.0)
            return K2 * (4 * cayley / h**2 - 4 * w / h - alpha) + G * ARM * math.cos(theta + step)

        step = brentq(residual, -0.5, 0.5, xtol=1e-15)
        cayley = 2.0 * math.tan(step / 2.0)
        w, alpha = 2 * cayley / h - w, 4 * cayley / h**2 - 4 * w / h - alpha
        theta += step
    return abs(theta)


def ours(suite: Path, steps: int) -> float:
    """tissuesim's ri09 (FEBio's solver) with `steps` steps to t = 2 s."""
    text = (suite / "Verify" / "ri09.feb").read_text(encoding="latin-1")
    text = text.replace("<time_steps>200</time_steps>", f"<time_steps>{steps}</time_steps>")
    text = text.replace("<step_size>0.01</step_size>", f"<step_size>{END / steps:g}</step_size>")
    with tempfile.TemporaryDirectory() as tmp:
        deck = Path(tmp) / "ri09.feb"
        deck.write_text(text, encoding="latin-1")
        out = subprocess.run(
            [sys.executable, "-c", CHILD, str(deck), str(HERE)],
            capture_output=True,
            text=True,
            check=True,
        )
    return float(out.stdout.split()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, help="a local febiosoftware/TestSuite checkout")
    args = parser.parse_args(argv)
    rows = [("FEBio's record", FEBIO_NORM)]
    if args.suite is not None:
        rows += [(f"tissuesim, h = {END / n:g}", ours(args.suite, n)) for n in (200, 800)]
    rows += [
        ("exact, mass through the thickness behind the nodes (e = t/2)", exact(THICKNESS / 2)),
        ("exact, mass on the nodes (e = 0)", exact(0.0)),
        ("FEBio's scheme, h = 0.01, from a0 = M / J", febio_scheme(0.01, False)),
        ("FEBio's scheme, h = 0.01, from rest (FEBio's a0)", febio_scheme(0.01, True)),
    ]
    print("| ri09 at t = 2 s | rotation (rad) | against FEBio's record |")
    print("| --- | --- | --- |")
    for name, value in rows:
        print(f"| {name} | {value:.5f} | {value / FEBIO_NORM - 1:+.3f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
