"""Issue 41: two 2D bodies in contact (quasistatic, friction): the body-to-body forces are
3-vectors (z = 0) like the supports', and forces.csv holds them (the run crashed at its end in
force_table: a (2,) force into a (3,) row)."""

from __future__ import annotations

import csv

import pytest

import tissuesim as ts
from tissuesim.io.forces import force_table

pytest.importorskip("ipctk")

MATERIAL = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)


def pressed_squares() -> ts.Simulation:
    sim = ts.Simulation(integrator="quasistatic", time_step=0.1, gravity=(0.0, -9.81))
    low = sim.add_body("low", ts.rectangle((0, 0), (1, 0.3), (6, 2)), MATERIAL, density=100.0)
    sim.add_body("high", ts.rectangle((0.2, 0.305), (0.8, 0.6), (4, 2)), MATERIAL, density=100.0)
    sim.fix("low", ts.select.vertices_on_plane(low.mesh, axis=1, value=0.0), name="support")
    sim.set_contact(dhat=0.01, friction=0.3)
    return sim


def test_2d_body_to_body_forces_are_written_to_forces_csv(tmp_path):
    sim = pressed_squares()
    sim.run(2, output=tmp_path, progress=False)
    forces = sim.history[-1].extra["forces"]
    assert len(forces["low.contact.high"]) == 3 and forces["low.contact.high"][2] == 0.0
    with open(tmp_path / "forces.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2
    on_low = float(rows[-1]["low.contact.high_y_N"])
    assert on_low < 0  # the upper square presses the lower one down
    assert float(rows[-1]["high.contact.low_y_N"]) == pytest.approx(-on_low)
    assert float(rows[-1]["low.contact.high_z_N"]) == 0.0


def test_force_table_takes_2_component_forces():
    class Record:
        def __init__(self, time, forces):
            self.time, self.extra = time, {"forces": forces}

    names, times, table = force_table([Record(0.1, {"a": [1.0, 2.0]})])
    assert names == ["a"] and table[0, 0].tolist() == [1.0, 2.0, 0.0]
