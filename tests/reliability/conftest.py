"""Helpers for the reliability tests: a small scene, and running the CLI in-process the way a
user's shell does, capturing what it prints and its exit code."""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from tissuesim.cli import main

SCENE = """
[mesh]
generator = "rectangle"
lower = [0.0, 0.0]
upper = [1.0, 1.0]
divisions = [4, 4]

[material]
model = "neo_hookean"
youngs_modulus = 1000.0
poisson_ratio = 0.3

[simulation]
density = 1.0
integrator = "backward_euler"
time_step = 0.01

[[dirichlet]]
vertices = { on_plane = { axis = 0, value = 0.0 } }
displacement = ["0.1 * t", "0"]

[run]
steps = 3
render = false
"""


@dataclass
class Result:
    code: int
    out: str
    err: str

    @property
    def error_line(self) -> str:
        """The one error line; fails unless stderr is exactly one 'tissuesim: error:' line
        (warnings may come before it)."""
        lines = [line for line in self.err.splitlines() if line.strip()]
        errors = [line for line in lines if line.startswith("tissuesim: error: ")]
        assert len(errors) == 1, f"expected one error line, got:\n{self.err}"
        assert "Traceback" not in self.err, self.err
        others = [
            line
            for line in lines
            if not line.startswith(("tissuesim: error: ", "tissuesim: warning: ", "tissuesim: "))
        ]
        assert not others, f"unexpected lines on stderr:\n{self.err}"
        return errors[0]


@pytest.fixture
def cli(capsys):
    """cli(*argv) -> Result (exit code, stdout, stderr)."""

    def run(*argv: str) -> Result:
        code = main([str(a) for a in argv])
        captured = capsys.readouterr()
        return Result(code, captured.out, captured.err)

    return run


@pytest.fixture
def scene(tmp_path):
    """scene(text=SCENE, (old, new), ...) -> path of a scene file with each old text (which
    must be there) replaced by new."""

    def write(text: str = SCENE, *replace: tuple[str, str], name: str = "scene.toml") -> Path:
        for old, new in replace:
            assert old in text, old
            text = text.replace(old, new)
        path = tmp_path / name
        path.write_text(text)
        return path

    return write


PYTHON = sys.executable
