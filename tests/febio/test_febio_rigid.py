"""FEBio's rigid bodies (febio/rigid/): a model of our own, a hex8
block under a rigid platen sharing its top nodes, pressed, then free under a force, then a
platen of its own glued by <bc type="rigid">; each against the same block with its top nodes
prescribed, and the converted scene against the model."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from tissuesim.errors import TissueSimError
from tissuesim.febio import convert_febio, load_febio, read_feb
from tissuesim.scene.loader import load_scene

MODELS = Path(__file__).parent / "models"
PLATEN = (MODELS / "rigid_platen.feb").read_text()
TOP = list(range(10, 19))  # FEBio ids of the block's top nodes


def _run(text: str, tmp_path: Path, name: str = "m.feb"):
    path = tmp_path / name
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(path)
    sim = scene.simulation
    for _ in range(scene.run["steps"]):
        sim.step()
    return sim, read_feb(path)


def _prescribed(dz: float) -> str:
    """The same block, no platen: its top nodes moved dz down and held in x and y."""
    text = PLATEN
    start, end = text.index('    <Elements type="hex8" name="plate">'), text.index("  </Mesh>")
    plate = text[start:end]
    text = text.replace(plate, plate[plate.index("    <NodeSet") :])
    text = text.replace('    <SolidDomain name="plate" mat="platen"/>\n', "")
    start, end = text.index("  <Rigid>"), text.index("  <LoadData>")
    text = text[:start] + text[end:]
    return text.replace(
        "  </Boundary>",
        '    <bc name="top" node_set="top" type="zero displacement">\n'
        "      <x_dof>1</x_dof>\n      <y_dof>1</y_dof>\n      <z_dof>0</z_dof>\n    </bc>\n"
        '    <bc name="press" node_set="top" type="prescribed displacement">\n'
        f'      <dof>z</dof>\n      <value lc="1">{float(dz)!r}</value>\n'
        "      <relative>0</relative>\n    </bc>\n  </Boundary>",
    )


def _own_nodes() -> str:
    """The platen model with the platen on nodes of its own (ids 100..108, a copy of the
    block's top face), so that it no longer shares the block's."""
    text = PLATEN
    copies = "".join(
        f'      <node id="{100 + k}">{x:g},{y:g},0.5</node>\n'
        for k, (y, x) in enumerate((y, x) for y in (0, 0.5, 1) for x in (0, 0.5, 1))
    )
    text = text.replace("    </Nodes>", copies + "    </Nodes>")
    plate = text[text.index('<Elements type="hex8" name="plate">') :]
    plate = plate[: plate.index("</Elements>")]
    new = plate
    for k, node in enumerate(TOP):
        new = new.replace(f">{node},", f">{100 + k},").replace(f",{node},", f",{100 + k},")
    return text.replace(plate, new)


def test_a_pressed_platen_is_the_same_motion_prescribed_on_the_nodes(tmp_path):
    sim, model = _run(PLATEN, tmp_path)
    ref, _ = _run(_prescribed(-0.05), tmp_path, "ref.feb")
    assert np.abs(sim.body_positions("block") - ref.body_positions("body")).max() < 1e-12
    f, g = sim.forces(), ref.forces()
    assert f["platen"] == pytest.approx(g["press"], rel=1e-10, abs=1e-8)
    assert f["platen"][2] < -100.0  # what holds the platen pushes it down into the block
    assert np.allclose(f["platen.moment"], 0.0, atol=1e-8)  # symmetric
    centre, R = sim.rigid_state("platen")
    assert centre == pytest.approx([0.5, 0.5, 0.55 - 0.05])  # its centre of mass, moved
    assert R == pytest.approx(np.eye(3))
    plate = sim.body_positions("plate") - model.nodes[np.unique(model.parts["plate"][1])]
    assert plate == pytest.approx(np.tile([0.0, 0.0, -0.05], (len(plate), 1)))


def test_a_free_platen_under_a_force_sinks_as_far_as_that_force_presses(tmp_path):
    """z free under rigid_force -F: the base holds F, and prescribing the depth it reached
    takes the same force."""
    force = 800.0
    text = PLATEN.replace(
        '    <rigid_bc name="press" type="rigid_displacement">\n      <rb>platen</rb>\n'
        '      <dof>z</dof>\n      <value lc="1">-0.05</value>\n      <relative>0</relative>\n'
        "    </rigid_bc>\n",
        '    <rigid_load name="push" type="rigid_force">\n      <rb>platen</rb>\n'
        f'      <dof>Rz</dof>\n      <value lc="1">{-force}</value>\n'
        "      <load_type>LOAD</load_type>\n      <relative>0</relative>\n    </rigid_load>\n",
    )
    assert "rigid_force" in text
    sim, _ = _run(text, tmp_path)
    f = sim.forces()
    assert f["base"][2] == pytest.approx(force, rel=1e-8)
    assert f["platen"][2] == pytest.approx(0.0, abs=1e-6)  # a free DOF carries nothing
    centre, _ = sim.rigid_state("platen")
    depth = centre[2] - 0.55
    ref, _ = _run(_prescribed(depth), tmp_path, "ref.feb")
    assert ref.forces()["press"][2] == pytest.approx(-force, rel=1e-6)


def test_a_platen_glued_by_a_rigid_bc_is_the_shared_nodes_platen(tmp_path):
    """The platen on nodes of its own (a copy of the top face) and the block's top node set
    glued to it by <bc type="rigid">: the same block as the one sharing its nodes."""
    text = _own_nodes()
    text = text.replace(
        "  </Boundary>",
        '    <bc name="glue" node_set="top" type="rigid">\n      <rb>platen</rb>\n    </bc>\n'
        "  </Boundary>",
    )
    sim, _ = _run(text, tmp_path)
    shared, _ = _run(PLATEN, tmp_path, "shared.feb")
    assert np.abs(sim.body_positions("block") - shared.body_positions("block")).max() < 1e-12
    assert sim.forces()["platen"] == pytest.approx(shared.forces()["platen"], rel=1e-10)


def test_the_converted_scene_runs_the_same(tmp_path):
    sim, _ = _run(PLATEN, tmp_path)
    scene_path = tmp_path / "platen.toml"
    convert_febio(MODELS / "rigid_platen.feb", scene_path)
    assert "[[rigid_bodies]]" in scene_path.read_text()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(scene_path)
    other = scene.simulation
    for _ in range(scene.run["steps"]):
        other.step()
    assert np.array_equal(other.body_positions("block"), sim.body_positions("block"))


@pytest.mark.parametrize(
    "old, new, message",
    [
        ('<rigid_bc name="press" type="rigid_displacement">',
         '<rigid_bc name="press" type="rigid_euler_angles">', "rigid_euler_angles"),
        ("<rb>platen</rb>\n      <dof>z</dof>", "<rb>tissue</rb>\n      <dof>z</dof>",
         "not a 'rigid body' material"),
        ("  </Rigid>", '    <rigid_connector type="rigid spring"/>\n  </Rigid>',
         "a rigid spring needs <body_a>"),
        ("<value lc=\"1\">-0.05</value>\n      <relative>0</relative>",
         "<value lc=\"1\">-0.05</value>\n      <relative>1</relative>", "relative = 1"),
    ],
)  # fmt: skip
def test_refusals_name_the_element_and_line(old, new, message, tmp_path):
    assert old in PLATEN
    path = tmp_path / "bad.feb"
    path.write_text(PLATEN.replace(old, new, 1))
    with pytest.raises(TissueSimError, match=message) as info:
        read_feb(path)
    assert "bad.feb:" in str(info.value) and "\n" not in str(info.value)


def test_a_platen_pressed_through_contact_moves_inside_the_solve(tmp_path):
    """The platen on nodes of its own, pressed onto the block through frictionless
    sliding-elastic contact, augmented as FEBio does (contact/penalty/): the block then is the
    block with its top pushed down 0.05 and free to slide: the force within 1e-5, the platen
    at its prescribed place."""
    text = _own_nodes()
    faces = "".join(
        f'      <quad4 id="{i + 1}">{",".join(str(n) for n in q)}</quad4>\n'
        for i, q in enumerate([(10, 11, 14, 13), (11, 12, 15, 14), (13, 14, 17, 16),
                               (14, 15, 18, 17)])
    )  # fmt: skip
    under = "".join(
        f'      <quad4 id="{i + 1}">{",".join(str(100 + n - 10) for n in q)}</quad4>\n'
        for i, q in enumerate([(10, 13, 14, 11), (11, 14, 15, 12), (13, 16, 17, 14),
                               (14, 17, 18, 15)])
    )  # fmt: skip
    text = text.replace(
        "  </Mesh>",
        f'    <Surface name="block_top">\n{faces}    </Surface>\n'
        f'    <Surface name="plate_under">\n{under}    </Surface>\n'
        '    <SurfacePair name="press">\n      <primary>plate_under</primary>\n'
        "      <secondary>block_top</secondary>\n    </SurfacePair>\n  </Mesh>",
    )
    text = text.replace(
        "  <LoadData>",
        '  <Contact>\n    <contact type="sliding-elastic" surface_pair="press">\n'
        "      <fric_coeff>0</fric_coeff>\n      <laugon>AUGLAG</laugon>\n"
        "      <penalty>1e4</penalty>\n      <tolerance>1e-8</tolerance>\n"
        "      <maxaug>50</maxaug>\n    </contact>\n  </Contact>\n  <LoadData>",
    )
    sim, _ = _run(text, tmp_path)
    free = _prescribed(-0.05).replace(
        '    <bc name="top" node_set="top" type="zero displacement">\n'
        "      <x_dof>1</x_dof>\n      <y_dof>1</y_dof>\n      <z_dof>0</z_dof>\n    </bc>\n",
        "",
    )
    ref, _ = _run(free, tmp_path, "ref.feb")
    pushed = sim.forces()["platen"][2]
    assert pushed == pytest.approx(ref.forces()["press"][2], rel=1e-5)  # measured: 1.8e-6
    centre, _ = sim.rigid_state("platen")
    assert centre[2] == pytest.approx(0.55 - 0.05, abs=1e-12)


def test_rigid_body_data_is_logged_as_febio_names_it(tmp_path):
    """<rigid_body_data> (material id 2, the platen): a CSV table per frame with FEBio's
    variable names, its force the forces.csv column's, its centre the rigid state's; the
    converted scene writes the same table."""
    from tissuesim.cli import main

    text = PLATEN.replace(
        "  <LoadData>",
        '  <Output>\n    <logfile>\n      <rigid_body_data data="x;y;z;Fz;Mx;qw;thy;R33" '
        'file="platen.txt">2</rigid_body_data>\n    </logfile>\n  </Output>\n  <LoadData>',
    )
    path = tmp_path / "logged.feb"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--no-render", "--quiet"]) == 0
    lines = (out / "platen.txt").read_text().splitlines()
    assert lines[0] == "time,body,x,y,z,Fz,Mx,qw,thy,R33"
    last = [float(v) for v in lines[-1].split(",")]
    assert last[0] == pytest.approx(1.0) and last[1] == 2  # FEBio's material id
    assert last[2:5] == pytest.approx([0.5, 0.5, 0.5])  # the centre pressed 0.05 down
    forces = (out / "forces.csv").read_text().splitlines()
    column = forces[0].split(",").index("platen_z_N")
    assert "platen.moment_x_Nm" in forces[0]
    assert last[5] == pytest.approx(float(forces[-1].split(",")[column]), rel=1e-9)
    assert last[6:] == pytest.approx([0.0, 1.0, 0.0, 1.0], abs=1e-9)
    assert len(lines) == 1 + 3  # the start and two steps
    scene = tmp_path / "logged.toml"
    convert_febio(path, scene)
    assert 'kind = "rigid_body_data"' in scene.read_text()
    again = tmp_path / "again"
    assert main(["run", str(scene), "--out", str(again), "--no-render", "--quiet"]) == 0
    assert (again / "platen.txt").read_text() == (out / "platen.txt").read_text()


def _tall(platen: bool) -> str:
    """A 2 x 2 x 2 hex8 block (free middle nodes) under the platen model's rigid plate on its
    top nodes, pressed 0.2 down in four steps; ``platen`` False: no plate, the top nodes
    held in x, y and moved as the plate would."""
    text = PLATEN
    n = lambda i, j, k: 1 + i + 3 * j + 9 * k  # noqa: E731
    nodes = "".join(f'      <node id="{n(i, j, k)}">{0.5 * i:g},{0.5 * j:g},{0.5 * k:g}</node>\n'
                    for k in range(3) for j in range(3) for i in range(3))  # fmt: skip
    nodes += "".join(f'      <node id="{28 + i + 3 * j}">{0.5 * i:g},{0.5 * j:g},1.1</node>\n'
                     for j in range(3) for i in range(3))  # fmt: skip

    def hexes(first: int, corner) -> str:
        rows = []
        for e, (i, j, k) in enumerate((i, j, k) for k in range(2 if first == 1 else 1)
                                      for j in range(2) for i in range(2)):  # fmt: skip
            lo = [
                corner(i, j, k),
                corner(i + 1, j, k),
                corner(i + 1, j + 1, k),
                corner(i, j + 1, k),
            ]
            hi = [corner(i, j, k + 1), corner(i + 1, j, k + 1), corner(i + 1, j + 1, k + 1),
                  corner(i, j + 1, k + 1)]  # fmt: skip
            rows.append(f'      <elem id="{first + e}">{",".join(map(str, lo + hi))}</elem>\n')
        return "".join(rows)

    plate = lambda i, j, k: n(i, j, 2) if k == 0 else 28 + i + 3 * j  # noqa: E731
    mesh = (f"    <Nodes name=\"all\">\n{nodes}    </Nodes>\n"
            f'    <Elements type="hex8" name="block">\n{hexes(1, n)}    </Elements>\n'
            f'    <Elements type="hex8" name="plate">\n{hexes(9, plate)}    </Elements>\n'
            '    <NodeSet name="base">1,2,3,4,5,6,7,8,9</NodeSet>\n'
            '    <NodeSet name="top">19,20,21,22,23,24,25,26,27</NodeSet>\n')  # fmt: skip
    start, end = text.index("    <Nodes"), text.index("  </Mesh>")
    text = text[:start] + mesh + text[end:]
    text = text.replace("<time_steps>2</time_steps>", "<time_steps>4</time_steps>")
    text = text.replace("<step_size>0.5</step_size>", "<step_size>0.25</step_size>")
    text = text.replace('<value lc="1">-0.05</value>', '<value lc="1">-0.2</value>')
    if platen:
        return text
    start, end = text.index('    <Elements type="hex8" name="plate">'), text.index("    <NodeSet")
    text = text[:start] + text[end:]
    text = text.replace('    <SolidDomain name="plate" mat="platen"/>\n', "")
    start, end = text.index("  <Rigid>"), text.index("  <LoadData>")
    text = text[:start] + text[end:]
    return text.replace(
        "  </Boundary>",
        '    <bc name="top" node_set="top" type="zero displacement">\n'
        "      <x_dof>1</x_dof>\n      <y_dof>1</y_dof>\n      <z_dof>0</z_dof>\n    </bc>\n"
        '    <bc name="press" node_set="top" type="prescribed displacement">\n'
        '      <dof>z</dof>\n      <value lc="1">-0.2</value>\n'
        "      <relative>0</relative>\n    </bc>\n  </Boundary>",
    )


def test_febios_solver_moves_a_prescribed_platen_by_its_increment_as_febio(tmp_path):
    """With FEBio's solver (--febio-solver) a prescribed rigid body enters each step's first
    iteration as FEBio's m_Fd = -K_fp du_p, its increment taken once (its vertices' stiffness
    reaches it through the links, rigid/links.py): a block with free middle nodes under a
    pressed platen iterates exactly as the same block with its top nodes prescribed (FEM
    m_Fd), step by step, to the same positions. (Started from the moved platen, or with the
    increment on its vertices too, the iterations differed.)"""
    runs = []
    for platen in (True, False):
        path = tmp_path / f"tall_{platen}.feb"
        path.write_text(_tall(platen))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene = load_febio(path, febio_solver=True)
        sim = scene.simulation
        iterations = [sim.step().newton_iterations for _ in range(scene.run["steps"])]
        runs.append((sim, iterations))
    (platen, a), (nodes, b) = runs
    assert a == b and len(a) == 4 and min(a) > 1
    np.testing.assert_allclose(platen.body_positions("block"), nodes.body_positions("body"),
                               atol=1e-9)  # fmt: skip
    assert np.ptp(platen.body_positions("block")[9:18, 0]) > 1.0 + 1e-3  # the middle bulges
