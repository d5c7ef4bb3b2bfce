"""The start of every implicit step: Newton begins at the candidate of lowest energy."""

from __future__ import annotations

import numpy as np

__all__ = ["choose_start"]


def choose_start(evaluate, candidates, apply_prescribed, keep: bool = False):
    """The candidate (with prescribed values applied) of lowest energy; ties and NaN: the
    first. One candidate is returned without evaluating it.

    keep: evaluate the candidates with their gradients and return (start, its accumulator),
    which Newton starts from instead of evaluating the start again (when nothing changes the
    energy in between: no contact stiffness set at the start, no lag)."""
    starts = []
    for guess in candidates:
        x0 = apply_prescribed(guess)
        acc = evaluate(x0, 1 if keep else 0, False) if keep or len(candidates) > 1 else None
        value = 0.0 if acc is None else acc.value
        starts.append((np.nan_to_num(value, nan=np.inf), len(starts), x0, acc))
    best = min(starts, key=lambda s: (s[0], s[1]))
    return (best[2], best[3]) if keep else best[2]
