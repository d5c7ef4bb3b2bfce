"""FEBio's <logfile> requests (issue 42): node_data and element_data become CSV tables a run
writes beside its VTU series, with FEBio's ids and variable names; what tissuesim cannot
write is named in one line; the converted scene writes the same tables."""

from __future__ import annotations

import json
from pathlib import Path

import meshio
import numpy as np
import pytest

from tissuesim.cli import main
from tissuesim.errors import InputError, SceneError
from tissuesim.febio import FebError, convert_febio, read_feb
from tissuesim.scene.loader import load_scene

MODELS = Path(__file__).parent / "models"


class Table:
    """A log table's columns by name (what pd.read_csv gives, without pandas)."""

    def __init__(self, path: Path) -> None:
        lines = path.read_text().splitlines()
        self.columns = lines[0].split(",")
        self.values = np.array([[float(v) for v in r.split(",")] for r in lines[1:]])

    def __getitem__(self, key):
        if isinstance(key, str):
            return self.values[:, self.columns.index(key)]
        if isinstance(key, list):
            return self.values[:, [self.columns.index(k) for k in key]]
        out = object.__new__(Table)
        out.columns, out.values = self.columns, self.values[key]
        return out


MODEL = MODELS / "logfile_uniaxial.feb"
TABLES = ("pulled.csv", "node_data_2.csv", "stress.txt")


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("logfile") / "out"
    assert main(["run", str(MODEL), "--out", str(out), "--no-render", "--quiet"]) == 0
    return out


def _frames(out: Path) -> list[tuple[float, meshio.Mesh]]:
    text = (out / "body.pvd").read_text()
    frames = []
    for line in text.splitlines():
        if "<DataSet" in line:
            t = float(line.split('timestep="')[1].split('"')[0])
            file = line.split('file="')[1].split('"')[0]
            frames.append((t, meshio.read(out / file)))
    return frames


def test_the_tables_are_written_and_listed(run):
    manifest = json.loads((run / "manifest.json").read_text())
    for name in TABLES:
        assert name in manifest["files"]
    pulled = Table(run / "pulled.csv")
    assert list(pulled.columns) == ["time", "node", "ux", "uy", "uz", "Rx"]
    assert sorted(set(pulled["node"].astype(int))) == [3, 6, 9, 12, 15, 18, 21, 24, 27]
    assert list(Table(run / "node_data_2.csv").columns) == ["time", "node", "x", "y", "z"]
    stress = Table(run / "stress.txt")
    assert list(stress.columns[:2]) == ["time", "element"]
    assert list(stress["element"][:2].astype(int)) == [8, 1]  # the set's order
    times = [t for t, _ in _frames(run)]
    for name in TABLES:  # one block of rows per written frame, the first at t = 0
        assert sorted(set(Table(run / name)["time"].tolist())) == pytest.approx(times)


def test_node_values_match_the_vtu_series_and_the_reaction(run):
    pulled = Table(run / "pulled.csv")
    where = Table(run / "node_data_2.csv")
    rows = np.array([3, 6, 9, 12, 15, 18, 21, 24, 27]) - 1  # one body: rows are ids - 1
    forces = Table(run / "forces.csv")
    for t, frame in _frames(run):
        u = frame.point_data["displacement"]
        mine = pulled[pulled["time"] == t]
        np.testing.assert_allclose(mine[["ux", "uy", "uz"]], u[rows], atol=1e-14)
        x = where[where["time"] == t]
        np.testing.assert_allclose(x[["x", "y", "z"]], (frame.points + u)[[0, 13, 26]], atol=1e-14)
        if t > 0:  # the pulled face's reactions sum to the support's force
            pull = forces[np.isclose(forces["time_s"], t)]["pull_x_N"].item()
            assert mine["Rx"].sum() == pytest.approx(pull, rel=1e-12)
    assert pulled["ux"].max() == pytest.approx(0.2)


def test_element_values_match_the_vtu_stress_and_strain(run):
    stress = Table(run / "stress.txt")
    for t, frame in _frames(run):
        s = frame.cell_data["cauchy_stress"][0].reshape(-1, 3, 3)[[7, 0]]
        E = frame.cell_data["green_strain"][0].reshape(-1, 3, 3)[[7, 0]]
        J = frame.cell_data["J"][0][[7, 0]]
        mine = stress[stress["time"] == t]
        for name, (i, k) in {"sx": (0, 0), "sy": (1, 1), "sz": (2, 2), "sxy": (0, 1),
                             "syz": (1, 2), "sxz": (0, 2)}.items():  # fmt: skip
            np.testing.assert_allclose(mine[name], s[:, i, k], rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(mine["Ex"], E[:, 0, 0], atol=1e-14)
        np.testing.assert_allclose(mine["Ey"], E[:, 1, 1], atol=1e-14)
        np.testing.assert_allclose(mine["J"], J, atol=1e-14)
        np.testing.assert_allclose(mine["s1"], np.linalg.eigvalsh(s)[:, 2], atol=1e-9)
        np.testing.assert_allclose(mine["s3"], np.linalg.eigvalsh(s)[:, 0], atol=1e-9)
        np.testing.assert_allclose(mine["E1"], np.linalg.eigvalsh(E)[:, 2], atol=1e-14)
    assert stress["sx"][-1] > 0  # the block is pulled


def test_the_converted_scene_writes_the_same_tables(run, tmp_path):
    scene = tmp_path / "scene.toml"
    convert_febio(MODEL, scene)
    assert "[[logfiles]]" in scene.read_text()
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--no-render", "--quiet"]) == 0
    for name in TABLES:
        assert (out / name).read_text() == (run / name).read_text()


def test_a_resumed_run_goes_on_with_its_tables(tmp_path):
    scene = tmp_path / "scene.toml"
    convert_febio(MODEL, scene)
    load_scene(scene).simulation.run(4, tmp_path / "whole", progress=False, render=False)
    load_scene(scene).simulation.run(2, tmp_path / "out", progress=False, render=False)
    with open(tmp_path / "out" / "pulled.csv", "a") as f:  # a frame half written, then killed
        f.write("0.75,3,0.1")
    load_scene(scene).simulation.run(4, tmp_path / "out", progress=False, render=False, resume=True)
    for name in TABLES:
        assert (tmp_path / "out" / name).read_text() == (tmp_path / "whole" / name).read_text()


def _with(text: str) -> str:
    feb = MODEL.read_text()
    start, end = feb.index("    <logfile>"), feb.index("    </logfile>") + len("    </logfile>")
    return feb[:start] + text + feb[end:]


def test_variables_tissuesim_cannot_write_are_one_note(tmp_path):
    feb = tmp_path / "m.feb"
    feb.write_text(_with('    <logfile>\n      <node_data data="ux;ax;ay" file="a.csv"/>\n'
                         "    </logfile>"))  # fmt: skip
    model = read_feb(feb)
    notes = [n for n in model.notes if "node_data" in n]
    assert len(notes) == 1 and "\n" not in notes[0]
    assert notes[0].startswith(f"{feb}:") and "ax, ay not written" in notes[0]
    assert [r["data"] for r in model.logfiles] == [["ux"]]
    feb.write_text(_with('    <logfile>\n      <element_data data="Ex;sed"/>\n    </logfile>'))
    assert any("sed not written" in n for n in read_feb(feb).notes)


@pytest.mark.parametrize(
    "request_text, message",
    [
        ('<rigid_body_data data="x;y;z">1</rigid_body_data>', "not a 'rigid body' material"),
        ('<rigid_connector_data data="Fx">1</rigid_connector_data>', "no rigid connectors"),
        ('<node_data data="ux" node_set="nowhere"/>', "no NodeSet"),
        ('<element_data data="J">99</element_data>', "element id 99"),
        ('<node_data data="ux" kind="x"/>', 'attribute kind="x"'),
    ],
)
def test_refused_requests_are_one_line_with_the_element_and_line(tmp_path, request_text, message):
    feb = tmp_path / "m.feb"
    text = _with(f"    <logfile>\n      {request_text}\n    </logfile>")
    feb.write_text(text)
    with pytest.raises(FebError) as info:
        read_feb(feb)
    said = str(info.value)
    line = next(i for i, s in enumerate(text.splitlines(), 1) if request_text in s)
    assert "\n" not in said and said.startswith(f"{feb}:{line}") and message in said


def test_the_scene_table_is_checked_like_the_others(tmp_path):
    scene = tmp_path / "scene.toml"
    convert_febio(MODEL, scene)
    text = scene.read_text()
    bad = {
        'file = "pulled.csv"': ('file = "pulled.csv"\nnode = [1]', "unknown key 'node'"),
        'data = ["ux", "uy", "uz", "Rx"]': ('data = ["ux", "ax"]', "'ax' is not a node_data"),
        "elements = [7, 0]": ("nodes = [7, 0]", "nodes is not a key of a element_data"),
        'file = "stress.txt"': ('file = "pulled.csv"', "written by another table"),
    }
    for old, (new, message) in bad.items():
        scene.write_text(text.replace(old, new))
        with pytest.raises(SceneError) as info:
            load_scene(scene)
        assert "\n" not in str(info.value) and message in str(info.value)
        assert "logfiles[" in str(info.value)


def test_the_python_api_checks_its_request():
    import tissuesim as ts

    sim = ts.Simulation(
        ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1)),
        ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3),
    )
    request = sim.add_logfile("element_data", ["J"])
    assert request.file == "element_data_1.csv"
    with pytest.raises(InputError, match="kind must be one of"):
        sim.add_logfile("rigid_connector_data", ["x"])
    with pytest.raises(InputError, match="the simulation has no rigid bodies"):
        sim.add_logfile("rigid_body_data", ["x"])
    with pytest.raises(InputError, match="2 ids for 1 items"):
        sim.add_logfile("node_data", ["ux"], items=[0], ids=[1, 2])


def test_a_request_over_several_bodies_is_one_table_per_body(tmp_path):
    """contact_stack: three blocks, three bodies; one request over nodes of two of them and one
    over every element become a table per body, each with its FEBio ids, and the run writes
    them."""
    text = (MODELS / "contact_stack.feb").read_text()
    logfile = (
        "  <Output>\n    <logfile>\n"
        '      <node_data data="uz" file="z.csv">1,13,14</node_data>\n'
        '      <element_data data="J"/>\n'
        "    </logfile>\n  </Output>\n</febio_spec>"
    )
    feb = tmp_path / "stack.feb"
    feb.write_text(text.replace("</febio_spec>", logfile))
    scene = tmp_path / "scene.toml"
    convert_febio(feb, scene)
    import tomllib

    tables = tomllib.loads(scene.read_text())["logfiles"]
    nodes = {t["body"]: (t["ids"], t["file"]) for t in tables if t["kind"] == "node_data"}
    assert nodes == {"lower": ([1], "z_lower.csv"), "upper": ([13, 14], "z_upper.csv")}
    elements = {t["body"]: (t.get("ids"), t["file"]) for t in tables if t["kind"] == "element_data"}
    assert elements == {
        "lower": (None, "element_data_2_lower.csv"),  # every row, ids = rows + 1: left out
        "upper": ([2], "element_data_2_upper.csv"),
        "puck": ([3], "element_data_2_puck.csv"),
    }
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--no-render", "--quiet"]) == 0
    upper = Table(out / "z_upper.csv")
    assert upper.columns == ["time", "node", "uz"] and len(upper.values) == 2 * 3  # 3 frames
    assert Table(out / "element_data_2_puck.csv")["element"].tolist() == [3.0] * 3


def test_a_body_that_tears_is_not_logged(tmp_path):
    import tissuesim as ts

    sim = ts.Simulation(
        ts.box((0, 0, 0), (1, 1, 1), (1, 1, 1)),
        ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3),
    )
    sim.add_logfile("node_data", ["ux"])
    sim.set_tearing(body="body", stretch=2.0)
    with pytest.raises(InputError, match="which is cut"):
        sim.run(1, tmp_path / "out", progress=False, render=False)


def test_a_shells_node_data_lists_febios_nodes_once_with_their_displacement(tmp_path):
    """A quad4 shell's body holds back nodes of tissuesim's own (febio/shells.py): the table
    of every node lists FEBio's 243 ids, each once per frame, each with the displacement the
    VTU series gives at that node's place (the shell's front), not the back nodes under
    stray ids."""
    text = (MODELS / "shell_cantilever_quad4.feb").read_text()
    logfile = ('  <Output>\n    <logfile>\n      <node_data data="ux;uy;uz" file="nd.csv"/>\n'
               "    </logfile>\n  </Output>\n</febio_spec>")  # fmt: skip
    feb = tmp_path / "shell.feb"
    feb.write_text(text.replace("</febio_spec>", logfile))
    out = tmp_path / "out"
    assert main(["run", str(feb), "--out", str(out), "--no-render", "--quiet"]) == 0
    table = Table(out / "nd.csv")
    last = table[table["time"] == table["time"].max()]
    ids = last["node"].astype(int)
    assert sorted(ids.tolist()) == list(range(1, 244))
    model = read_feb(feb)
    t, mesh = _frames(out)[-1]
    assert t == pytest.approx(table["time"].max())
    from scipy.spatial import cKDTree

    dist, j = cKDTree(mesh.points).query(model.nodes[ids - 1])
    assert dist.max() < 1e-12
    u = mesh.point_data["displacement"][j]
    assert np.abs(u).max() > 1e-3  # it bends
    np.testing.assert_allclose(last[["ux", "uy", "uz"]], u, atol=1e-12)
