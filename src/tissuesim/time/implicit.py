"""The start of every implicit step: Newton begins at the candidate of lowest energy."""

from __future__ import annotations

import numpy as np

__all__ = ["choose_start"]


def choose_start(evaluate, candidates, apply_prescribed) -> np.ndarray:
    """The candidate (with prescribed values applied) of lowest energy; ties and NaN: the
    first. One candidate is returned without evaluating it."""
    starts = []
    for guess in candidates:
        x0 = apply_prescribed(guess)
        value = evaluate(x0, 0, False).value if len(candidates) > 1 else 0.0
        starts.append((np.nan_to_num(value, nan=np.inf), len(starts), x0))
    return min(starts, key=lambda s: (s[0], s[1]))[2]
