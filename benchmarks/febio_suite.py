"""FEBio's verification suite (issue 42): every model of FEBio's TestSuite ``Verify`` folder
converted, run and compared with the result FEBio recorded for it.

What it measures, per model: whether tissuesim reads it (``load_febio``) or refuses it (the
one-line ``FebError`` / ``InputError``, sorted into a feature bucket by its text); for a
model that loads, a run to its end as ``tests/febio/test_febio_published.py`` runs one (the
scene's ``[run] steps``, stopping early when an adaptive run is ``finished``), its wall time,
its steps against FEBio's recorded time steps, and tissuesim's solution norm against FEBio's
``solution_norm``: the L2 norm of the final displacement over FEBio's equations, every
component of every node of a deformable part that no zero or prescribed displacement active
in the last step holds (a node held in one body is held; the nodes of a ``rigid body`` part
are FEBio's rigid nodes, not equations, and are left out; FEBio's vector also holds the free
DOFs of its rigid bodies, the centre's displacement and the rotation vector, and so does this
norm). Each model runs in its own process
(this script with ``--one``) under a wall-time limit, so a hang or a crash is recorded as one
and the others go on: status ``refused``, ``ran``, ``failed`` (``RunError``: Newton did not
converge), ``crashed`` (any other exception, with its type, message and where it was raised,
or the process died), ``timeout``, or ``script error`` (this script could not take the norm:
a body not found under the converter's name).

FEBio's results come from the suite's gold-standard file ``code/linuxGoldStandards.py``
(read with ``ast``, never executed): per model ``['Normal', time steps, iterations, right
hand sides, reformations, plot file size, value]``, the value being the first logged data
record, which FEBio's test task makes ``solution_norm`` when the model logs nothing (all the
Verify models but the optimisation decks ``op*``, whose records are objectives).

The suite's decks cannot be shipped with tissuesim (they carry no licence); get them with

    git clone https://github.com/febiosoftware/TestSuite ~/TestSuite
    python benchmarks/febio_suite.py --suite ~/TestSuite
    python benchmarks/febio_suite.py --suite ~/TestSuite --only 'mi*' --timeout 60
    python benchmarks/febio_suite.py --suite DIR_OF_FEB_FILES --gold linuxGoldStandards.py

It writes ``benchmarks/results/febio_suite.csv`` (every model) and ``febio_suite.md`` (the
counts, the table of runs, the refusals ranked by feature and the most common messages);
``--out`` names another stem; ``--report CSV`` writes the tables again from a run's CSV.
"""

from __future__ import annotations

import argparse
import ast
import csv
import fnmatch
import json
import os
import re
import subprocess
import sys
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results" / "febio_suite"

#: status of a model, in the order the tables list them
STATUSES = ("ran", "failed", "crashed", "timeout", "script error", "refused")

#: (bucket, patterns of the refusal's text), the first bucket with a match wins
BUCKETS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("optimisation decks (febio_optimize)", ("febio_optimize",)),
    (
        "fluid / FSI / biphasic / multiphasic / solute modules (out of scope)",
        ("module '",),
    ),
    ("rigid bodies", ("'rigid body'", "<Rigid", "rigid_body", "rigid_connector", "type 'rigid'")),
    ("shells", ("quad4", "quad8", "tri3", "tri6", "shell")),
    ("reactive viscoelastic / plasticity / damage", ("reactive", "damage")),
    ("solid mixture components", ("in a solid mixture",)),
    ("generalised-alpha dynamics", ("generalised-alpha",)),
    ("contact options", ("<contact>", "contact type")),
    (
        "constraints / springs / initial conditions",
        ("<Constraints>", "Discrete", "<Initial>", "linear constraint"),
    ),
    ("material law not implemented", ("material type", "<fiber>", "a material parameter")),
    (
        "loads (other types, on the deformed surface, given by expressions)",
        ("<body_load>", "<surface_load>", "<linear>", "<pressure>"),
    ),
    (
        "other solvers and element formulations (explicit, CG, ut4, laugon)",
        ("solver type", "domain type", "domain options"),
    ),
    ("mesh adaptation", ("<MeshAdaptor>",)),
)

#: what a difference or a missing record comes from, where it is known (the .md's table)
REMARKS = {
    "mi16": "the pressure is one period of a sine, 0 at the end: the elastic disk is back at "
    "its start (tissuesim's peak norm 7.6); FEBio's norm is what its Newton tolerance leaves "
    "(--febio-solver gives it)",
    "co35": "two nearly incompressible blocks pressed by a penalty: tissuesim's solve leaves "
    "the symmetric path for an asymmetric state of lower energy",
    "ms01": "FEBio's quasi-Newton stops at its tolerances (dtol, etol) and in undamped "
    "vibration the leftovers add up: --febio-solver gives FEBio's norm",
    "ms02": "FEBio's quasi-Newton stops at its tolerances (dtol, etol) and in undamped "
    "vibration the leftovers add up: --febio-solver gives FEBio's norm",
    "dy02": "FEBio's quasi-Newton stops at its tolerances (dtol, etol) and in undamped "
    "vibration the leftovers add up: --febio-solver gives FEBio's norm",
    "ma57": "nothing holds the plate along z: its answer is defined up to a z shift, and "
    "FEBio's record holds the one its factorisation picked (with either z face held still, "
    "8.2e-6: benchmarks/febio_free_translation.py)",
    "ma62": "nothing moves: FEBio records round-off",
    "ma64": "nothing moves: FEBio records round-off",
}
OTHER = "other"

CHILD_ENV = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")


# -- FEBio's recorded results -----------------------------------------------------------------
def read_gold(path: Path) -> dict[str, list]:
    """The gold-standard file's ``stdResults`` dict, read as a literal (nothing executed)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "stdResults" for t in node.targets
        ):
            return ast.literal_eval(node.value)
    raise SystemExit(f"{path}: no 'stdResults = {{...}}' assignment")


def febio_record(gold: dict[str, list], name: str) -> tuple[int | None, float | None]:
    """(FEBio's time steps, its solution_norm) of a model; None where none is recorded (no
    entry, or an optimisation deck's record of four fields)."""
    entry = gold.get(name)
    if entry is None or len(entry) != 7:
        return None, None
    try:
        return int(entry[1]), float(entry[6])
    except (TypeError, ValueError):
        return None, None


# -- one model, in a process of its own --------------------------------------------------------
def one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def crash_line(exc: BaseException) -> str:
    """An unexpected exception's line and where it was raised (the deepest frame)."""
    import traceback

    frames = traceback.extract_tb(exc.__traceback__)
    where = f" ({Path(frames[-1].filename).name}:{frames[-1].lineno})" if frames else ""
    return one_line(exc) + where


def run_one(path: Path, febio_solver: bool = False) -> dict[str, Any]:
    """Convert, run and measure one model (in the child process); ``febio_solver``: with
    FEBio's quasi-Newton (``tissuesim run --febio-solver``)."""
    import warnings

    import numpy as np

    from tissuesim.errors import InputError, RunError
    from tissuesim.febio import load_febio, read_feb

    out: dict[str, Any] = {"status": "", "message": "", "steps": 0, "end_time": None}
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = read_feb(path)
            scene = load_febio(path, febio_solver=febio_solver)
    except InputError as exc:
        out.update(status="refused", error=type(exc).__name__, message=one_line(exc))
        return out
    except Exception as exc:  # noqa: BLE001 - a crash of the converter is a result
        out.update(status="crashed", error=type(exc).__name__, message=crash_line(exc))
        return out
    out["load_s"] = time.perf_counter() - start
    sim = scene.simulation
    started = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            turns: dict[str, np.ndarray] = {}  # each rigid body's quaternion, followed
            for _ in range(scene.run["steps"]):
                sim.step()
                out["steps"] += 1
                follow_rotations(sim, turns)
                if sim.finished:  # an adaptive model's [run] steps is an upper bound
                    break
        out["status"] = "ran"
    except RunError as exc:
        out.update(status="failed", error=type(exc).__name__, message=one_line(exc))
    except InputError as exc:  # refused at the first step (its start), in one line
        out.update(status="refused", error=type(exc).__name__, message=one_line(exc))
        return out
    except Exception as exc:  # noqa: BLE001
        out.update(status="crashed", error=type(exc).__name__, message=crash_line(exc))
    out["run_s"] = time.perf_counter() - started
    out["end_time"] = float(sim.time)
    if out["status"] != "ran":
        return out
    try:
        out.update(solution_norm(model, sim, np, turns))
    except Exception as exc:  # noqa: BLE001 - the script's own error, not tissuesim's
        out.update(status="script error", error=type(exc).__name__, message=crash_line(exc))
    return out


def follow_rotations(sim: Any, turns: dict) -> None:
    """Each rigid body's rotation as a quaternion (x, y, z, w) followed step by step (the sign
    of the two that give one rotation kept next to the last step's), as FEBio carries it: a
    full turn is then the quaternion -1, angle 2 pi, not the identity."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    system = sim.system
    for r, sc in zip(system.rigid, system.rigid_config_slices, strict=True):
        q = Rotation.from_matrix(sim.state.x[sc][3:12].reshape(3, 3)).as_quat()
        last = turns.get(r.name, np.array([0.0, 0.0, 0.0, 1.0]))
        turns[r.name] = q if q @ last >= 0 else -q


def solution_norm(model: Any, sim: Any, np: Any, turns: dict | None = None) -> dict[str, Any]:
    """tissuesim's final displacement over FEBio's equations.

    The bodies are the converter's (``febio/scene.py`` ``scene_bodies``: its names, its
    vertices ``np.unique`` of a body's cells, in order). Every vertex of a deformable body is
    mapped back to its FEBio node. Left out, as FEBio's equations leave them out: the
    components held by a condition active in the last step (held in one body, held), and
    FEBio's rigid nodes (``FERigidSystem``: every node of a rigid element, shared ones
    included, and the nodes of a ``<bc type="rigid">`` set)."""

    from tissuesim.febio.rigid.scene import rigid_material_of
    from tissuesim.febio.scene import scene_bodies

    rigid_nodes = np.zeros(len(model.nodes), dtype=bool)
    for part in model.parts:
        if rigid_material_of(model, part) is not None:
            rigid_nodes[np.unique(model.parts[part][1])] = True
    for entry in model.rigid_nodes:  # <bc type="rigid">: (set, body, element)
        rigid_nodes[model.node_sets[entry[0]]] = True
    u = np.zeros(model.nodes.shape)
    deformable = np.zeros(len(model.nodes), dtype=bool)
    for name, body in scene_bodies(model):
        if body["rigid"] is not None:
            continue
        if name not in sim.bodies:
            raise KeyError(f"body {name!r} not in the simulation (it has {list(sim.bodies)})")
        used = np.unique(body["cells"])
        x = sim.body_positions(name)
        if x.shape != (len(used), 3):
            raise ValueError(f"body {name!r} has {x.shape} positions for {len(used)} nodes")
        u[used] = x - model.nodes[used]
        deformable[used] = True
    free = np.repeat((deformable & ~rigid_nodes)[:, None], 3, axis=1)
    for nodes, comps, _, _, window in model.dirichlet:
        if window is not None and not window[0] < sim.time <= window[1]:
            continue  # a condition of an earlier step: its DOFs are free in the last one
        free[np.ix_(model.node_sets[nodes], range(3) if comps is None else comps)] = False
    for c in getattr(model, "linear_constraints", ()):  # a linear constraint's parent DOF:
        if c.get("parent") is not None:  # FEBio eliminates it (FELinearConstraintManager)
            free[c["parent"]] = False
    # FEBio's vector also holds each rigid body's free DOFs: the centre's displacement and
    # the rotation vector (FERigidSolver UpdateIncrements, the exponential map, of the
    # quaternion it carries from step to step: ``follow_rotations``)
    turns = turns or {}
    from tissuesim.frames.rotations import log_map

    own = []
    state, system = sim.state, sim.system
    for r, sc in zip(system.rigid, system.rigid_config_slices, strict=True):
        z = state.x[sc]
        rotation = log_map(z[3:12].reshape(3, 3))[0]
        if r.name in turns:  # FEBio's angle 2 acos(w) of the quaternion it carries: up to 2 pi
            q = turns[r.name]
            sin = float(np.linalg.norm(q[:3]))
            rotation = q[:3] / sin * 2.0 * np.arccos(np.clip(q[3], -1.0, 1.0)) if sin else 0 * q[:3]
        values = np.concatenate([z[:3] - r.center, rotation])
        own += [values[k] for k in range(6) if k not in r.held]
    values = np.concatenate([u[free], np.asarray(own, dtype=float)])
    return {"norm": float(np.linalg.norm(values)), "dofs": int(values.size), "note": ""}


# -- the parent: every model, a process each --------------------------------------------------
def measure(path: Path, timeout: float, febio_solver: bool = False) -> dict[str, Any]:
    env = dict(os.environ)
    for key in CHILD_ENV:
        env[key] = "1"
    start = time.perf_counter()
    try:
        done = subprocess.run(
            [sys.executable, __file__, "--one", str(path)] + ["--febio-solver"] * febio_solver,
            capture_output=True, text=True, env=env, timeout=timeout,
        )  # fmt: skip
    except subprocess.TimeoutExpired:
        return {
            "status": "timeout",
            "message": f"still running after {timeout:g} s (killed)",
            "wall_s": time.perf_counter() - start,
        }
    wall = time.perf_counter() - start
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode != 0 or not lines:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        return {
            "status": "crashed",
            "error": f"exit {done.returncode}",
            "message": tail[:300],
            "wall_s": wall,
        }
    result = json.loads(lines[-1])
    result["wall_s"] = wall
    return result


def short(message: str) -> str:
    """A refusal without the file's path (``model.feb:42 <tag>: ...`` -> ``<tag>: ...``)."""
    message = re.sub(r"^\S+\.feb(:\d+)?:? ", "", message)
    return re.sub(r"/\S+/(\w+\.feb)", r"\1", message)


def gist(message: str, width: int = 150) -> str:
    """The message up to its first ';' (the list of what tissuesim does run left off)."""
    text = short(message).split("; it ")[0].split("; tissuesim runs")[0]
    return text if len(text) <= width else text[: width - 3] + "..."


def bucket(message: str) -> str:
    message = gist(message, 10**6)  # what is refused, not the list of what runs
    for name, patterns in BUCKETS:
        if any(p in message for p in patterns):
            return name
    return OTHER


def law(message: str) -> str | None:
    found = re.search(r"material type '([^']+)'", message)
    return found.group(1) if found else None


def relative(norm: float | None, febio: float | None) -> float | None:
    if norm is None or febio is None or abs(febio) < 1e-12:
        return None
    return norm / febio - 1.0


def within(row: dict[str, Any], tol: float) -> bool:
    """tissuesim's norm agrees with FEBio's to ``tol`` (relative; a recorded norm of
    round-off size, below 1e-12, agrees with a tissuesim norm below 1e-12)."""
    if row["status"] != "ran" or row.get("norm") is None or row.get("febio_norm") is None:
        return False
    if abs(row["febio_norm"]) < 1e-12:
        return abs(row["norm"]) < 1e-12
    return abs(row["rel_error"]) <= tol


def remark(row: dict[str, Any], message: str) -> str:
    parts = [message, row.get("note") or "", REMARKS.get(row["model"], "")]
    if row["status"] == "ran" and row.get("febio_norm") is None:
        oi = row["model"].startswith("oi")  # runTests.py skips them: no record
        parts.append("no record (an optimisation deck's input)" if oi else "no record")
    return "; ".join(p for p in parts if p)


def error_cell(row: dict[str, Any]) -> str:
    if row.get("rel_error") is not None:
        return f"{row['rel_error']:+.1e}"
    if row["status"] != "ran":
        return ""
    if row.get("febio_norm") is None:
        return "no record"
    return "round-off" if within(row, 0.0) else f"{row['norm'] - row['febio_norm']:+.1e} (abs.)"


def fmt(value: Any, spec: str = "") -> str:
    if value is None or value == "":
        return ""
    return format(value, spec)


FIELDS = (
    "model", "status", "bucket", "error", "message", "steps", "febio_steps", "end_time",
    "norm", "febio_norm", "rel_error", "dofs", "wall_s", "load_s", "run_s", "note",
)  # fmt: skip


def write_csv(rows: list[dict[str, Any]], path: Path) -> None:
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS, extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: row.get(k, "") for k in FIELDS})


def converted_ok(row: dict[str, Any]) -> bool:
    """The model loaded: it ran, failed or crashed in its run, or ran out of time (loading
    takes a second; a timeout is counted as loaded)."""
    if row["status"] in ("refused", "crashed"):
        return row["status"] == "crashed" and row.get("load_s") not in (None, "")
    return True


def read_csv(path: Path) -> list[dict[str, Any]]:
    """The rows of an earlier run's CSV, numbers as numbers (empty cells None)."""
    ints = ("steps", "febio_steps", "dofs")
    floats = ("end_time", "norm", "febio_norm", "rel_error", "wall_s", "load_s", "run_s")
    rows = []
    with path.open(newline="") as f:
        for row in csv.DictReader(f):
            for key in ints + floats:
                text = row.get(key) or ""
                row[key] = None if text == "" else (int(text) if key in ints else float(text))
            rows.append(row)
    return rows


def summary(rows: list[dict[str, Any]], command: str, at: str = "") -> str:
    count = Counter(r["status"] for r in rows)
    converted = sum(1 for r in rows if converted_ok(r))
    recorded = [r for r in rows if r["status"] == "ran" and r.get("febio_norm") is not None]
    w3 = sum(within(r, 1e-3) for r in rows)
    w5 = sum(within(r, 1e-5) for r in rows)
    out = [
        "# FEBio's verification suite",
        "",
        f"`{command}` ({time.strftime('%Y-%m-%d')}{', ' + at if at else ''}). "
        "The suite's decks are not shipped "
        "(no licence): `git clone https://github.com/febiosoftware/TestSuite`.",
        "",
        "| models | converted | ran to the end | with a recorded norm | within 1e-3 | "
        "within 1e-5 | failed (RunError) | crashed | timed out | script errors | refused |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        f"| {len(rows)} | {converted} | {count['ran']} | {len(recorded)} | {w3} | {w5} | "
        f"{count['failed']} | {count['crashed']} | {count['timeout']} | "
        f"{count['script error']} | {count['refused']} |",
        "",
        "## Runs",
        "",
        "Relative error: tissuesim's solution norm / FEBio's - 1.",
        "",
        "| model | status | steps | FEBio's steps | end time | solution norm | FEBio's | "
        "rel. error | DOFs | wall (s) | message |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in sorted(
        (r for r in rows if r["status"] != "refused"),
        key=lambda r: (STATUSES.index(r["status"]), r["model"]),
    ):
        message = gist(f"{r.get('error', '')}: {r['message']}") if r.get("message") else ""
        out.append(
            f"| {r['model']} | {r['status']} | {r.get('steps', '')} | "
            f"{fmt(r.get('febio_steps'))} | {fmt(r.get('end_time'), '.6g')} | "
            f"{fmt(r.get('norm'), '.10g')} | {fmt(r.get('febio_norm'), '.12g')} | "
            f"{error_cell(r)} | {fmt(r.get('dofs'))} | "
            f"{fmt(r.get('wall_s'), '.1f')} | {remark(r, message)} |"
        )
    refused = [r for r in rows if r["status"] == "refused"]
    for r in refused:
        r["bucket"] = bucket(r["message"])
    buckets = Counter(r["bucket"] for r in refused)
    out += [
        "",
        f"## Refusals by feature ({len(refused)} models)",
        "",
        "| feature | models | example |",
        "| --- | --- | --- |",
    ]
    for name, n in buckets.most_common():
        example = Counter(gist(r["message"]) for r in refused if r["bucket"] == name)
        text = example.most_common(1)[0][0]
        model = next(r["model"] for r in refused if gist(r["message"]) == text)
        out.append(f"| {name} | {n} | {model}: `{text}` |")
    laws = Counter(
        law(r["message"]) for r in refused if law(r["message"]) not in (None, "rigid body")
    )
    if laws:
        out += ["", "Material laws refused (rigid body aside; alone or in a mixture; models):", ""]
        out.append(", ".join(f"{name} {n}" for name, n in laws.most_common()))
    messages = Counter(gist(r["message"]) for r in refused)
    out += ["", "## The most common refusals", "", "| models | message |", "| --- | --- |"]
    for text, n in messages.most_common(12):
        out.append(f"| {n} | `{text}` |")
    return "\n".join(out) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, help="TestSuite root, or a folder of .feb files")
    parser.add_argument("--gold", type=Path, help="gold-standard file (default: the suite's)")
    parser.add_argument(
        "--only", default="*", help="globs on the model names, '|' between, e.g. 'mi*|co16'"
    )
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per model")
    parser.add_argument("--jobs", type=int, default=1, help="models run at once")
    parser.add_argument("--out", type=Path, default=RESULTS, help="stem of the .csv and .md")
    parser.add_argument("--report", type=Path, help="rewrite the .md from this run's .csv")
    parser.add_argument("--command", help="the command named in the .md (with --report)")
    parser.add_argument("--at", default="", help="what was run, for the .md (a commit)")
    parser.add_argument("--one", type=Path, help=argparse.SUPPRESS)
    parser.add_argument(
        "--febio-solver", action="store_true", help="run with FEBio's quasi-Newton (its <solver>)"
    )
    args = parser.parse_args()
    if args.one is not None:  # the child: one model, its result as one JSON line
        print(json.dumps(run_one(args.one, args.febio_solver)))
        return
    if args.report is not None:  # the tables again, from the CSV of a run
        command = args.command or "python benchmarks/febio_suite.py"
        text = summary(read_csv(args.report), command, args.at)
        args.out.with_suffix(".md").write_text(text)
        print(text)
        return
    if args.suite is None:
        parser.error(
            "--suite DIR is required (git clone https://github.com/febiosoftware/TestSuite)"
        )
    verify = args.suite / "Verify" if (args.suite / "Verify").is_dir() else args.suite
    gold_path = args.gold or args.suite / "code" / "linuxGoldStandards.py"
    if not gold_path.is_file():
        parser.error(f"no gold-standard file {gold_path}: give it with --gold")
    gold = read_gold(gold_path)
    globs = args.only.split("|")
    paths = [p for p in sorted(verify.glob("*.feb"))
             if any(fnmatch.fnmatch(p.stem, g) for g in globs)]  # fmt: skip
    if not paths:
        parser.error(f"no .feb model matching {args.only!r} in {verify}")

    def task(path: Path) -> dict[str, Any]:
        row = {"model": path.stem, **measure(path, args.timeout, args.febio_solver)}
        row["message"] = re.sub(r"\S*/(\w+\.feb)", r"\1", row.get("message", ""))  # no folder
        row["febio_steps"], row["febio_norm"] = febio_record(gold, path.stem)
        row["rel_error"] = relative(row.get("norm"), row["febio_norm"])
        row["bucket"] = bucket(row["message"]) if row["status"] == "refused" else ""
        error = "" if row.get("rel_error") is None else f" {row['rel_error']:+.1e}"
        print(f"{path.stem}: {row['status']}{error} {row.get('wall_s', 0):.1f} s "
              f"{gist(row.get('message', ''), 100)}", flush=True)  # fmt: skip
        return row

    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        rows = list(pool.map(task, paths))
    command = "python benchmarks/febio_suite.py --suite TestSuite"
    if args.only != "*":
        command += f" --only '{args.only}'"
    command += f" --timeout {args.timeout:g} --jobs {args.jobs}"
    command += " --febio-solver" * args.febio_solver
    text = summary(rows, command, args.at)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_csv(rows, args.out.with_suffix(".csv"))
    args.out.with_suffix(".md").write_text(text)
    print()
    print(text.split("## Runs")[0].strip())
    print(text[text.index("## Refusals") :].split("\nMaterial laws")[0].strip())


if __name__ == "__main__":
    main()
