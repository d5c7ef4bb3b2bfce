"""``tissuesim identify SCENE``: a scene's [identify] table (identification/scene.py) fitted
by the command line, its files, and its one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tissuesim.cli import main
from tissuesim.errors import SceneError
from tissuesim.identification.scene import read_identify_scene

SCENE = """
[mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [1.0, 1.0, 1.0]
divisions = [2, 2, 2]

[material]
model = "neo_hookean"
youngs_modulus = {E}
poisson_ratio = 0.3

[simulation]
integrator = "quasistatic"
time_step = 0.25

[[dirichlet]]
vertices = {{ on_plane = {{ axis = 2, value = 0.0 }} }}
components = [2]
name = "table"

[[dirichlet]]
vertices = {{ in_box = {{ lower = [-0.01, -0.01, -0.01], upper = [0.01, 0.01, 0.01] }} }}
name = "pin"

[[dirichlet]]
vertices = {{ on_plane = {{ axis = 2, value = 1.0 }} }}
displacement = ["0", "0", "-0.1 * t"]
components = [2]
name = "platen"

[run]
steps = 4
"""

IDENTIFY = """
[identify]
steps = 4
parameters = { "material.youngs_modulus" = [2e4, 1e3, 1e6] }
observations = [ { reaction = "platen", component = 2 } ]
data = "measured.csv"
"""


def _measured(tmp_path, E):
    """The platen's force of the scene at E, as a CSV of measurements."""
    (tmp_path / "truth.toml").write_text(SCENE.format(E=E))
    from tissuesim.scene.loader import load_scene

    sim = load_scene(tmp_path / "truth.toml").simulation
    rows = ["step,platen_z"]
    for n in range(4):
        sim.step()
        rows.append(f"{n + 1},{sim.forces()['platen'][2]!r}")
    (tmp_path / "measured.csv").write_text("\n".join(rows) + "\n")


def test_identify_command_fits_the_scenes_modulus_and_writes_its_files(tmp_path, capsys):
    _measured(tmp_path, 5e4)
    scene = tmp_path / "fit.toml"
    scene.write_text(SCENE.format(E=2e4) + IDENTIFY)
    assert main(["identify", str(scene), "--out", str(tmp_path / "out")]) == 0
    report = json.loads((tmp_path / "out" / "identify.json").read_text())
    assert report["parameters"]["material.youngs_modulus"] == pytest.approx(5e4, rel=1e-6)
    assert report["runs"] <= 10
    table = np.genfromtxt(tmp_path / "out" / "fit.csv", delimiter=",", names=True)
    np.testing.assert_allclose(table["simulated_0"], table["measured_0"], rtol=1e-6)
    assert json.loads(capsys.readouterr().out)["written"][0].endswith("identify.json")


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ("", "no \\[identify\\] table"),
        (
            '[identify]\nparameters = { "material.youngs_module" = 1e4 }\n'
            'observations = [ { reaction = "platen" } ]\ndata = [[1.0]]\n',
            "youngs_modulus",
        ),
        (
            '[identify]\nparameters = { "material.youngs_modulus" = 1e4 }\n'
            'observations = [ { force = "platen" } ]\ndata = [[1.0]]\n',
            "one of reaction",
        ),
        (
            '[identify]\nparameters = { "material.youngs_modulus" = 1e4 }\n'
            'observations = [ { reaction = "platen" } ]\ndata = "missing.csv"\n',
            "cannot read",
        ),
        (
            '[identify]\nparameters = { "material.youngs_modulus" = [1e4, 2e4] }\n'
            'observations = [ { reaction = "platen" } ]\ndata = [[1.0]]\n',
            "initial, low, high",
        ),
    ],
)
def test_a_bad_identify_table_is_refused_in_one_line(tmp_path, table, message):
    scene = tmp_path / "bad.toml"
    scene.write_text(SCENE.format(E=2e4) + table)
    with pytest.raises(SceneError, match=message) as info:
        read_identify_scene(scene)
    assert "\n" not in str(info.value)


def test_an_instruments_contact_force_can_be_observed_from_a_scene():
    from tissuesim.identification.observations import ContactForce
    from tissuesim.identification.scene import _observation

    entry = {"contact_force": "probe", "component": 2}
    assert _observation(entry, 0, "fit.toml") == ContactForce("probe", 2)
