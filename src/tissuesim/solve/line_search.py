"""Newton's backtracking line search on the incremental potential (``newton.py``)."""

from __future__ import annotations

import numpy as np

__all__ = ["line_search"]


def line_search(
    evaluate, x, acc, slope, dx, options, retract, noise_scale, first=1.0, path_free=None
):
    """Backtracking: the largest alpha in 1, 1/2, ... with Armijo decrease and finite Phi.

    A trial may exceed the Armijo bound by Phi's round-off, 1e-12 times the largest of |Phi|,
    the sum of its terms' magnitudes and the model's energy scale: near the solution the true
    decrease of the last, correct step is below what Phi can resolve. ``first``: the first
    trial (below 1 when contact's CCD limits the step); ``path_free``: a trial whose move from x
    is not free of intersection is halved before it is evaluated."""
    alpha = first
    value = acc.value
    magnitude = max(abs(value), sum(abs(v) for v in acc.terms.values()), noise_scale)
    noise = 1e-12 * max(magnitude, 1e-300)
    for _ in range(options.max_line_search):
        y = retract(x, alpha * dx)
        if path_free is not None and not path_free(x, y):
            alpha *= 0.5
            continue
        trial = evaluate(y, 1, False)
        if (
            np.isfinite(trial.value)
            and trial.value <= value + options.armijo * alpha * slope + noise
        ):
            return alpha, trial
        alpha *= 0.5
    return None
