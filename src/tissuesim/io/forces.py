"""Forces per step as a table: ``forces.csv`` (time, then x, y, z columns per named force, N) and
``forces.png`` (the force curves: one panel per force, its components and magnitude against
time, units on both axes; for a sphere probe (an obstacle with an indentation depth), also
its force's magnitude against that depth)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from tissuesim.io.atomic import atomic_output, write_text_atomic

__all__ = ["force_table", "write_forces_csv", "render_forces_png"]


def force_table(history: Sequence) -> tuple[list[str], np.ndarray, np.ndarray]:
    """(names, times (k,), forces (k, len(names), 3)) from step records' extra["forces"]."""
    names: list[str] = []
    for r in history:
        for name in r.extra.get("forces", {}):
            if name not in names:
                names.append(name)
    times = np.array([r.time for r in history], dtype=float)
    table = np.full((len(history), len(names), 3), np.nan)
    for i, r in enumerate(history):
        for j, name in enumerate(names):
            if name in r.extra.get("forces", {}):
                # a 2D force (2 components) fills x, y; z stays 0
                f = np.asarray(r.extra["forces"][name], dtype=float).ravel()
                table[i, j] = 0.0
                table[i, j, : f.size] = f
    return names, times, table


def _unit(name: str) -> str:
    """N for a force, Nm for a rigid body's moment (``<name>.moment``)."""
    return "Nm" if name.endswith(".moment") else "N"


def write_forces_csv(path: str | os.PathLike[str], history: Sequence) -> Path:
    names, times, table = force_table(history)
    header = ["time_s"] + [f"{n}_{c}_{_unit(n)}" for n in names for c in "xyz"]
    rows = [",".join(header)]
    for i, t in enumerate(times):
        rows.append(",".join([repr(float(t))] + [repr(float(f)) for f in table[i].ravel()]))
    return write_text_atomic(Path(path), "\n".join(rows) + "\n")


def depth_table(history: Sequence, names: list[str]) -> dict[str, np.ndarray]:
    """Per force name that is also an obstacle with an indentation depth: depths (k,) in m
    (NaN where a step has none), from extra["contact"]["indentation_depth"]."""
    out: dict[str, np.ndarray] = {}
    for i, r in enumerate(history):
        depths = (r.extra.get("contact") or {}).get("indentation_depth") or {}
        for name, d in depths.items():
            if name in names:
                out.setdefault(name, np.full(len(history), np.nan))[i] = d
    return out


def render_forces_png(path: str | os.PathLike[str], history: Sequence) -> Path | None:
    """The force curves, or None when there is no force to draw."""
    names, times, table = force_table(history)
    if not names or not len(times):
        return None
    from matplotlib.figure import Figure

    depths = depth_table(history, names)
    n = len(names)
    fig = Figure(figsize=(7.0, 2.2 * (n + len(depths)) + 0.6), layout="constrained")
    grid = fig.subplots(n + len(depths), 1, squeeze=False)[:, 0]
    axes = grid[:n]
    for ax in axes[1:]:
        ax.sharex(axes[0])
    for ax, name in zip(grid[n:], depths, strict=True):
        d = depths[name]
        f = np.linalg.norm(table[:, names.index(name)], axis=1)
        ax.plot(d * 1e3, f, "o-", color="k", lw=1.4, ms=3, label="|F|")
        ax.set_xlabel("indentation depth (mm)")
        ax.set_ylabel("force (N)")
        ax.set_title(f"{name}: force against indentation depth", loc="left", fontsize=10)
        ax.grid(alpha=0.3)
    for ax, name, forces in zip(axes, names, np.swapaxes(table, 0, 1), strict=True):
        for k, (label, colour) in enumerate(
            zip("xyz", ("#1f77b4", "#2ca02c", "#d62728"), strict=True)
        ):
            symbol = "M" if _unit(name) == "Nm" else "F"
            ax.plot(times, forces[:, k], color=colour, lw=1.2, label=f"${symbol}_{label}$")
        magnitude = "|M|" if _unit(name) == "Nm" else "|F|"
        ax.plot(times, np.linalg.norm(forces, axis=1), color="k", lw=1.6, ls="--", label=magnitude)
        ax.set_ylabel("moment (N m)" if _unit(name) == "Nm" else "force (N)")
        ax.set_title(name, loc="left", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8, ncols=4)
    for ax in axes:
        ax.set_xlabel("time (s)")
    path = Path(path)
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    return path
