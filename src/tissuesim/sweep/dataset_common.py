"""What both dataset formats (dataset.py's HDF5, dataset_zarr.py's Zarr) write per run: the
fields a study can save, a run's arrays and attributes, and the rest mesh's fingerprint."""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

__all__ = ["FIELDS", "CELL_FIELDS", "frame_fields", "run_arrays", "run_attributes"]

#: the fields a study can save per run: the displacement of the vertices, and the cell fields
#: every FEM body writes (``Simulation.cell_fields``: J, Green strain, Cauchy stress, von
#: Mises stress, energy density; one value or 3 x 3 tensor per cell)
FIELDS = ("displacement", "J", "green_strain", "cauchy_stress", "von_mises", "energy_density")
CELL_FIELDS = FIELDS[1:]


def _rest(sim) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    return {
        name: (np.asarray(b.mesh.points, float), np.asarray(b.mesh.cells, np.int64))
        for name, b in sim.bodies.items()
        if b.kind == "fem"
    }


def _sha(rest: dict[str, tuple[np.ndarray, np.ndarray]]) -> str:
    h = hashlib.sha256()
    for name in sorted(rest):
        points, cells = rest[name]
        h.update(name.encode())
        h.update(np.ascontiguousarray(points).tobytes())
        h.update(np.ascontiguousarray(cells).tobytes())
    return h.hexdigest()[:16]


def frame_fields(sim: Any, fields: tuple[str, ...]) -> dict[str, dict[str, np.ndarray]]:
    """The asked ``fields`` of every FEM body now: {body: {field: array}}."""
    out: dict[str, dict[str, np.ndarray]] = {}
    for name, body in sim.bodies.items():
        if body.kind != "fem":
            continue
        values = {}
        if "displacement" in fields:
            values["displacement"] = sim.body_displacement(name)
        wanted = [k for k in CELL_FIELDS if k in fields]
        if wanted:
            cell = sim.cell_fields(name)
            values.update({k: np.asarray(cell[k], float) for k in wanted})
        out[name] = values
    return out


def run_arrays(task: Any, sim: Any, names: list[str], frames: list | None) -> dict[str, np.ndarray]:
    """The run's arrays by their path in its file: ``times`` (with ``frames``) and
    ``<body>/<field>`` for the FEM bodies ``names``."""
    arrays: dict[str, np.ndarray] = {}
    if frames:
        arrays["times"] = np.array([t for t, _ in frames], float)
        for name in names:
            for key in frames[0][1][name]:
                arrays[f"{name}/{key}"] = np.stack([values[name][key] for _, values in frames])
    else:
        for name, values in frame_fields(sim, task.fields).items():
            for key, value in values.items():
                arrays[f"{name}/{key}"] = value
    return arrays


def run_attributes(task: Any, sha: str) -> dict[str, Any]:
    """The run's attributes: run_id, index, rest_sha256 and each parameter as
    ``param:<key path>``."""
    attrs: dict[str, Any] = {"run_id": task.run_id, "index": task.index, "rest_sha256": sha}
    attrs.update({f"param:{key}": value for key, value in task.values.items()})
    return attrs
