"""The instrument's linearised force (contact/haptics.py): the derivative of the step's
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


def pressed(last_offset, friction: float, friction_iterations: int):
    sim = pressed_block(TIGHT, friction=friction)
    sim.set_contact(dhat=1e-4, friction=friction, friction_iterations=friction_iterations)
    for k, u in enumerate(PATH):
        offset = last_offset if k == len(PATH) - 1 else 0.0
        sim.drive_obstacle("probe", translation=np.add(u, offset))
        sim.step()
    return sim


@pytest.mark.parametrize(
    ("friction", "iterations", "tolerance"), [(0.0, 1, 1e-4), (0.3, 1, 1e-4), (0.3, 2, 5e-2)]
)
def test_the_linearised_force_is_the_derivative_of_the_solved_force(
    friction, iterations, tolerance
):
    """Central differences of the step re-solved with the probe moved by +-0.2 um per axis:
    exact with the friction lagged at the step's start, within 5 % when it is re-lagged inside
    the step (the lag then moves with the probe; K holds it)."""
    sim = pressed(np.zeros(3), friction, iterations)
    lin = sim.instrument_linearization("probe")
    assert np.allclose(lin.force, sim.forces()["probe"])
    assert lin.force[2] < -0.01  # pressed down into the block
    assert np.allclose(lin.stiffness, lin.stiffness.T)
    delta = 2e-7
    for axis in range(3):
        d = np.zeros(3)
        d[axis] = delta
        plus = np.array(pressed(d, friction, iterations).forces()["probe"])
        minus = np.array(pressed(-d, friction, iterations).forces()["probe"])
        column = (plus - minus) / (2 * delta)
        error = np.linalg.norm(column - lin.stiffness[:, axis])
        assert error <= tolerance * np.linalg.norm(lin.stiffness[:, axis]), (axis, column)
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
