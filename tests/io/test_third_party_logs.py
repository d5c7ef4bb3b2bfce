"""Issue 41: third-party log lines (``[ipctk] [warning] ...``) reached the terminal between
tissuesim's own lines (stdout, where the JSON report goes). Once a simulation builds its
contact model, ipctk logs errors only."""

from __future__ import annotations

import subprocess
import sys

import pytest

pytest.importorskip("ipctk")

# CCD from two surfaces that already touch: ipctk warns "Initial distance 0 <= d_min=0"
TOUCHING = """
import numpy as np, ipctk
V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0.0], [0.2, 0.2, 0.5]], float)
E = np.array([[0, 1], [1, 2], [2, 0], [3, 4]], np.int32)
F = np.array([[0, 1, 2]], np.int32)
print(ipctk.compute_collision_free_stepsize(ipctk.CollisionMesh(V, E, F), V, V))
"""

SIMULATION = """
import tissuesim as ts
sim = ts.Simulation(integrator="quasistatic", time_step=0.1)
material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
sim.add_body("block", ts.box((0, 0, 0), (0.1, 0.05, 0.05), (2, 1, 1)), material)
sim.set_contact(dhat=1e-4)
sim.system  # builds the contact model
"""


def _output(code: str) -> str:
    """What the terminal shows: ipctk's logger writes to stdout."""
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip().splitlines()[-1] == "0.0"  # the step is refused either way
    return result.stdout + result.stderr


def test_ipctk_warnings_reach_the_terminal_without_tissuesim():
    assert "[ipctk] [warning]" in _output(TOUCHING)  # what the test below guards against


def test_ipctk_warnings_stay_off_the_terminal_once_contact_is_set_up():
    assert "[ipctk]" not in _output(SIMULATION + TOUCHING)


def test_quiet_ipctk_is_idempotent():
    from tissuesim.io.third_party_logs import quiet_ipctk

    quiet_ipctk()
    quiet_ipctk()
