"""An optimisation model's objective at given parameters, by tissuesim and (where a FEBio
executable is given) by FEBio itself: does the model tissuesim fits agree with FEBio's, and is
a fit that ends below FEBio's recorded objective lower by FEBio's own reckoning too?

    python3 benchmarks/febio_optimize_at.py --suite TestSuite --task op09 [--model oi09]
        [--found benchmarks/results/febio_optimize_differences.csv] [--febio febio4]
        [--symmetric] [--febio-solver]

Parameter sets: the task's start values, and the parameters a results CSV of
``febio_optimize.py`` found for the task (``--found``). For each, tissuesim's objective (one
run of the model, as the optimisation runs it) and FEBio's: the model with the parameters
written into its text (the element's one number, or a curve point's x or y) and a log file of
the quantity, run by ``febio4 -i``, its curve interpolated at the data's abscissae as FEBio's
data-fit does. FEBio's side takes data-fit objectives of a rigid body's force or moment
against time (op01, op03, op09). ``--symmetric``: the model's non-symmetric solver setting
made symmetric for FEBio (a FEBio built without MKL has no non-symmetric solver that factors
the models' first stiffness; the setting changes FEBio's iterations, not its equations).
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from tissuesim.febio.optimize import read_optimize
from tissuesim.febio.optimize.model import ModelBuilder
from tissuesim.febio.optimize.run import _Objective


def tissuesim_objective(builder: ModelBuilder, task, values: np.ndarray) -> float:
    r, _ = _Objective(task, builder, "differences")._residuals(values, False)
    return float(r @ r)


def _with_values(model: Path, builder: ModelBuilder, task, values: np.ndarray) -> str:
    """The model's text with each parameter's element set on its line."""
    lines = model.read_text().splitlines(keepends=True)
    for p, value in zip(task.parameters, values, strict=True):
        node, component = builder.targets[p.name]
        i = node.line - 1
        m = re.search(rf"(<{node.tag}\b[^>]*>)([^<]*)(</{node.tag}>)", lines[i])
        if m is None:
            raise SystemExit(f"{model}:{node.line}: <{node.tag}> is not on one line")
        text = repr(float(value))
        if component is not None:
            xy = m[2].split(",")
            xy[component] = text
            text = ",".join(xy)
        lines[i] = lines[i][: m.start(2)] + text + lines[i][m.end(2) :]
    return "".join(lines)


def febio_objective(febio: str, model: Path, builder, task, values, symmetric: bool) -> float:
    q, x = task.series
    if q.kind != "rigid" or x is not None:
        raise SystemExit("FEBio's side takes a rigid body's force or moment against time")
    text = _with_values(model, builder, task, values)
    materials = re.findall(r'<material\s+id="(\d+)"\s+name="([^"]*)"', text)
    ids = [i for i, name in materials if name == q.item]
    if not ids:
        raise SystemExit(f"no rigid material named {q.item!r} in {model}")
    if symmetric:
        text = text.replace("<symmetric_stiffness>non-symmetric</symmetric_stiffness>",
                            "<symmetric_stiffness>symmetric</symmetric_stiffness>")  # fmt: skip
    log = f'<logfile><rigid_body_data data="{q.variable}" file="q.txt">{ids[0]}' \
          "</rigid_body_data></logfile>"  # fmt: skip
    if "<Output>" in text:
        text = text.replace("<Output>", "<Output>" + log, 1)
    else:
        text = text.replace("</febio_spec>", f"<Output>{log}</Output></febio_spec>")
    with tempfile.TemporaryDirectory() as tmp:
        deck = Path(tmp) / model.name
        deck.write_text(text)
        subprocess.run([febio, "-i", deck.name, "-silent"], cwd=tmp, check=False,
                       capture_output=True)  # fmt: skip
        times, values_ = [], []
        now = None
        out = Path(tmp) / "q.txt"
        if not out.exists():
            raise SystemExit(f"FEBio wrote no log for {model} (see its .log)")
        for line in out.read_text().splitlines():
            if line.startswith("*Time"):
                now = float(line.split("=")[1])
            elif line[:1].isdigit():
                times.append(now)
                values_.append(float(line.split()[1]))
    y = np.interp(task.data[:, 0], np.array(times), np.array(values_))
    r = y - task.data[:, 1]
    return float(r @ r)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, required=True, help="TestSuite root or Verify")
    parser.add_argument("--task", default="op09")
    parser.add_argument("--model", help="the model (default: the task's oiNN)")
    parser.add_argument("--found", type=Path, help="a febio_optimize.py results CSV")
    parser.add_argument("--febio", help="a febio4 executable")
    parser.add_argument("--symmetric", action="store_true")
    parser.add_argument("--febio-solver", action="store_true")
    args = parser.parse_args()
    verify = args.suite / "Verify" if (args.suite / "Verify").is_dir() else args.suite
    task_path = verify / f"{args.task}.feb"
    model = verify / f"{args.model or 'oi' + args.task[2:]}.feb"
    warnings.simplefilter("ignore")
    task = read_optimize(task_path)
    builder = ModelBuilder(model, task, febio_solver=args.febio_solver)
    sets = {"start": np.array([p.initial for p in task.parameters])}
    if args.found is not None:
        for row in csv.DictReader(args.found.open()):
            if row["model"] == args.task and row.get("parameters"):
                found = json.loads(row["parameters"])
                sets[f"found ({args.found.name})"] = np.array(
                    [found[p.name] for p in task.parameters]
                )
    print(f"{args.task} on {model.name}: objective by tissuesim"
          f"{' (--febio-solver)' if args.febio_solver else ''}"
          + (" and by FEBio" if args.febio else ""))  # fmt: skip
    try:
        for label, values in sets.items():
            ours = tissuesim_objective(builder, task, values)
            line = f"  {label}: tissuesim {ours:.7g}"
            if args.febio:
                theirs = febio_objective(args.febio, model, builder, task, values,
                                         args.symmetric)  # fmt: skip
                line += f", FEBio {theirs:.7g} (tissuesim / FEBio - 1 = {ours / theirs - 1:+.1e})"
            print(line)
    finally:
        builder.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
