"""ipctk's threads (TISSUESIM_CONTACT_THREADS): one thread makes contact runs bit for bit
reproducible; a bad value is refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.obstacles import plane
from tissuesim.errors import InputError


def _drop() -> np.ndarray:
    mesh = ts.box((0.0, 0.0, 0.001), (0.02, 0.02, 0.021), (2, 2, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, time_step=0.01, gravity=(0, 0, -9.81))
    sim.set_contact(dhat=1e-3)
    sim.add_obstacle("floor", plane((0.01, 0.01, 0.0), (0.0, 0.0, 1.0), 0.1))
    for _ in range(4):
        sim.step()
    return sim.positions.copy()


@pytest.fixture
def threads(monkeypatch):
    import ipctk

    before = ipctk.get_num_threads()
    yield monkeypatch
    ipctk.set_num_threads(before)


def test_one_contact_thread_repeats_a_run_bit_for_bit(threads):
    threads.setenv("TISSUESIM_CONTACT_THREADS", "1")
    first = _drop()
    assert first[:, 2].min() < 0.001  # it fell onto the floor
    assert np.array_equal(first, _drop())


@pytest.mark.parametrize("value", ["two", "0", "-1"])
def test_a_bad_thread_count_is_refused_in_one_line(threads, value):
    threads.setenv("TISSUESIM_CONTACT_THREADS", value)
    with pytest.raises(InputError, match="TISSUESIM_CONTACT_THREADS"):
        _drop()
