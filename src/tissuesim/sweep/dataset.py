"""The study's dataset of fields, HDF5 (through h5py, the default) or Zarr (``dataset_format=
"zarr"``, dataset_zarr.py): one file (one Zarr group) per run, written by the worker that ran
it, so workers write in parallel with no lock and a killed study keeps every finished run's
file whole (each is written to a temporary name and renamed). In HDF5:

    fields/rest.h5              /<body>/points (n, d) float64, /<body>/cells (m, k) int64:
                                the rest mesh the runs share (written once, by the first run)
    fields/<run_id>.h5          /<body>/displacement (n, d) float64: the final displacement
                                of each FEM body's vertices from rest; /<body>/J,
                                von_mises, energy_density (m,), green_strain, cauchy_stress
                                (m, 3, 3): its final cell fields, where asked; attributes: run_id,
                                index, rest_sha256 and each parameter as "param:<key path>";
                                a run whose rest mesh differs from rest.h5 (a mesh per sample)
                                also holds its own /<body>/points and /<body>/cells

In Zarr the same groups, arrays and attributes under ``fields/rest.zarr`` and
``fields/<run_id>.zarr``. ``load_dataset(DIR)`` reads every run of either format into the same
NumPy arrays in one call.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.sweep.dataset_common import (  # noqa: F401  (re-exported)
    CELL_FIELDS,
    FIELDS,
    _rest,
    _sha,
    frame_fields,
    run_arrays,
    run_attributes,
)

__all__ = ["FIELDS", "FORMATS", "write_run_fields", "load_dataset", "check_format"]

#: the dataset's formats: one HDF5 file per run (h5py), or one Zarr group per run (zarr 3)
FORMATS = ("hdf5", "zarr")


def _h5py():
    try:
        import h5py
    except ImportError:
        raise InputError(
            "the fields dataset needs h5py: pip install 'tissuesim[sweep]' (or h5py)"
        ) from None
    return h5py


def check_format(dataset_format: str) -> str:
    """``dataset_format`` checked ("hdf5" or "zarr") and its library importable: a one-line
    InputError before a study starts, not a failure in every run."""
    if dataset_format not in FORMATS:
        raise InputError(
            f"--dataset-format {dataset_format!r}: choose hdf5 (one .h5 file per run) or zarr "
            "(one Zarr group per run)"
        )
    if dataset_format == "zarr":
        from tissuesim.sweep.dataset_zarr import zarr_module

        zarr_module()
    else:
        _h5py()
    return dataset_format


def write_run_fields(
    out: Path, task: Any, sim: Any, result: dict[str, Any], frames: list | None = None
) -> None:
    """Write the run's fields (``task.fields``) to ``fields/<run_id>.h5`` (or, with
    ``task.extra["dataset_format"] == "zarr"``, the group ``fields/<run_id>.zarr``): at its
    end, or with ``frames`` [(time, {body: {field: array}})] at each saved time (a leading
    axis, and ``/times``); the time it took and the file's size go into ``result``
    (``fields_write_s``, ``fields_bytes``)."""
    if task.extra.get("dataset_format", "hdf5") == "zarr":
        from tissuesim.sweep.dataset_zarr import write_run_fields_zarr

        write_run_fields_zarr(out, task, sim, result, frames)
        return
    from tissuesim.io.atomic import atomic_output

    h5py = _h5py()
    start = time.perf_counter()
    folder = out / "fields"
    folder.mkdir(parents=True, exist_ok=True)
    rest = _rest(sim)
    sha = _sha(rest)
    shared = folder / "rest.h5"
    own_rest = False
    if not shared.exists():
        with atomic_output(shared) as tmp, h5py.File(tmp, "w") as f:
            f.attrs["rest_sha256"] = sha
            for name, (points, cells) in rest.items():
                f.create_dataset(f"{name}/points", data=points)
                f.create_dataset(f"{name}/cells", data=cells)
    else:
        with h5py.File(shared, "r") as f:
            own_rest = f.attrs["rest_sha256"] != sha
    target = folder / f"{task.run_id}.h5"
    with atomic_output(target) as tmp, h5py.File(tmp, "w") as f:
        f.attrs.update(run_attributes(task, sha))
        for key, value in run_arrays(task, sim, list(rest), frames).items():
            f.create_dataset(key, data=value)
        for name, (points, cells) in rest.items():
            if own_rest:
                f.create_dataset(f"{name}/points", data=points)
                f.create_dataset(f"{name}/cells", data=cells)
    result["fields_write_s"] = time.perf_counter() - start
    result["fields_bytes"] = target.stat().st_size


def load_dataset(directory: str | Path) -> dict[str, np.ndarray]:
    """Every completed run's fields in a study's directory as NumPy arrays, runs in the order
    of their index, from the HDF5 files or the Zarr groups alike:

    - ``run_id`` (r,) str, ``index`` (r,) int;
    - each parameter by its key path, e.g. ``material.youngs_modulus`` (r,) (a vector: (r, k));
    - per FEM body: ``<body>/displacement`` (r, n, d), the cell fields asked for
      (``<body>/J`` (r, m), ``<body>/cauchy_stress`` (r, m, 3, 3), ...), ``<body>/points``
      (n, d) and ``<body>/cells`` (m, k), the rest mesh the runs share.

    Runs on different rest meshes (a mesh per sample) cannot be stacked: InputError; read
    their files one by one with h5py (zarr)."""
    folder = Path(directory) / "fields"
    h5, zarr_group = (folder / "rest.h5").exists(), (folder / "rest.zarr").is_dir()
    if not h5 and not zarr_group:
        raise InputError(
            f"{directory}: no fields dataset (fields/rest.h5 or fields/rest.zarr); run the "
            "study with --fields displacement (fields=('displacement',))"
        )
    if h5 and zarr_group:
        raise InputError(
            f"{directory}: holds both fields/rest.h5 and fields/rest.zarr (two studies' "
            "datasets in one folder); move one of them out"
        )
    if zarr_group:
        from tissuesim.sweep.dataset_zarr import read_zarr_runs

        rest, sha, runs = read_zarr_runs(folder)
        library = "zarr"
    else:
        rest, sha, runs = _read_h5_runs(folder)
        library = "h5py"
    return _stack(directory, rest, sha, runs, library)


def _read_h5_runs(folder: Path) -> tuple[dict[str, np.ndarray], str, list[dict[str, Any]]]:
    """The rest mesh ({<body>/points, <body>/cells}), its hash and every run file's
    attributes with its "fields" ({path: array}) and "path"."""
    h5py = _h5py()
    rest: dict[str, np.ndarray] = {}
    with h5py.File(folder / "rest.h5", "r") as f:
        sha = str(f.attrs["rest_sha256"])
        for name in f:
            rest[f"{name}/points"] = f[name]["points"][()]
            rest[f"{name}/cells"] = f[name]["cells"][()]
    files = sorted(p for p in folder.glob("r[0-9]*.h5") if not p.name.startswith("."))
    runs: list[dict[str, Any]] = []
    for path in files:
        with h5py.File(path, "r") as f:
            run = {k: f.attrs[k] for k in f.attrs}
            run["path"] = path
            run["fields"] = {
                f"{name}/{field}": f[name][field][()]
                for name in f
                if name != "times"
                for field in f[name]
                if field in FIELDS
            }
            if "times" in f:
                run["fields"]["times"] = f["times"][()]
            runs.append(run)
    return rest, sha, runs


def _stack(
    directory: str | Path,
    rest: dict[str, np.ndarray],
    sha: str,
    runs: list[dict[str, Any]],
    library: str,
) -> dict[str, np.ndarray]:
    """The runs' attributes and fields stacked along a leading axis of runs (by index)."""
    for run in runs:
        if run["rest_sha256"] != sha:
            raise InputError(
                f"{run['path']}: this run's rest mesh differs from the dataset's rest mesh (a "
                "mesh per sample): its fields cannot be stacked with the others; read each "
                f"run's file with {library} (its own <body>/points and <body>/cells)"
            )
    out: dict[str, Any] = dict(rest)
    runs = sorted(runs, key=lambda r: int(r["index"]))
    out["run_id"] = np.array([str(r["run_id"]) for r in runs])
    out["index"] = np.array([int(r["index"]) for r in runs], dtype=np.int64)
    keys = sorted({k for r in runs for k in r if k.startswith("param:")})
    for key in keys:
        out[key.removeprefix("param:")] = np.array([r.get(key) for r in runs])
    for key in sorted({k for r in runs for k in r["fields"]}):
        shapes = {r["fields"][key].shape for r in runs}
        if len(shapes) > 1:
            raise InputError(
                f"{directory}: the runs' {key} have different shapes {sorted(shapes)} (saved "
                "times that differ between runs: adaptive steps, a run that ended early); "
                f"read each run's file with {library}"
            )
        out[key] = np.stack([r["fields"][key] for r in runs]) if runs else np.empty((0,))
    return out
