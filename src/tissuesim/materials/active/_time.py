"""The time a law driven by time keeps itself (``prescribed_contraction.py``,
``kinematic_growth.py``): ``begin_step(h)`` sets the time of the step in progress to the last
accepted time plus h, ``accept_step`` makes it the accepted one (a rejected step is begun again
from the accepted time); the run starts at t = 0. And its parameters given as a number or an
expression of t (FEBio's value times its load curve, ``febio/curves.py``)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.validate import short

__all__ = ["TimeKept", "time_function"]


def time_function(law: str, key: str, value: object) -> Callable[[float], float]:
    """A parameter as given (a number or an expression string of t) -> f(t) -> float."""
    from tissuesim.errors import SceneError
    from tissuesim.scene.expressions import compile_expression

    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise MaterialError(
            f"{law}: {key} must be a number or an expression of t, not {short(value)}"
        )
    if not isinstance(value, str):
        v = float(value)
        if not np.isfinite(v):
            raise MaterialError(f"{law}: {key} must be finite, got {value!r}")
        return lambda t: v
    try:
        f = compile_expression(value, f"{law}: {key}")
    except SceneError as exc:
        raise MaterialError(str(exc)) from None
    origin = np.zeros((1, 3))

    def at(t: float) -> float:
        return float(np.asarray(f(origin, float(t))).reshape(-1)[0])

    at(0.0)  # an expression that fails fails here, not in the first step
    return at


class TimeKept:
    """The time of the accepted state and of the step in progress (a mixin)."""

    time: float = 0.0
    _trial: float = 0.0

    def begin_step(self, h: float) -> None:
        """A step of h s begins from the accepted time."""
        self._trial = self.time + float(h)

    def accept_step(self, F: np.ndarray) -> None:
        """The step in progress is accepted: its time is the law's."""
        self.time = self._trial

    def state_arrays(self) -> dict[str, np.ndarray]:
        """The law's state for a checkpoint: its time."""
        return {"time": np.array([self.time])}

    def set_state_arrays(self, arrays: dict[str, np.ndarray]) -> None:
        """The law's time from a checkpoint."""
        if "time" not in arrays:
            raise MaterialError(f"{getattr(self, 'name', 'law')}: no time in the saved state")
        self.time = self._trial = float(np.asarray(arrays["time"]).reshape(-1)[0])
