"""FEBio's ``constrained levmar`` (febio/optimize/levmar_bc.py: levmar's box-constrained
Levenberg-Marquardt as FEBio calls dlevmar_bc_dif): fits against SciPy's bounded least
squares, levmar's stopping rules, its forward-difference steps."""

import numpy as np
import pytest
from scipy.optimize import least_squares

from tissuesim.febio.optimize.levmar_bc import boxed_levenberg_marquardt
from tissuesim.febio.optimize.run import _constrained_levmar
from tissuesim.febio.optimize.task import OptimizeTask, Parameter

X = np.linspace(0.0, 1.0, 12)
DATA = 2.0 * np.exp(1.3 * X) + 0.01 * np.sin(7 * X)  # a near-exponential curve


def model(p):
    return p[0] * np.exp(p[1] * X)


def residuals(p):
    return model(p) - DATA


def jacobian(p):
    return np.column_stack([np.exp(p[1] * X), p[0] * X * np.exp(p[1] * X)])


@pytest.mark.parametrize("upper", [(10.0, 10.0), (10.0, 1.2)])  # optimum inside; b held
def test_the_fit_is_scipys_bounded_least_squares(upper):
    """Tight tolerances: SciPy's bounded least squares' fit (a bound met exactly); on the
    bound the projected steps zigzag (a few hundred iterations), as levmar's do."""
    lower = np.array([0.1, 0.1])
    fit = boxed_levenberg_marquardt(residuals, jacobian, np.array([1.0, 0.5]), lower,
                                    np.array(upper), eps=(1e-9, 1e-12, 1e-12),
                                    itmax=1000)  # fmt: skip
    ref = least_squares(residuals, [1.0, 0.5], jac=jacobian, bounds=(lower, upper),
                        xtol=1e-15, ftol=1e-15, gtol=1e-15)  # fmt: skip
    assert fit.converged, fit.reason
    np.testing.assert_allclose(fit.p, ref.x, rtol=1e-7)
    assert fit.objective == pytest.approx(2 * ref.cost, rel=1e-10)
    if upper[1] < 1.3:
        assert fit.p[1] == upper[1]  # on the bound, exactly (projected)
        assert {"LM", "projected gradient"} <= {h["step"] for h in fit.history}


def test_febios_tolerance_stops_on_a_short_step():
    """With FEBio's obj_tol 1e-3 as eps1, eps2 and eps3 (FEConstrainedLMOptimizeMethod), the
    projected step along the bound becomes shorter than 1e-3 |p| while the objective is 8x
    its minimum: levmar stops there (2), and so does tissuesim, where FEBio would (op01's
    objective is FEBio's within 0.6 % by this loop and levmar's differences)."""
    fit = boxed_levenberg_marquardt(residuals, jacobian, np.array([1.0, 0.5]), [0.1, 0.1],
                                    [10.0, 1.2], eps=(1e-3, 1e-3, 1e-3))  # fmt: skip
    assert (fit.reason, fit.iterations) == (2, 3)
    ref = least_squares(residuals, [1.0, 0.5], jac=jacobian, bounds=([0.1, 0.1], [10, 1.2]))
    assert fit.objective > 5 * 2 * ref.cost


def test_rosenbrock_in_a_box_needs_more_than_plain_steps():
    """Rosenbrock's valley from (-1.2, 1), x held in [-1.5, 0.5]: the constrained minimum
    (0.5, 0.25) is SciPy's, the steps taken are recorded by kind."""

    def r(p):
        return np.array([10.0 * (p[1] - p[0] ** 2), 1.0 - p[0]])

    def J(p):
        return np.array([[-20.0 * p[0], 10.0], [-1.0, 0.0]])

    lower, upper = np.array([-1.5, -5.0]), np.array([0.5, 5.0])
    fit = boxed_levenberg_marquardt(r, J, np.array([-1.2, 1.0]), lower, upper,
                                    eps=(1e-14, 1e-14, 1e-14), itmax=500)  # fmt: skip
    ref = least_squares(r, [-1.2, 1.0], jac=J, bounds=(lower, upper), xtol=1e-15, ftol=1e-15)
    np.testing.assert_allclose(fit.p, ref.x, atol=1e-7)
    np.testing.assert_allclose(fit.p, [0.5, 0.25], atol=1e-7)
    assert {h["step"] for h in fit.history} <= {"LM", "line search", "projected gradient"}


def test_levmars_stopping_rules():
    """|e|^2 <= eps3 before any step: 0 iterations (6); a step below eps2 |p| (2); the
    iteration limit (3)."""
    start = np.array([2.0, 1.3])
    small = boxed_levenberg_marquardt(residuals, jacobian, start, [0.1, 0.1], [10, 10],
                                      eps=(1e-20, 1e-20, 1.0))  # fmt: skip
    assert (small.iterations, small.reason) == (0, 6)
    assert np.array_equal(small.p, start)
    step = boxed_levenberg_marquardt(residuals, jacobian, start, [0.1, 0.1], [10, 10],
                                     eps=(1e-20, 1e-2, 1e-20))  # fmt: skip
    assert step.reason == 2
    limit = boxed_levenberg_marquardt(residuals, jacobian, np.array([1.0, 0.5]), [0.1, 0.1],
                                      [10, 10], eps=(1e-30, 1e-30, 1e-30), itmax=2)  # fmt: skip
    assert (limit.iterations, limit.reason) == (2, 3)


class _Recorder:
    """A stand-in for the FEBio objective: the points each run is asked at."""

    gradients = "differences"

    def __init__(self):
        self.asked, self.runs, self.last_a = [], 0, None

    def _residuals(self, a, derivatives):
        self.asked.append(np.array(a))
        self.runs += 1
        return residuals(a), None


def test_forward_differences_step_as_levmar_does():
    """With gradients "differences" each Jacobian moves parameter j by max(1e-4 |p_j|,
    f_diff_scale) from the point the last accepted run was at (levmar's forward
    differences), and parameters are clamped to their bounds before a run, as FEBio's
    objective does."""
    task = OptimizeTask(source="t.feb", method="constrained levmar", obj_tol=1e-10,
                        f_diff_scale=1e-3, max_iter=3)  # fmt: skip
    task.parameters = [Parameter(n, 1.0, 0.1, 50.0, 1.0, None) for n in ("a", "b")]
    rec = _Recorder()
    a0 = np.array([20.0, 0.5])
    _constrained_levmar(rec, a0, np.array([0.1, 0.1]), np.array([50.0, 10.0]), task,
                        lambda line: None)  # fmt: skip
    first, moved_a, moved_b = rec.asked[:3]
    np.testing.assert_array_equal(first, a0)
    np.testing.assert_allclose(moved_a - a0, [max(1e-4 * 20.0, 1e-3), 0.0], rtol=1e-12)
    np.testing.assert_allclose(moved_b - a0, [0.0, 1e-3], rtol=1e-12)
    assert all((p >= [0.1, 0.1]).all() and (p <= [50.0, 10.0]).all() for p in rec.asked)


def test_the_line_search_fits_a_quadratic_on_its_first_backtrack():
    """levmar's line search (Schnabel's lnsrch): for f = |e|^2 / 2 with e = p, a step that
    overshoots three-fold (to -2 p) is cut by the quadratic through f(p), f'(p) and the
    failed trial, lambda = 1/3: the minimum, exactly, at its second evaluation; a step that
    does not descend far enough returns nothing once lambda is below its tolerance."""
    from tissuesim.febio.optimize.levmar_bc import _line_search

    calls = []

    def objective_at(q):
        calls.append(q.copy())
        e = -np.asarray(q, dtype=float)
        return e, float(e @ e)

    p = np.array([0.7, -0.4])
    found = _line_search(objective_at, lambda q: q, p, float(p @ p), p, -3.0 * p, 1e3)
    assert found is not None and len(calls) == 2
    np.testing.assert_allclose(found[0], 0.0, atol=1e-15)
    calls.clear()
    # an ascent direction never satisfies the sufficient decrease: lambda shrinks to nothing
    assert _line_search(objective_at, lambda q: q, p, float(p @ p), p, 1e-3 * p, 1e3) is None
