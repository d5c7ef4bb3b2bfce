"""A rejected attempt's augmentations are undone (``time/attempts/history.py``): the halved
step starts from the last accepted multipliers, as FEBio's restart from its dump does."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from tissuesim.time.attempts.history import begin_attempt, end_attempt
from tissuesim.time.state import State, StepOutcome


def _system():
    passed = SimpleNamespace(multipliers=np.array([1.0, 2.0]), weights=np.array([0.5, 0.5]),
                             tie=(np.array([0]), np.array([3])), friction=None)  # fmt: skip
    pair = SimpleNamespace(passes=[passed], augmentations=0)
    joint = SimpleNamespace(multipliers=np.array([7.0]), augmentations=1)
    return SimpleNamespace(penalty_contacts=[pair], joints=[joint], bodies=()), passed, joint


def _augment(passed, joint) -> None:
    passed.multipliers += 10.0  # in place, as an augmentation may be
    passed.weights = np.array([0.6, 0.4])
    passed.tie = (np.array([0, 1]), np.array([3, 4]))
    joint.multipliers = np.array([9.0])
    joint.augmentations = 4


def test_a_rejected_attempt_leaves_the_lags_as_they_were():
    system, passed, joint = _system()
    state = State(0.0, np.zeros(3), np.zeros(3))
    begin_attempt(system, state, 0.1)
    _augment(passed, joint)
    end_attempt(system, StepOutcome(None, False))
    assert np.array_equal(passed.multipliers, [1.0, 2.0])
    assert np.array_equal(passed.weights, [0.5, 0.5])
    assert np.array_equal(passed.tie[0], [0]) and np.array_equal(passed.tie[1], [3])
    assert np.array_equal(joint.multipliers, [7.0]) and joint.augmentations == 1


def test_an_accepted_attempt_keeps_its_augmentations():
    system, passed, joint = _system()
    state = State(0.0, np.zeros(3), np.zeros(3))
    begin_attempt(system, state, 0.1)
    _augment(passed, joint)
    end_attempt(system, StepOutcome(State(0.1, np.zeros(3), np.zeros(3)), True))
    assert np.array_equal(passed.multipliers, [11.0, 12.0])
    assert np.array_equal(joint.multipliers, [9.0]) and joint.augmentations == 4
    # the next rejected attempt goes back to these, not to the first ones
    begin_attempt(system, state, 0.1)
    passed.multipliers = np.zeros(2)
    end_attempt(system, StepOutcome(None, False))
    assert np.array_equal(passed.multipliers, [11.0, 12.0])
