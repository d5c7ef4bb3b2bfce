"""The fuzz harness: run one generated case through the command line in-process, in a sandbox
directory, under a time limit, and check what every case must satisfy:

- the command returns (no exception escapes ``main``) with exit code 0, 1 or 2;
- a failure prints exactly one ``tissuesim: error:`` line (warnings aside), no traceback,
  and never an "internal error" (that is a bug in tissuesim);
- exit 1 only for a failed run (Newton, instability), never for bad input;
- nothing is written outside the output directory (the sandbox holds only the inputs and it);
- every series in the output is readable: each frame its PVD lists opens with meshio, and
  summary.json is valid JSON whose status matches the exit code.

Counts per kind of case are kept in ``COUNTS`` and written to ``$TISSUESIM_FUZZ_REPORT``.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import signal
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import meshio

from tissuesim.cli import main

LONG = os.environ.get("TISSUESIM_FUZZ", "") == "long"
#: seconds one case may take before it counts as a hang
TIME_LIMIT = 60 if LONG else 30
COUNTS: Counter = Counter()
OUTCOMES: Counter = Counter()


class Hang(Exception):
    pass


@contextlib.contextmanager
def time_limit(seconds: float):
    def on_alarm(sig, frame):
        raise Hang(f"no answer after {seconds} s")

    previous = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def toml_value(value) -> str:
    """TOML text of a value (inline tables and arrays only; enough for generated scenes)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(type(value))


def toml_string(text: str) -> str:
    """A TOML basic string: JSON's escapes, but astral characters raw (JSON would write them as
    surrogate pairs, which TOML refuses) and DEL escaped (TOML refuses it raw)."""
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def toml_key(key: str) -> str:
    bare = key and all(c.isalnum() or c in "_-" for c in key) and key.isascii()
    return key if bare else toml_string(key)


def to_toml(data: dict) -> str:
    return "".join(f"{toml_key(k)} = {toml_value(v)}\n" for k, v in data.items())


def run_case(kind: str, sandbox: Path, argv: list[str], inputs: set[str]) -> tuple[int, str]:
    """Run ``tissuesim *argv`` with cwd ``sandbox``; check the case; return (code, stderr)."""
    COUNTS[kind] += 1
    out_dir = sandbox / "out"
    err, out = io.StringIO(), io.StringIO()
    cwd = os.getcwd()
    os.chdir(sandbox)
    try:
        with (
            time_limit(TIME_LIMIT),
            contextlib.redirect_stderr(err),
            contextlib.redirect_stdout(out),
        ):
            code = main(argv)
    except Hang as exc:
        raise AssertionError(f"{kind}: hang: {exc}; argv {argv}") from None
    finally:
        os.chdir(cwd)
    text = err.getvalue()
    assert code in (0, 1, 2), (kind, code, text)
    assert "Traceback" not in text, text
    if code:
        errors = [line for line in text.splitlines() if line.startswith("tissuesim: error: ")]
        assert len(errors) == 1, f"{kind}: expected one error line:\n{text}"
        assert "internal error" not in errors[0], f"{kind}: a bug:\n{errors[0]}\nargv {argv}"
        assert len(errors[0]) <= 1100, errors[0]
        if "wrong type or shape for its key" in errors[0]:  # no validator caught it first
            OUTCOMES[f"{kind}: generic wrong-type message"] += 1
    OUTCOMES[f"{kind}: exit {code}"] += 1
    written = {str(p.relative_to(sandbox)) for p in sandbox.rglob("*") if p.is_file()} - inputs
    outside = sorted(w for w in written if not w.startswith("out" + os.sep))
    assert not outside, f"{kind}: wrote outside the output directory: {outside}"
    if (out_dir / "summary.json").is_file():
        check_output(out_dir, code)
    return code, text


def check_output(directory: Path, code: int) -> None:
    summary = json.loads((directory / "summary.json").read_text())
    expected = {0: {"completed"}, 1: {"failed"}, 2: {"failed"}}[code]
    assert summary["status"] in expected, (summary["status"], code, summary.get("error"))
    for pvd in directory.glob("*.pvd"):
        for d in ET.parse(pvd).getroot().iter("DataSet"):
            meshio.read(directory / d.get("file"))


def write_report() -> None:
    path = os.environ.get("TISSUESIM_FUZZ_REPORT")
    if path:
        report = {
            "mode": "long" if LONG else "short",
            "cases": sum(COUNTS.values()),
            "by_kind": dict(COUNTS),
            "outcomes": dict(sorted(OUTCOMES.items())),
        }
        Path(path).write_text(json.dumps(report, indent=2) + "\n")
