"""FEBio itself on the suite's models (issue 42): how close a FEBio build of today comes to the
results FEBio recorded, beside tissuesim's.

    python3 benchmarks/febio_reference.py --febio ~/febio/build/bin/febio4 --suite DIR \\
        --gold linuxGoldStandards.py --only 'co16|co37|dy03' \\
        [--tissuesim benchmarks/results/febio_suite_febio_solver.csv] [--timeout 300] \\
        [--write benchmarks/results/febio_reference.md]

Each model runs as the suite's own script runs it (``febio4 -i MODEL.feb -task=test
-silent``: the test task logs ``solution_norm``) in a folder of its own under ``--work``;
from its log: the last ``solution_norm``, the time steps, equilibrium iterations and stiffness
reformations, against the record (``code/linuxGoldStandards.py``: time steps, iterations,
right-hand sides, reformations, value). ``--config`` names FEBio's configuration file (its
default linear solver); a model whose stiffness is not symmetric needs a non-symmetric
solver: without MKL, FEBio's dense ``LU`` (``<default_linear_solver type="LU">``), tried
after ``skyline`` fails with "does not support the requested matrix format" when
``--lu-config`` is given. ``--tissuesim`` adds tissuesim's norm from a suite run's CSV
(``benchmarks/febio_suite.py``).

FEBio builds on this machine in about ten minutes without MKL (its skyline solver then):
``cmake SRC -G Ninja -DCMAKE_BUILD_TYPE=Release -DUSE_MKL=OFF
-DCMAKE_EXE_LINKER_FLAGS=-fopenmp -DCMAKE_SHARED_LINKER_FLAGS=-fopenmp`` and ``ninja
febio4`` (FECore/FSPath.cpp needs ``#include <cstring>`` with GCC 12).
"""

from __future__ import annotations

import argparse
import csv
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from febio_suite import read_gold  # noqa: E402

NORM = re.compile(r"Data = solution_norm\s*\n\s*0\s+(\S+)")
COUNTS = {
    "steps": re.compile(r"Number of time steps completed \.+ : (\d+)"),
    "iterations": re.compile(r"Total number of equilibrium iterations \.+ : (\d+)"),
    "reformations": re.compile(r"Total number of stiffness reformations \.+ : (\d+)"),
}
UNSYMMETRIC = "does not support the requested matrix"


def run_febio(febio: Path, deck: Path, work: Path, config: Path, timeout: float) -> dict:
    """One model in FEBio (the suite's command): its status, norm, counts and wall time."""
    work.mkdir(parents=True, exist_ok=True)
    local = work / deck.name
    shutil.copy(deck, local)
    log = work / (deck.stem + ".log")
    command = [str(febio), "-i", local.name, "-o", log.name, "-p", deck.stem + ".xplt",
               "-task=test", "-silent", "-cnf", str(config)]  # fmt: skip
    start = time.perf_counter()
    try:
        subprocess.run(command, cwd=work, capture_output=True, timeout=timeout, check=False)
        status = "ran"
    except subprocess.TimeoutExpired:
        status = "timeout"
    wall = time.perf_counter() - start
    text = log.read_text(errors="replace") if log.exists() else ""
    norms = NORM.findall(text)
    out = {"status": status, "wall_s": wall, "norm": float(norms[-1]) if norms else None}
    for key, pattern in COUNTS.items():
        found = pattern.findall(text)
        out[key] = int(found[-1]) if found else None
    if status == "ran" and "N O R M A L   T E R M I N A T I O N" not in text:
        out["status"] = "unsymmetric" if UNSYMMETRIC in text else "error"
    return out


def relative(value, reference) -> float | None:
    if value is None or reference is None:
        return None
    return (value - reference) / abs(reference) if reference else value - reference


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--febio", type=Path, required=True, help="the febio4 executable")
    parser.add_argument("--suite", type=Path, required=True, help="folder of the Verify decks")
    parser.add_argument("--gold", type=Path, required=True, help="linuxGoldStandards.py")
    parser.add_argument("--only", required=True, help="model names, '|'-separated")
    parser.add_argument("--config", type=Path, help="FEBio's configuration (default: beside it)")
    parser.add_argument("--lu-config", type=Path, help="a configuration with the LU solver")
    parser.add_argument("--tissuesim", type=Path, help="a febio_suite.py CSV to compare")
    parser.add_argument("--work", type=Path, default=Path("febio_reference_runs"))
    parser.add_argument("--timeout", type=float, default=300.0)
    parser.add_argument("--write", type=Path, help="write the markdown table here")
    args = parser.parse_args()
    config = args.config or args.febio.parent / "febio.xml"
    gold = read_gold(args.gold)
    ours = {}
    if args.tissuesim:
        with args.tissuesim.open() as f:
            ours = {row["model"]: row for row in csv.DictReader(f)}
    rows = []
    for name in args.only.split("|"):
        deck = args.suite / f"{name}.feb"
        result = run_febio(args.febio, deck, args.work / name, config, args.timeout)
        if result["status"] == "unsymmetric" and args.lu_config:
            result = run_febio(args.febio, deck, args.work / name, args.lu_config, args.timeout)
            result["solver"] = "LU"
        record = gold.get(name, [None] * 7)
        value = float(record[-1]) if record[-1] is not None else None
        mine = ours.get(name, {})
        tissuesim = float(mine["norm"]) if mine.get("norm") else None
        rows.append((name, result, record, value, tissuesim))
        print(name, result, value, tissuesim, flush=True)
    lines = [
        "| model | recorded norm | FEBio here | FEBio here vs record | tissuesim vs record | "
        "tissuesim vs FEBio here | steps (record / here) | iterations (record / here) | "
        "reformations (record / here) | FEBio here: solver, s |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]

    def fmt(x):
        return "" if x is None else f"{x:+.1e}"

    for name, r, record, value, tissuesim in rows:
        here = r["norm"] if r["status"] == "ran" else None
        lines.append(
            f"| {name} | {value if value is not None else ''} | "
            f"{here if here is not None else r['status']} | {fmt(relative(here, value))} | "
            f"{fmt(relative(tissuesim, value))} | {fmt(relative(tissuesim, here))} | "
            f"{record[1]} / {r['steps']} | {record[2]} / {r['iterations']} | "
            f"{record[4]} / {r['reformations']} | {r.get('solver', config.stem)}, "
            f"{r['wall_s']:.1f} |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    if args.write:
        args.write.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
