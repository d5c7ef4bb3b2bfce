"""Third-party log lines kept off stderr: the IPC Toolkit (ipctk) logs warnings of its own
numerics through spdlog (``[ipctk] [warning] Initial distance 0 <= d_min=0, returning toi=0!``)
straight to stdout, between tissuesim's progress lines and into the JSON report of
``tissuesim run``. tissuesim reports what they
mean in its own words (a step that cannot move, a start that intersects), so ipctk is set to
log errors only. VTK's warnings are quieted where PyVista is imported (render/pyvista3d.py)."""

from __future__ import annotations

import importlib.util

__all__ = ["quiet_ipctk"]

_done = False  # once per process: the level is ipctk's global state


def quiet_ipctk() -> None:
    """ipctk logs errors only (its warnings and info lines are dropped); a no-op without
    ipctk, and after the first call."""
    global _done
    if _done or importlib.util.find_spec("ipctk") is None:
        return
    import ipctk

    ipctk.set_logger_level(ipctk.LoggerLevel.error)
    _done = True
