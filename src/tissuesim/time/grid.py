"""Times on the step grid: a time too large for its steps to be resolved is refused."""

from __future__ import annotations

from tissuesim.errors import InputError

__all__ = ["check_time_resolution"]


def check_time_resolution(t: float, h: float, what: str) -> None:
    """Refuse a time so large that steps of h are lost to round-off (t + h == t, or h
    resolved to worse than 1e-3 of itself): every frame would carry the same time."""
    if abs(t) * 2.0**-52 > 1e-3 * h:
        raise InputError(
            f"{what} {t:g} s is too large for time_step {h:g} s: a double cannot resolve steps of "
            f"{h:g} s at t = {t:g} s; count time from 0 (start_time = 0)"
        )
