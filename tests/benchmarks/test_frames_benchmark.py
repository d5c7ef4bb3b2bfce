"""The frames-vs-FEM cantilever benchmark (benchmarks/frames_cantilever.py) runs in quick mode,
writes its tables, and its frame tip error falls as frames are added; no timing is asserted."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _finite(row: dict, keys) -> None:
    for key in keys:
        assert isinstance(row[key], (int, float)) and math.isfinite(row[key]), (key, row)


def test_frames_cantilever_quick_mode(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks/frames_cantilever.py"),
            "--quick",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    data = json.loads((tmp_path / "frames_cantilever.json").read_text())

    static = data["static"]
    assert len(static["fem"]) >= 2
    for row in static["fem"]:
        _finite(row, ["tip_deflection", "solve_s", "error_vs_finest", "error_vs_richardson"])
        assert row["tip_deflection"] > 0 and row["solve_s"] > 0
    _finite(static["fem_reference"], ["finest_tip_deflection", "richardson_tip_deflection"])

    by_clamp: dict[str, dict[int, dict]] = {}
    for row in static["frames"]:
        _finite(
            row,
            [
                "tip_deflection",
                "error_vs_finest_fem",
                "error_vs_richardson",
                "solve_s",
                "frames_per_point",
                "dofs",
                "integration_points",
                "newton_iterations",
            ],
        )
        assert row["tip_deflection"] > 0 and row["solve_s"] > 0
        by_clamp.setdefault(row["clamp"], {})[row["frames"]] = row
    assert len(by_clamp) >= 2  # the fixed frame and the spring clamp
    for clamp, rows in by_clamp.items():
        errors = [rows[n]["error_vs_finest_fem"] for n in (2, 4, 8)]
        assert errors[0] > errors[1] > errors[2], (clamp, errors)

    freq = data["frequency"]
    assert math.isfinite(freq["euler_bernoulli_hz"]) and freq["euler_bernoulli_hz"] > 0
    for row in freq["fem_modal"] + freq["frames_modal"]:
        _finite(row, ["frequency_hz", "partner_frequency_hz"])
        assert row["frequency_hz"] > 0
    vibration = [r for r in freq["frames_free_vibration"] if "skipped" not in r]
    assert {r["integrator"] for r in vibration} == {"explicit", "backward_euler"}
    for row in vibration:
        _finite(row, ["frequency_hz", "rel_diff_vs_fem_finest", "time_step"])
    # free vibration agrees with the frames' own eigenfrequency (same discretisation)
    modal = {r["clamp"]: r["frequency_hz"] for r in freq["frames_modal"]}
    for row in vibration:
        assert abs(row["frequency_hz"] / modal[row["clamp"]] - 1) < 0.02, row
    _finite(freq["fem_free_vibration"], ["frequency_hz"])

    md = (tmp_path / "frames_cantilever.md").read_text()
    assert "| clamp | frames |" in md and "## First bending frequency" in md
