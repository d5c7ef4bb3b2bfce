"""The instrument's linearised force (contact/readout/haptics.py): the derivative of the step's
solution force with respect to the instrument's translation, against central differences of
re-solved steps, and the errors of asking for it where it does not exist."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError

pytest.importorskip("ipctk")

from test_interactive import pressed_block  # noqa: E402  (pytest puts this folder on the path)

TIGHT = ts.NewtonOptions(gradient_tolerance=1e-12, absolute_tolerance=1e-14)
#: the probe's driven path: down into the block, then a little sideways
PATH = [(0.0, 0.0, -2e-4), (0.0, 0.0, -4e-4), (1e-4, 0.0, -5e-4)]


def pressed(last_offset, friction: float, friction_iterations: int, frozen_lag=None):
    """The block pressed along PATH, the last target moved by ``last_offset``; ``frozen_lag``
    (a list) receives the arguments of the last step's last friction lag, or, when it already
    holds them, the last step uses that lag instead of its own (the lag held fixed, as K is)."""
    sim = pressed_block(TIGHT, friction=friction)
    sim.set_contact(dhat=1e-4, friction=friction, friction_iterations=friction_iterations)
    for k, u in enumerate(PATH):
        last = k == len(PATH) - 1
        offset = last_offset if last else 0.0
        sim.drive_obstacle("probe", translation=np.add(u, offset))
        if last and frozen_lag is not None:
            _step_with_lag(sim, frozen_lag)
        else:
            sim.step()
    return sim


def _step_with_lag(sim, frozen_lag: list) -> None:
    """Record (``frozen_lag`` empty) or replay (it holds [V_start, V_lag]) the step's last lag."""
    model = type(sim.system.contact)
    original = model.lag_friction
    replay = len(frozen_lag) == 2
    calls = []

    def lag(self, V_start, V_lag, h):
        calls.append(1)
        if replay:
            return original(self, V_start, frozen_lag[1], h)
        frozen_lag[:] = [V_start, np.array(V_lag)]
        return original(self, V_start, V_lag, h)

    try:
        model.lag_friction = lag
        sim.step()
    finally:
        model.lag_friction = original
    if not replay:
        frozen_lag.append(len(calls))  # the lags of the step: at its start, then re-lags


def _central_difference(axis: int, delta: float, friction, iterations, frozen_lag):
    d = np.zeros(3)
    d[axis] = delta
    columns = []
    for sign in (1.0, -1.0):
        lag = None if frozen_lag is None else frozen_lag[:2]
        columns.append(np.array(pressed(sign * d, friction, iterations, lag).forces()["probe"]))
    return (columns[0] - columns[1]) / (2 * delta)


@pytest.mark.parametrize(("friction", "iterations"), [(0.0, 1), (0.3, 1), (0.3, 2)])
def test_the_linearised_force_is_the_derivative_of_the_solved_force(friction, iterations):
    """Central differences of the step re-solved with the probe moved by +-50 nm per axis and
    the friction lagged as in the step (at its start, or where it was re-lagged inside it): K is
    the derivative of the force at the step's lag, which the haptic loop holds between steps."""
    frozen_lag = [] if iterations > 1 else None
    sim = pressed(np.zeros(3), friction, iterations, frozen_lag)
    assert frozen_lag is None or frozen_lag[2] == 2  # lagged at the start, re-lagged once
    lin = sim.instrument_linearization("probe")
    assert np.allclose(lin.force, sim.forces()["probe"])
    assert lin.force[2] < -0.01  # pressed down into the block
    assert np.allclose(lin.stiffness, lin.stiffness.T)
    for axis in range(3):
        column = _central_difference(axis, 5e-8, friction, iterations, frozen_lag)
        error = np.linalg.norm(column - lin.stiffness[:, axis])
        assert error <= 1e-4 * np.linalg.norm(lin.stiffness[:, axis]), (axis, column)
    assert lin.stiffness[2, 2] > 10.0  # N/m: pressing further pushes back
    # the rendered force: the passive (PSD) stiffness, its compliance its inverse where touched
    P = lin.passive_stiffness
    assert np.all(np.linalg.eigvalsh(P) >= -1e-9 * np.abs(lin.stiffness).max())
    d = np.array([1e-6, -2e-6, -3e-6])
    assert np.allclose(lin.force_at(d), lin.force + P @ d)
    assert np.allclose(lin.force_at(d, passive=False), lin.force + lin.stiffness @ d)
    assert np.allclose(P @ lin.compliance @ P, P, atol=1e-9 * np.abs(P).max())


def test_without_contact_the_stiffness_is_zero():
    sim = pressed_block(TIGHT)
    sim.step()  # the probe hangs 0.2 mm above the block
    lin = sim.instrument_linearization("probe")
    assert np.all(lin.force == 0.0)
    assert np.all(lin.stiffness == 0.0)


def test_asking_where_there_is_no_linearisation_says_why():
    sim = pressed_block(TIGHT)
    with pytest.raises(InputError, match=r"take a step\(\) first"):
        sim.instrument_linearization("probe")
    sim.step()
    with pytest.raises(InputError, match="no obstacle 'needle' .*obstacles: probe"):
        sim.instrument_linearization("needle")
    with pytest.raises(InputError, match="displacement must be 3 finite numbers"):
        sim.instrument_linearization("probe").force_at([0.0, np.nan, 0.0])
