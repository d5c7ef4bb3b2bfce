"""Row reductions and the row-wise unique by one int64 key per row (mesh/rows.py): the same
results as numpy's own, also where the rows' range is too wide for a key."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.mesh.rows import row_keys, row_max, rows_all, rows_any, unique_rows

OPTIONS = [
    {},
    {"return_inverse": True},
    {"return_inverse": True, "return_counts": True},
    {"return_index": True, "return_inverse": True, "return_counts": True},
]


@pytest.mark.parametrize("options", OPTIONS)
@pytest.mark.parametrize("high", [20, 2**40])  # keys fit / too wide: numpy's row-wise unique
@pytest.mark.parametrize("shape", [(500, 3), (40, 2), (0, 3)])
def test_unique_rows_is_numpys_unique_along_rows(shape, high, options):
    rows = np.random.default_rng(0).integers(0, high, shape) - high // 2
    if shape[0]:
        rows[shape[0] // 2 :] = rows[: shape[0] - shape[0] // 2]  # duplicates
    assert (row_keys(rows) is None) == (high > 2**30 and shape[0] > 0)
    mine, theirs = unique_rows(rows, **options), np.unique(rows, axis=0, **options)
    if not options:
        assert np.array_equal(mine, theirs)
        return
    assert len(mine) == len(theirs)
    for a, b in zip(mine, theirs, strict=True):
        assert np.array_equal(a, b if b.ndim != 2 or a.ndim == 2 else b.reshape(-1))


def test_row_reductions_are_numpys():
    a = np.random.default_rng(1).normal(size=(50, 4))
    assert np.array_equal(row_max(a), a.max(axis=1))
    b = a > 0
    assert np.array_equal(rows_all(b), b.all(axis=1))
    assert np.array_equal(rows_any(b), b.any(axis=1))
