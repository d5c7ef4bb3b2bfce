"""The study's dataset of fields in Zarr (``dataset_format="zarr"``, ``--dataset-format zarr``;
zarr 3, imported only here): the groups, arrays and attributes of the HDF5 files
(dataset.py), one Zarr group (a directory) per run:

    fields/rest.zarr            <body>/points (n, d) float64, <body>/cells (m, k) int64: the
                                rest mesh the runs share (written once, by the first run);
                                attribute rest_sha256
    fields/<run_id>.zarr        <body>/displacement (n, d) float64, the cell fields asked for,
                                times (s,) with saved times; attributes run_id, index,
                                rest_sha256 and each parameter as "param:<key path>" (JSON: a
                                vector is a list); a run on another rest mesh also holds its
                                own <body>/points and <body>/cells

Each group is written by the worker that ran the run into a hidden temporary directory beside
it, its files fsynced, then renamed into place: no lock, no shared store between workers, and a
killed study leaves every finished run's group whole (a leftover ``.<run_id>.tmp-XXXXXXXX.zarr``
is hidden from ``load_dataset``). An array is one chunk, or with saved times one chunk per time
(zarr's default codec, Zstandard: lossless, the floats read back bit for bit). Each file of a
group is fsynced before the rename, as the HDF5 file is: with two bodies a run's group is 7
small files, and their fsyncs are half of its write time (30-40 ms a run on the loaded 2-core
development machine against 8-11 ms for the one HDF5 file, for a quarter of its size).
"""

from __future__ import annotations

import os
import secrets
import shutil
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError

__all__ = ["zarr_module", "write_run_fields_zarr", "read_zarr_runs"]


def zarr_module() -> Any:
    """zarr, or a one-line InputError saying how to install it."""
    try:
        import zarr
    except ImportError:
        raise InputError(
            "--dataset-format zarr needs zarr (3.x): pip install 'tissuesim[sweep]' (or zarr)"
        ) from None
    return zarr


def _tree_bytes(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def _fsync_tree(path: Path) -> None:
    for p in path.rglob("*"):
        if p.is_file():
            fd = os.open(p, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)


@contextmanager
def _atomic_group(target: Path) -> Iterator[Path]:
    """Yield a hidden temporary directory beside ``target``; on success its files are fsynced
    and it is renamed to ``target`` (an older ``target`` removed first: a run written again
    after a study was killed between its fields and its result). A ``target`` that appears
    meanwhile (another worker's rest.zarr) is kept and the temporary one removed."""
    tmp = target.with_name(f".{target.stem}.tmp-{secrets.token_hex(4)}{target.suffix}")
    try:
        yield tmp
        _fsync_tree(tmp)
        if target.exists() and target.stem != "rest":
            shutil.rmtree(target)
        try:
            os.rename(tmp, target)
        except OSError:
            if not target.is_dir():
                raise
            shutil.rmtree(tmp)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _write_array(group: Any, key: str, value: np.ndarray, frames: bool) -> None:
    value = np.ascontiguousarray(value)
    chunks = (1, *value.shape[1:]) if frames and value.ndim > 1 else value.shape
    group.create_array(key, data=value, chunks=tuple(max(1, c) for c in chunks) or None)


def write_run_fields_zarr(
    out: Path, task: Any, sim: Any, result: dict[str, Any], frames: list | None = None
) -> None:
    """``dataset.write_run_fields`` in Zarr: the group ``fields/<run_id>.zarr`` (and
    ``fields/rest.zarr`` if no run wrote it yet)."""
    from tissuesim.io.atomic import to_json_compatible
    from tissuesim.sweep.dataset_common import _rest, _sha, run_arrays, run_attributes

    zarr = zarr_module()
    start = time.perf_counter()
    folder = out / "fields"
    folder.mkdir(parents=True, exist_ok=True)
    rest = _rest(sim)
    sha = _sha(rest)
    shared = folder / "rest.zarr"
    if not shared.is_dir():
        with _atomic_group(shared) as tmp:
            group = zarr.open_group(tmp, mode="w", attributes={"rest_sha256": sha})
            for name, (points, cells) in rest.items():
                _write_array(group, f"{name}/points", points, False)
                _write_array(group, f"{name}/cells", cells, False)
    # read back, not assumed: another worker may have renamed its rest.zarr in first
    own_rest = zarr.open_group(shared, mode="r").attrs["rest_sha256"] != sha
    target = folder / f"{task.run_id}.zarr"
    attributes = to_json_compatible(run_attributes(task, sha))
    with _atomic_group(target) as tmp:
        group = zarr.open_group(tmp, mode="w", attributes=attributes)  # one zarr.json write
        for key, value in run_arrays(task, sim, list(rest), frames).items():
            _write_array(group, key, value, bool(frames) and key != "times")
        if own_rest:
            for name, (points, cells) in rest.items():
                _write_array(group, f"{name}/points", points, False)
                _write_array(group, f"{name}/cells", cells, False)
    result["fields_write_s"] = time.perf_counter() - start
    result["fields_bytes"] = _tree_bytes(target)


def read_zarr_runs(folder: Path) -> tuple[dict[str, np.ndarray], str, list[dict[str, Any]]]:
    """``dataset._read_h5_runs`` for the Zarr groups: the rest mesh, its hash and every run's
    attributes with its "fields" ({path: array}) and "path"."""
    from tissuesim.sweep.dataset_common import FIELDS

    zarr = zarr_module()
    group = zarr.open_group(folder / "rest.zarr", mode="r")
    sha = str(group.attrs["rest_sha256"])
    rest: dict[str, np.ndarray] = {}
    for name in sorted(group.group_keys()):
        rest[f"{name}/points"] = group[f"{name}/points"][...]
        rest[f"{name}/cells"] = group[f"{name}/cells"][...]
    paths = sorted(p for p in folder.glob("r[0-9]*.zarr") if p.is_dir())
    runs: list[dict[str, Any]] = []
    for path in paths:
        group = zarr.open_group(path, mode="r")
        run: dict[str, Any] = dict(group.attrs.asdict())
        run["path"] = path
        run["fields"] = {
            f"{name}/{field}": group[f"{name}/{field}"][...]
            for name in sorted(group.group_keys())
            for field in sorted(group[name].array_keys())
            if field in FIELDS
        }
        if "times" in set(group.array_keys()):
            run["fields"]["times"] = group["times"][...]
        runs.append(run)
    return rest, sha, runs
