"""Many runs of one scene: parameter studies and training data (docs/guide/sweeps.md).

``tissuesim.sweep(scene, vary, out=DIR, ...)`` runs a study (this module is callable: it is
``tissuesim.sweep.sweep``); ``tissuesim.sweep.load_dataset(DIR)`` reads its fields into NumPy,
``tissuesim.sweep.load_table(DIR)`` its table. The parts: key paths (``keypaths.py``), values and
samplers (``samples.py``), one run in a worker (``runs.py``) and its mesh cache (``cache.py``),
executors (``executors.py``), the table (``results.py``), the fields dataset (``dataset.py``, its
Zarr writer ``dataset_zarr.py``), the study (``study.py``). Dask, pyarrow, h5py and zarr are
imported only where used (``pip install 'tissuesim[sweep]'``).
"""

from __future__ import annotations

import sys
import types
from pathlib import Path
from typing import Any

from tissuesim.sweep.dataset import load_dataset
from tissuesim.sweep.executors import executor_from_spec, process_pool
from tissuesim.sweep.runs import RunTask, execute_run
from tissuesim.sweep.samples import Interval, make_samples, parameters
from tissuesim.sweep.study import sweep

__all__ = [
    "sweep",
    "load_dataset",
    "load_table",
    "Interval",
    "RunTask",
    "execute_run",
    "executor_from_spec",
    "make_samples",
    "parameters",
    "process_pool",
]


def load_table(directory: str | Path) -> list[dict[str, Any]]:
    """The study's table (``runs.csv``'s rows, numbers as numbers) without pandas or pyarrow:
    one dict per run; with pandas, ``pandas.read_parquet(DIR / "runs.parquet")`` is the same."""
    import csv

    rows = []
    with open(Path(directory) / "runs.csv", newline="", encoding="utf-8") as f:
        for row in csv.DictReader(f):
            rows.append({k: _number(v) for k, v in row.items()})
    return rows


def _number(text: str) -> Any:
    if text == "":
        return None
    for convert in (int, float):
        try:
            return convert(text)
        except ValueError:
            pass
    return text


class _CallableModule(types.ModuleType):
    """``tissuesim.sweep(...)`` calls ``sweep``; ``tissuesim.sweep.load_dataset`` is the
    module's function: one name for the study and its helpers."""

    def __call__(self, *args: Any, **kwargs: Any) -> list[dict[str, Any]]:
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
