"""The retraction benchmark (benchmarks/coupled_retraction.py) runs in quick mode and writes its
tables; its force curve rises while the grasper retracts. No timing is asserted."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_coupled_retraction_quick_mode(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks/coupled_retraction.py"),
            "--quick",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    data = json.loads((tmp_path / "coupled_retraction_quick.json").read_text())
    forces = [c["force"][2] for c in data["curve"]]
    assert len(forces) == 6
    assert all(b > a for a, b in zip(forces, forces[1:], strict=False))
    assert forces[0] > data["grasped_organ_weight_N"]  # the tissue holds the organ back
    assert all(c["newton_iterations"] >= 1 for c in data["curve"])
    assert "| t (s) |" in (tmp_path / "coupled_retraction_quick.md").read_text()
