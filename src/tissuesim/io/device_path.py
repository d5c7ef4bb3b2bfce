"""A recorded instrument path for ``tissuesim play --path FILE`` and ``LiveSession``: a CSV of
time (s) and the instrument's translation (m) from its rest place, optionally its rotation
vector (rad) about its rest centroid, one row per sample:

    time_s,x_m,y_m,z_m[,rx_rad,ry_rad,rz_rad]
    0.0,0,0,0
    0.35,0,0,-0.007

A header row (any row whose first field is not a number) is skipped; times must increase.
Between samples the path is linear; before the first and after the last it holds still.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tissuesim.errors import InputError

__all__ = ["DevicePath", "read_device_path"]


@dataclass(frozen=True)
class DevicePath:
    """``times`` (k,) s, increasing; ``translations`` (k, 3) m; ``rotations`` (k, 3) rad or
    None."""

    times: np.ndarray
    translations: np.ndarray
    rotations: np.ndarray | None = None

    def translation(self, t: float) -> np.ndarray:
        return np.array([np.interp(t, self.times, c) for c in self.translations.T])

    def rotation(self, t: float) -> np.ndarray | None:
        if self.rotations is None:
            return None
        return np.array([np.interp(t, self.times, c) for c in self.rotations.T])


def read_device_path(path: str | Path) -> DevicePath:
    """The DevicePath in the CSV ``path`` (module docstring); an InputError naming the file
    and line on anything else."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such device path file (a CSV of time_s,x_m,y_m,z_m rows)")
    rows, width = [], None
    for number, line in enumerate(path.read_text(errors="replace").splitlines(), start=1):
        fields = [f.strip() for f in line.split(",")]
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            values = [float(f) for f in fields]
        except ValueError:
            if not rows and width is None:  # a header
                width = 0
                continue
            raise InputError(
                f"{path}, line {number}: {line.strip()[:60]!r} is not numbers; each row is "
                "time_s,x_m,y_m,z_m[,rx_rad,ry_rad,rz_rad]"
            ) from None
        if len(values) not in (4, 7):
            raise InputError(
                f"{path}, line {number}: {len(values)} columns; give 4 (time, x, y, z) or 7 "
                "(with a rotation vector rx, ry, rz)"
            )
        if rows and len(values) != len(rows[0]):
            raise InputError(f"{path}, line {number}: {len(values)} columns, the rows above have "
                             f"{len(rows[0])}")  # fmt: skip
        if not np.all(np.isfinite(values)):
            raise InputError(f"{path}, line {number}: a value is not finite")
        if rows and values[0] <= rows[-1][0]:
            raise InputError(
                f"{path}, line {number}: time {values[0]:g} s does not increase (the row above "
                f"has {rows[-1][0]:g} s)"
            )
        rows.append(values)
    if not rows:
        raise InputError(f"{path}: no samples (rows of time_s,x_m,y_m,z_m)")
    data = np.array(rows)
    return DevicePath(data[:, 0], data[:, 1:4], data[:, 4:7] if data.shape[1] == 7 else None)
