"""The shipped example scenes: where they are and what each is (``tissuesim examples``).

What an example shows is the first sentence of its scene file's opening comment; what it is
made of (dimension, bodies, contact, frames, tissue, cuts) is read from its tables without
building it; how long it takes is the scene's own ``# Runs in about ...`` comment line,
measured with the plain install (SciPy's solvers, no Numba) on one thread of a 2-core machine,
pictures included (``benchmarks/examples_timing.py``; docs/examples.md has both installs' times).
An example may also be a FEBio model (``.feb``): its opening ``<!-- ... -->`` comment says the
same."""

from __future__ import annotations

import re
import tomllib
from importlib import resources
from importlib.util import find_spec
from pathlib import Path
from typing import Any

__all__ = ["example_path", "list_examples", "describe_example", "RUNTIME_NOTE"]

_RUNTIME = re.compile(r"^#\s*Runs in about (\d+(?:\.\d+)? s)\b", re.MULTILINE)
#: how the run times in the scenes' comments were measured
RUNTIME_NOTE = (
    "run times: the plain install (pip install .), one thread of a 2-core machine, pictures "
    "included; with tissuesim[fast] (Numba, PARDISO): docs/examples.md"
)
_MESH_FILE_DIMS = {".msh": 3, ".vtu": 3}  # the shipped mesh files are tetrahedral


#: the file types of shipped examples: scenes, and FEBio models
SUFFIXES = (".toml", ".feb")


def example_path(name: str) -> Path:
    """Path of a shipped example scene (or FEBio model) by name (``tissuesim examples``)."""
    root = resources.files("tissuesim") / "examples"
    for suffix in SUFFIXES[1:]:
        path = Path(str(root / f"{name}{suffix}"))
        if path.exists():
            return path
    return Path(str(root / f"{name}.toml"))


def list_examples() -> list[str]:
    """The names of the shipped example scenes and FEBio models, sorted."""
    root = resources.files("tissuesim") / "examples"
    return sorted(p.name.rsplit(".", 1)[0] for p in root.iterdir() if p.name.endswith(SUFFIXES))


def _first_sentence(text: str) -> str:
    lines = []
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        body = line.lstrip("#").strip()
        if not body:
            break
        lines.append(body)
    paragraph = " ".join(lines)
    match = re.search(r"(?<!\be\.g)(?<!\bi\.e)\.(\s|$)", paragraph)
    return paragraph[: match.start() + 1] if match else paragraph


def _dimension(table: dict) -> int:
    mesh = table.get("mesh", {})
    generator = mesh.get("generator")
    if generator == "rectangle":
        return 2
    if generator in ("box", "ellipsoid") or "surface" in mesh:
        return 3
    return _MESH_FILE_DIMS.get(Path(str(mesh.get("file", ""))).suffix, 3)


def describe_example(name: str) -> dict[str, Any]:
    """What the example ``name`` is: its path, what it shows, its make-up, the optional
    packages its output uses, and its measured run time (None where the scene does not say)."""
    path = example_path(name)
    text = path.read_text()
    if path.suffix == ".feb":
        return _describe_febio(name, path, text)
    scene = tomllib.loads(text)
    bodies = scene.get("bodies") or ([scene] if "mesh" in scene else [])
    dims = {_dimension(b) for b in bodies} or {3}
    parts = []
    dim = max(dims)
    parts.append(f"{dim}D")
    n_bodies = len(bodies) + ("frames" in scene)
    parts.append(f"{n_bodies} bod{'y' if n_bodies == 1 else 'ies'}")
    for key, what in (
        ("frames", "meshless frames"),
        ("tissue", "connective tissue"),
        ("contact", "contact"),
        ("cuts", "cutting"),
    ):
        if key in scene:
            parts.append(what)
    steps = scene.get("run", {}).get("steps")
    if steps is not None:
        parts.append(f"{steps} steps")
    needs = []
    if dim == 3:
        have = find_spec("pyvista") is not None
        several = n_bodies > 1 or "tissue" in scene
        what = "need" if several else "are best with"
        state = "installed" if have else "not installed: pip install 'tissuesim[pyvista]'"
        needs.append(f"3D pictures {what} PyVista ({state})")
    runtime = _RUNTIME.search(text)
    return {
        "name": name,
        "path": str(path),
        "shows": _first_sentence(text),
        "made_of": ", ".join(parts),
        "needs": needs,
        "runtime": runtime.group(1) if runtime else None,
    }


def _describe_febio(name: str, path: Path, text: str) -> dict[str, Any]:
    """A shipped FEBio model, described from its opening comment and its steps."""
    from tissuesim.febio import read_feb

    match = re.search(r"<!--(.*?)-->", text, flags=re.S)
    lines = (match.group(1) if match else "").strip().splitlines()
    comment = "\n".join(f"# {line.strip()}" for line in lines)
    model = read_feb(path)
    steps = sum(p["time_steps"] for p in model.phases) or model.time_steps
    runtime = _RUNTIME.search(comment)
    return {
        "name": name,
        "path": str(path),
        "shows": _first_sentence(comment),
        "made_of": f"3D, a FEBio model in {len(model.phases) or 1} steps, {steps} time steps",
        "needs": [],
        "runtime": runtime.group(1) if runtime else None,
    }
