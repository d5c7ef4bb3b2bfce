"""FEBio's rigid connectors (febio/rigid/connectors.py): a model of our own, two rigid cubes
(a fixed ground and a free block) joined by a revolute joint turned by its prescribed
rotation, and by a prismatic joint with a rigid spring under a rigid force, against closed
forms; the converted scene the same; refusals in one line."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from tissuesim.errors import TissueSimError
from tissuesim.febio import convert_febio, load_febio, read_feb
from tissuesim.rigid.joints import Enforcement
from tissuesim.scene.loader import load_scene


def _cube(first: int, lower: tuple[float, float, float]) -> tuple[str, str]:
    """Nodes (ids from ``first``) and one hex8 of a unit cube at ``lower``."""
    x0, y0, z0 = lower
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1),
               (0, 1, 1)]  # fmt: skip
    nodes = "".join(
        f'      <node id="{first + k}">{x0 + a:g},{y0 + b:g},{z0 + c:g}</node>\n'
        for k, (a, b, c) in enumerate(corners)
    )
    return nodes, ",".join(str(first + k) for k in range(8))


def model(connectors: str, loads: str = "") -> str:
    ground_nodes, ground = _cube(1, (-0.5, -0.5, -1.0))
    block_nodes, block = _cube(9, (1.0, -0.5, -0.5))
    fixed = "".join(f"      <R{d}_dof>1</R{d}_dof>\n" for d in "xyzuvw")
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>4</time_steps>
    <step_size>0.25</step_size>
  </Control>
  <Material>
    <material id="1" name="ground" type="rigid body"><density>1</density></material>
    <material id="2" name="block" type="rigid body"><density>1</density></material>
  </Material>
  <Mesh>
    <Nodes name="all">
{ground_nodes}{block_nodes}    </Nodes>
    <Elements type="hex8" name="g"><elem id="1">{ground}</elem></Elements>
    <Elements type="hex8" name="b"><elem id="2">{block}</elem></Elements>
  </Mesh>
  <MeshDomains>
    <SolidDomain name="g" mat="ground"/>
    <SolidDomain name="b" mat="block"/>
  </MeshDomains>
  <Rigid>
    <rigid_bc name="fix" type="rigid_fixed">
      <rb>ground</rb>
{fixed}    </rigid_bc>
{connectors}{loads}  </Rigid>
  <LoadData>
    <load_controller id="1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <points><pt>0,0</pt><pt>1,1</pt></points>
    </load_controller>
  </LoadData>
</febio_spec>
"""


REVOLUTE = """    <rigid_connector name="hinge" type="rigid revolute joint">
      <body_a>ground</body_a>
      <body_b>block</body_b>
      <laugon>1</laugon>
      <tolerance>0</tolerance>
      <joint_origin>0,0,0</joint_origin>
      <rotation_axis>0,0,1</rotation_axis>
      <transverse_axis>1,0,0</transverse_axis>
      <prescribed_rotation>1</prescribed_rotation>
      <rotation lc="1">0.8</rotation>
      <moment>0</moment>
    </rigid_connector>
"""
SLIDER = """    <rigid_connector name="rail" type="rigid prismatic joint">
      <body_a>ground</body_a>
      <body_b>block</body_b>
      <joint_origin>1.5,0,0</joint_origin>
      <translation_axis>1,0,0</translation_axis>
      <transverse_axis>0,1,0</transverse_axis>
      <prescribed_translation>0</prescribed_translation>
      <translation>0</translation>
      <force>0</force>
    </rigid_connector>
    <rigid_connector name="spring" type="rigid spring">
      <body_a>ground</body_a>
      <body_b>block</body_b>
      <k>40</k>
      <insertion_a>0,0,0</insertion_a>
      <insertion_b>1.5,0,0</insertion_b>
    </rigid_connector>
"""
PULL = """    <rigid_load name="pull" type="rigid_force">
      <rb>block</rb>
      <dof>Rx</dof>
      <value lc="1">6</value>
    </rigid_load>
"""


def _run(text: str, tmp_path: Path):
    path = tmp_path / "m.feb"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(path)
    sim = scene.simulation
    for _ in range(scene.run["steps"]):
        sim.step()
    return sim, path


def test_a_revolute_joint_turns_the_block_about_the_hinge(tmp_path):
    sim, _ = _run(model(REVOLUTE), tmp_path)
    centre, R = sim.rigid_state("block")
    phi = 0.8
    Rz = np.array([[np.cos(phi), -np.sin(phi), 0], [np.sin(phi), np.cos(phi), 0], [0, 0, 1]])
    assert centre == pytest.approx(Rz @ [1.5, 0.0, 0.0], abs=1e-8)
    assert R == pytest.approx(Rz, abs=1e-8)


def test_a_prismatic_joint_and_a_spring_take_a_rigid_force(tmp_path):
    """6 N along the rail against a 40 N/m spring: 0.15 m; the spring pulls back 6 N."""
    sim, path = _run(model(SLIDER, PULL), tmp_path)
    centre, R = sim.rigid_state("block")
    assert centre == pytest.approx([1.65, 0.0, 0.0], abs=1e-8)
    assert R == pytest.approx(np.eye(3), abs=1e-8)
    assert sim.forces()["spring"] == pytest.approx([-6.0, 0.0, 0.0], abs=1e-6)
    scene = tmp_path / "m.toml"
    convert_febio(path, scene)
    assert "[[rigid_joints]]" in scene.read_text()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        again = load_scene(scene)
    for _ in range(again.run["steps"]):
        again.simulation.step()
    assert np.array_equal(again.simulation.state.x, sim.state.x)


@pytest.mark.parametrize(
    "old, new, message",
    [
        ('type="rigid revolute joint"', 'type="rigid damper"', "'rigid damper' is not"),
        ("<moment>0</moment>", "<moment>2</moment>", "applies no force or moment through"),
        ("<body_b>block</body_b>", "<body_b>nothing</body_b>", "not a 'rigid body' material"),
        ("<joint_origin>0,0,0</joint_origin>\n", "", "needs <joint_origin>"),
    ],
)
def test_refusals_are_one_line(old, new, message, tmp_path):
    path = tmp_path / "bad.feb"
    text = model(REVOLUTE)
    assert old in text
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(TissueSimError, match=message) as info:
        read_feb(path)
    assert "bad.feb:" in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("analysis", ["STATIC", "DYNAMIC"])
def test_an_initial_rigid_velocity_is_a_note_in_a_static_analysis(analysis, tmp_path):
    """FEBio's rj04 gives its crank an initial angular velocity in a STATIC analysis, where
    it has no effect: a note; in a DYNAMIC one tissuesim refuses it in one line."""
    ic = ('    <rigid_ic name="spin" type="initial_rigid_angular_velocity">\n'
          "      <rb>block</rb>\n      <value>0,0,0.2</value>\n    </rigid_ic>\n")  # fmt: skip
    path = tmp_path / "ic.feb"
    path.write_text(model(REVOLUTE, ic).replace("STATIC", analysis))
    if analysis == "STATIC":
        assert any("no effect in a STATIC analysis" in n for n in read_feb(path).notes)
    else:
        with pytest.raises(TissueSimError, match="starts a rigid body at rest"):
            read_feb(path)


BALL = """    <rigid_connector name="ball" type="{kind}">
      <body_a>ground</body_a>
      <body_b>block</body_b>
      <{origin}>1.5,0,0</{origin}>
{settings}    </rigid_connector>
"""


def _ball(kind: str, settings: str) -> str:
    origin = "joint" if kind == "rigid joint" else "joint_origin"
    return BALL.format(kind=kind, origin=origin, settings=settings)


@pytest.mark.parametrize(
    "kind, settings, expected",
    [
        ("rigid joint", "<laugon>1</laugon><tolerance>0.1</tolerance><penalty>10</penalty>",
         {"penalty": 10.0, "augmented": True, "tolerance": 0.1}),
        ("rigid joint", "<penalty>5</penalty>",  # FERigidJoint's defaults: AUGLAG, 0.01
         {"penalty": 5.0, "augmented": True, "tolerance": 0.01}),
        ("rigid joint", "<laugon>PENALTY</laugon><penalty>5</penalty>",
         {"penalty": 5.0, "augmented": False, "tolerance": 0.01}),
        ("rigid spherical joint", "",  # FERigidSphericalJoint's defaults
         {"penalty": 1.0, "augmented": True, "tolerance": 0.0, "gap_tolerance": 0.0,
          "min_augmentations": 0, "max_augmentations": 10}),
        ("rigid spherical joint", "<laugon>1</laugon><tolerance>0.2</tolerance>"
         "<gaptol>1e-3</gaptol><force_penalty>30</force_penalty><minaug>1</minaug>"
         "<maxaug>4</maxaug>",
         {"penalty": 30.0, "augmented": True, "tolerance": 0.2, "gap_tolerance": 1e-3,
          "min_augmentations": 1, "max_augmentations": 4}),
        ("rigid joint", "<laugon>2</laugon><penalty>5</penalty>", None),  # LAGMULT: tight
        ("rigid spherical joint", "<auto_penalty>1</auto_penalty>", None),
    ],
)  # fmt: skip
def test_a_rigid_joints_enforcement_is_febios(kind, settings, expected, tmp_path):
    """FEBio's laugon, tolerance, penalty, gaptol, minaug, maxaug (and its defaults) become
    the joint's enforcement; LAGMULT and auto_penalty leave tissuesim's tight hold, a note."""
    path = tmp_path / "ball.feb"
    path.write_text(model(_ball(kind, settings)))
    feb = read_feb(path)
    (entry,) = feb.rigid_connectors
    assert entry.get("enforcement") == expected
    assert any("joint enforcement" in n for n in feb.notes) == (expected is None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (joint,) = load_febio(path).simulation.rigid_joints
    assert (joint.enforcement is None) == (expected is None)
    if expected is not None:
        assert joint.enforcement == Enforcement.of(expected, "test")


@pytest.mark.parametrize(
    "kind, settings, message",
    [
        ("rigid joint", "<laugon>1</laugon>", "positive <penalty>"),
        ("rigid spherical joint", "<force_penalty>0</force_penalty>", "positive <force_pen"),
        ("rigid joint", "<laugon>3</laugon><penalty>1</penalty>", "laugon = '3'"),
        ("rigid spherical joint", "<maxaug>2.5</maxaug>", "maxaug = 2.5"),
    ],
)
def test_enforcement_refusals_are_one_line(kind, settings, message, tmp_path):
    path = tmp_path / "bad.feb"
    path.write_text(model(_ball(kind, settings)))
    with pytest.raises(TissueSimError, match=message) as info:
        read_feb(path)
    assert "bad.feb:" in str(info.value) and "\n" not in str(info.value)


def test_a_converted_joints_enforcement_survives_the_scene_file(tmp_path):
    path = tmp_path / "ball.feb"
    path.write_text(model(_ball("rigid joint", "<tolerance>0.1</tolerance><penalty>10</penalty>")))
    scene = tmp_path / "ball.toml"
    convert_febio(path, scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (joint,) = load_scene(scene).simulation.rigid_joints
    assert joint.enforcement == Enforcement(10.0, True, 0.1)
