"""The fingerprint of a simulation's set-up that a checkpoint (``io/checkpoints/checkpoint.py``)
must match: readable parts, one per setting group, body, obstacle and the scene file's hash,
compared part by part so that a mismatch names what differs.

A cut or torn body is fingerprinted by the mesh it was set up with (its cut state's original
mesh and densities), not by its cut mesh: a checkpoint written after a cut is loaded into a
simulation set up anew, not cut yet, and its cuts are restored from the checkpoint
(``io/checkpoints/cuts.py``). Blades and tearing are part of the set-up too.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict
from pathlib import Path

import numpy as np

from tissuesim.errors import InputError

__all__ = ["FIX", "check_fingerprint", "fingerprint", "scene_hash"]

#: what the user can do when a checkpoint does not fit
FIX = "run without --resume to start afresh, or resume with the original scene"


def _digest(*arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(str((a.dtype.str, a.shape)).encode())
        h.update(a.tobytes())
    return h.hexdigest()[:16]


def _scheme(sim) -> str:
    """The time scheme as set up: integrator and time step, or the phases (whose current
    ones change as the run goes), and Newmark's parameters where Newmark runs."""
    schedule = getattr(sim, "schedule", None)
    if schedule is None:
        text = f"{sim.integrator}, time_step {sim.time_step!r} s"
    else:
        phases = [(p.steps, p.time_step, p.integrator) for p in schedule.phases]
        text = f"{sim._base_integrator}, phases {phases}"
    uses = [sim.integrator] if schedule is None else [p.integrator for p in schedule.phases]
    if "newmark" in uses or sim.integrator == "newmark":
        text += f", newmark {tuple(sim.newmark)}"
    if "generalized_alpha" in uses or sim.integrator == "generalized_alpha":
        text += f", generalized_alpha {tuple(sim.generalized_alpha)}"
    adaptive = [getattr(sim, "adaptive", None)]  # FEBio's adaptive steps, where they run
    adaptive += [] if schedule is None else [p.adaptive for p in schedule.phases]
    if any(a is not None for a in adaptive):
        text += f", adaptive {adaptive}"
    return text


def _fem(b) -> tuple[str, str]:
    """(what, data digest) of a FEM body as set up: a cut body's original mesh."""
    state = getattr(b, "cut_state", None)
    mesh = b.mesh if state is None else state.original
    density = b.model.density if state is None else state.density
    data = _digest(mesh.points, mesh.cells, np.asarray(density, float))
    return f"{mesh.n_points} points, {mesh.n_cells} cells, {b.model.mass_kind} mass", data


def _cutting(sim) -> str:
    """The blades cutting FEM bodies and the bodies that tear, as set up."""
    parts = [
        f"{c.name}: body {c.body}, {c.start!r}..{c.end!r} s, toughness {c.toughness!r}, "
        f"obstacle {c.obstacle}, contact {c.contact}"
        for c in sim.organ_cuts
    ]
    parts += [
        f"{t.body} tears: stress {t.stress!r}, stretch {t.stretch!r}" for t in sim.organ_tears
    ]
    return "; ".join(parts)


def fingerprint(sim, scene: str | None = None) -> dict[str, str]:
    """Readable parts of the set-up a checkpoint must match (one per setting group and body);
    ``scene``: the scene file's hash, when run from one."""
    parts = {
        "simulation settings": (
            f"{_scheme(sim)}, start_time {sim.start_time!r} s, "
            f"max_step_halvings {sim.max_step_halvings}, "
            f"gravity {[g.tolist() for g in sim.gravity]}"
        ),
        "newton options": json.dumps(asdict(sim.newton), sort_keys=True),
        "bodies": ", ".join(sim.bodies),
    }
    for name, b in sim.bodies.items():
        # a tissue's model is remade as it is cut (None once all of it is gone): its own law
        model = b.material if b.kind == "tissue" else getattr(b.model, "material", None)
        material = repr(model) if model is not None else ""
        if b.kind == "fem":
            what, data = _fem(b)
        elif b.kind == "frames":
            data = _digest(b.config, b.model.samples.points, b.model.samples.volumes)
            what = f"{b.model.n_frames} frames, {b.model.samples.n} points"
        else:
            data, what = _digest(b.samples.points), f"{b.samples.n} points"
        parts[f"body {name!r}"] = f"{b.kind}: {what}, {material}, data {data}"
    if sim.contact is not None:
        parts["contact"] = repr(sim.contact)
    for ob in sim.obstacles:
        parts[f"obstacle {ob.name!r}"] = f"surface {_digest(ob.rest, ob.triangles)}"
    if sim.organ_cuts or sim.organ_tears:  # absent otherwise: as checkpoints of format 1
        parts["cutting"] = _cutting(sim)
    if sim.tissue is not None:  # its cuts and tearing (absent otherwise, as before)
        t = sim.tissue.describe()
        parts["tissue"] = json.dumps({k: t[k] for k in ("cuts", "tear_threshold", "frames")})
    if scene:
        parts["scene file (all but [run])"] = scene
    return parts


def check_fingerprint(saved: dict, now: dict, path: Path) -> None:
    """InputError naming the first part of the set-up that differs."""
    for key in sorted(set(saved) | set(now)):
        if key.startswith("scene file") and (key not in saved or key not in now):
            continue  # a run from a scene file resumed from Python, or the other way round
        if saved.get(key) != now.get(key):
            old = _clip(saved.get(key, "none")) if key in saved else "absent"
            new = _clip(now.get(key, "none")) if key in now else "absent"
            raise InputError(
                f"{path} was written for a different scene; {key}: checkpoint {old}, now {new}; "
                f"{FIX}"
            )


def _clip(text: str, n: int = 120) -> str:
    return text if len(text) <= n else text[: n - 3] + "..."


def scene_hash(path: str | os.PathLike[str]) -> str:
    """The hash of a scene file's tables except [run] (steps, every, render, field may change
    between a run and its resume)."""
    import tomllib

    data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    data.pop("run", None)
    text = json.dumps(data, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]
