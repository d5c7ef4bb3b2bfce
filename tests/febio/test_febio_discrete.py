"""FEBio's discrete springs (<DiscreteSet>, <Discrete>: febio/discrete.py), rigid walls in
<Constraints> (febio/constraint_sections.py) and the sign of a body load, on a cube of our
own (one hex8, symmetry supports, its x = 1 face pulled 0.15 along x): each against its
closed form."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from tissuesim.febio import load_febio, read_feb
from tissuesim.febio.xml import FebError

MODELS = Path(__file__).parent / "models"
CUBE = (MODELS / "hyperelastic_uniaxial.feb").read_text()
E = 40.0


def _run(text: str, tmp_path: Path, name: str = "m.feb"):
    path = tmp_path / name
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(path)
    sim = scene.simulation
    for _ in range(scene.run["steps"]):
        sim.step()
    return sim


def _with_spring(anchor: tuple[float, float, float], material: str) -> str:
    """The cube with node 9 at ``anchor`` (no element; clamped) tied to node 2 (1, 0, 0)."""
    text = CUBE.replace("    </Nodes>", f'      <node id="9">{",".join(map(str, anchor))}</node>\n'
                        "    </Nodes>")  # fmt: skip
    text = text.replace(
        "  </Mesh>",
        '    <NodeSet name="anchor">9</NodeSet>\n'
        '    <DiscreteSet name="tie">\n      <delem>2,9</delem>\n    </DiscreteSet>\n  </Mesh>',
    )
    text = text.replace(
        "  </Boundary>",
        '    <bc name="hold" node_set="anchor" type="zero displacement">\n'
        "      <x_dof>1</x_dof>\n      <y_dof>1</y_dof>\n      <z_dof>1</z_dof>\n    </bc>\n"
        "  </Boundary>\n  <Discrete>\n"
        f'    <discrete_material id="1" name="spring" {material}\n    </discrete_material>\n'
        '    <discrete dmat="1" discrete_set="tie"/>\n  </Discrete>',
    )
    return text


LINEAR = f'type="linear spring">\n      <E>{E}</E>'
TENSION = f'type="tension-only linear spring">\n      <E>{E}</E>'


def _curve(measure: str) -> str:
    return ('type="nonlinear spring">\n      <scale>2</scale>\n'
            f"      <measure>{measure}</measure>\n"
            '      <force type="point">\n        <interpolate>smooth</interpolate>\n'
            "        <extend>constant</extend>\n        <points>\n          <pt>-1,-1</pt>\n"
            "          <pt>0,0</pt>\n          <pt>1,2</pt>\n        </points>\n"
            "      </force>")  # fmt: skip


def _smooth(s: float) -> float:
    """The smooth curve through (-1, -1), (0, 0), (1, 2): one quadratic."""
    return 1.5 * s + 0.5 * s * s


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    return np.asarray(_run(CUBE, tmp_path_factory.mktemp("plain")).forces()["pull"])


@pytest.mark.parametrize(
    ("anchor", "material", "extra"),
    [
        ((2.0, 0.0, 0.0), LINEAR, 0.15 * E),  # compressed by 0.15: pushes node 2 back
        ((-1.0, 0.0, 0.0), LINEAR, 0.15 * E),  # stretched by 0.15: pulls node 2 back
        ((2.0, 0.0, 0.0), TENSION, 0.0),  # compressed: no force
        ((-1.0, 0.0, 0.0), TENSION, 0.15 * E),
        ((2.0, 0.0, 0.0), _curve("elongation"), -2.0 * _smooth(-0.15)),
        ((3.0, 0.0, 0.0), _curve("strain"), -2.0 * _smooth(-0.075)),
        ((3.0, 0.0, 0.0), _curve("stretch"), -2.0 * (_smooth(1 - 0.075) - 0 * _smooth(1.0))),
    ],
)
def test_a_spring_adds_its_closed_form_force_to_the_pull(anchor, material, extra, plain,
                                                          tmp_path):  # fmt: skip
    """Node 2 moves 0.15 along x with its face (the cube's state is the same with the spring:
    it acts along x, on a node whose x is prescribed), so the pull's reaction grows by the
    spring's force at that elongation: E DL, scale F(measure)."""
    sim = _run(_with_spring(anchor, material), tmp_path)
    pull = np.asarray(sim.forces()["pull"])
    np.testing.assert_allclose(pull - plain, [extra, 0.0, 0.0], atol=1e-7 * abs(plain[0]))


def test_the_stretch_measure_starts_from_its_value_at_rest(tmp_path):
    """With the stretch measure the force at rest is scale F(1) = 4 (FEBio's definition): the
    model starts out of balance; the spring still adds scale F(l / L0) at the end."""
    model = tmp_path / "m.feb"
    model.write_text(_with_spring((3.0, 0.0, 0.0), _curve("stretch")))
    assert read_feb(model).springs[0]["measure"] == "stretch"


def test_spring_refusals_name_the_element(tmp_path):
    text = _with_spring((2.0, 0.0, 0.0), LINEAR)
    bad = {
        "type 'Hill' is not supported": text.replace('type="linear spring"', 'type="Hill"'),
        'no DiscreteSet named': text.replace('discrete_set="tie"/>', 'discrete_set="tye"/>'),
        "not clamped": text.replace("<z_dof>1</z_dof>\n    </bc>\n  </Boundary>",
                                    "<z_dof>0</z_dof>\n    </bc>\n  </Boundary>"),
    }  # fmt: skip
    for message, deck in bad.items():
        path = tmp_path / "bad.feb"
        path.write_text(deck)
        with pytest.raises(FebError, match=message.replace("(", r"\(")):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                load_febio(path)


def _walled(offset: float) -> str:
    """The cube without its z = 0 support, on a rigid wall at z = 0 that rises by offset."""
    text = CUBE.replace(
        '    <bc name="sz" node_set="z0" type="zero displacement">\n      <x_dof>0</x_dof>\n'
        "      <y_dof>0</y_dof>\n      <z_dof>1</z_dof>\n    </bc>\n",
        '    <bc name="sz" node_set="z1" type="zero displacement">\n      <x_dof>0</x_dof>\n'
        "      <y_dof>0</y_dof>\n      <z_dof>1</z_dof>\n    </bc>\n",
    )
    text = text.replace('<NodeSet name="x1">', '<NodeSet name="z1">5,6,7,8</NodeSet>\n'
                        '    <Surface name="bottom">\n      <quad4 id="1">1,4,3,2</quad4>\n'
                        '    </Surface>\n    <NodeSet name="x1">')  # fmt: skip
    text = text.replace('<value lc="1">0.15</value>', '<value lc="1">0.0</value>')
    return text.replace(
        "  <LoadData>",
        '  <Constraints>\n    <constraint name="wall" surface="bottom" type="rigid_wall">\n'
        "      <laugon>PENALTY</laugon>\n      <penalty>1000</penalty>\n"
        f'      <offset lc="1">{offset}</offset>\n      <plane>0,0,1,0</plane>\n'
        "    </constraint>\n  </Constraints>\n  <LoadData>",
    )


def test_a_rising_rigid_wall_presses_the_cube_as_a_prescribed_face(tmp_path):
    """The wall (penalty 1000 Pa/m) at z = 0 under the cube's bottom face rises 0.1 against its
    top held in z. FEBio's penalty lets the face in by g = pressure / penalty (the unit face
    presses uniformly: g = F / 1000), so the cube is the same as its bottom nodes moved
    0.1 - g up (free in x and y: the wall has no friction): positions and the top's reaction
    to 1e-6."""
    sim = _run(_walled(0.1), tmp_path)
    wall, top = sim.forces()["wall"], sim.forces()["sz"]
    bottom = sim.positions[:4, 2]
    assert wall[2] > 10.0 and np.ptp(bottom) < 1e-12
    assert 0.1 - bottom[0] == pytest.approx(wall[2] / 1000.0, rel=1e-9)
    assert top[2] == pytest.approx(-wall[2], rel=1e-7)  # to Newton's tolerance
    ref_text = _walled(0.1).replace('type="rigid_wall"', 'type="x"')
    start = ref_text.index("  <Constraints>")
    ref_text = ref_text[:start] + ref_text[ref_text.index("  <LoadData>") :]
    ref_text = ref_text.replace(
        "  </Boundary>",
        '    <bc name="lift" node_set="z0" type="prescribed displacement">\n      <dof>z</dof>\n'
        f'      <value lc="1">{float(bottom[0])!r}</value>\n'
        "      <relative>0</relative>\n    </bc>\n"
        "  </Boundary>",
    )
    ref = _run(ref_text, tmp_path, "ref.feb")
    np.testing.assert_allclose(sim.positions, ref.positions, atol=1e-6)
    assert top[2] == pytest.approx(ref.forces()["sz"][2], rel=1e-6)


def test_a_body_load_pushes_against_the_vector_given(tmp_path):
    """FEBio applies -rho f (FEElasticSolidDomain::BodyForce): z = 9.81 is gravity along
    -z, so the z = 0 support of a 1000 kg/m^3 unit cube carries its weight upwards (the
    pull held at 0)."""
    text = CUBE.replace('<value lc="1">0.15</value>', '<value lc="1">0.0</value>').replace(
        "  <LoadData>",
        '  <Loads>\n    <body_load type="const">\n      <x>0</x>\n      <y>0</y>\n'
        "      <z>9.81</z>\n    </body_load>\n  </Loads>\n  <LoadData>",
    )
    sim = _run(text, tmp_path)
    assert sim.forces()["sz"][2] == pytest.approx(1000.0 * 9.81, rel=1e-8)


def _flying(nodes: str = "1,2,3,4,5,6,7,8") -> str:
    """The cube with no support and no load, DYNAMIC, its nodes started at 2 m/s along x."""
    start, end = CUBE.index("  <Boundary>"), CUBE.index("  <LoadData>")
    text = CUBE[:start] + CUBE[end:]
    text = text.replace("<analysis>STATIC</analysis>", "<analysis>DYNAMIC</analysis>")
    text = text.replace("  </Mesh>", f'    <NodeSet name="all">{nodes}</NodeSet>\n  </Mesh>')
    return text.replace(
        "  <LoadData>",
        '  <Initial>\n    <ic name="v0" node_set="all" type="velocity">\n'
        "      <value>2,0,0</value>\n    </ic>\n  </Initial>\n  <LoadData>",
    )


def test_an_initial_velocity_is_a_free_flight(tmp_path):
    """No force: every node moves v t (1 s at 2 m/s: 2 m along x), the body unstrained."""
    sim = _run(_flying(), tmp_path)
    rest = read_feb(tmp_path / "m.feb").nodes
    np.testing.assert_allclose(sim.positions - rest, np.tile([2.0, 0.0, 0.0], (8, 1)),
                               atol=1e-9)  # fmt: skip


def test_an_initial_velocity_on_part_of_a_body_is_refused(tmp_path):
    path = tmp_path / "part.feb"
    path.write_text(_flying("1,2,3,4"))
    with pytest.raises(FebError, match=r"part\.feb:\d+ <ic>: an initial velocity on 4"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            load_febio(path)


def test_a_linear_constraint_pulls_the_face_with_one_node(tmp_path):
    """FEBio's linear constraint (parent = value * child + offset): only node 7 of the x = 1
    face is pulled, nodes 2, 3 and 6 follow its x through constraints, one of them with a
    value on a load curve that is 1 at the end and an offset 0: the same cube as the face
    pulled whole, to the penalty's 1e-5."""
    text = CUBE.replace('<NodeSet name="x1">2,3,6,7</NodeSet>', '<NodeSet name="x1">7</NodeSet>')
    bcs = "".join(
        f'    <bc name="follow{n}" type="linear constraint">\n      <dof>x</dof>\n'
        f"      <node>{n}</node>\n      <offset>0</offset>\n      <child_dof>\n"
        f"        <dof>x</dof>\n        <node>7</node>\n        <value{lc}>1</value>\n"
        "      </child_dof>\n    </bc>\n"
        for n, lc in ((2, ""), (3, ' lc="1"'), (6, ""))
    )
    text = text.replace("  </Boundary>", bcs + "  </Boundary>")
    sim = _run(text, tmp_path)
    ref = _run(CUBE, tmp_path, "ref.feb")
    np.testing.assert_allclose(sim.positions, ref.positions, atol=1e-5 * 0.15)
    assert sim.positions[1, 0] == pytest.approx(1.15, abs=1e-5 * 0.15)
    model = read_feb(tmp_path / "m.feb")
    assert [c["parent"] for c in model.linear_constraints] == [(1, 0), (2, 0), (5, 0)]


def _twisted(rotation: str) -> str:
    """The rigid platen model with the platen turned about z instead of held (``rotation``
    replaces its Ru, Rv, Rw rows)."""
    text = (MODELS / "rigid_platen.feb").read_text()
    return text.replace(
        "      <Ru_dof>1</Ru_dof>\n      <Rv_dof>1</Rv_dof>\n      <Rw_dof>1</Rw_dof>\n"
        "    </rigid_bc>",
        f"      <Ru_dof>0</Ru_dof>\n      <Rv_dof>0</Rv_dof>\n      <Rw_dof>0</Rw_dof>\n"
        f"    </rigid_bc>\n{rotation}",
    )


def test_a_rigid_rotation_vector_is_three_prescribed_rotations(tmp_path):
    """FEBio's rigid_rotation_vector (FERigidRotationVector) prescribes Ru, Rv, Rw to vx, vy,
    vz: the same motion as three rigid_rotation conditions; the platen ends turned 0.2 rad
    about z (R = exp(0.2 e_z))."""
    vector = _twisted(
        '    <rigid_bc name="turn" type="rigid_rotation_vector">\n      <rb>platen</rb>\n'
        '      <vx>0</vx>\n      <vy>0</vy>\n      <vz lc="1">0.2</vz>\n    </rigid_bc>\n'
    )
    three = _twisted("".join(
        f'    <rigid_bc name="turn{d}" type="rigid_rotation">\n      <rb>platen</rb>\n'
        f'      <dof>{d}</dof>\n      <value lc="1">{v}</value>\n    </rigid_bc>\n'
        for d, v in (("Ru", 0.0), ("Rv", 0.0), ("Rw", 0.2))
    ))  # fmt: skip
    sim, ref = _run(vector, tmp_path), _run(three, tmp_path, "ref.feb")
    np.testing.assert_allclose(sim.body_positions("block"), ref.body_positions("block"),
                               atol=1e-12)  # fmt: skip
    _, R = sim.rigid_state("platen")
    c, s = np.cos(0.2), np.sin(0.2)
    np.testing.assert_allclose(R, [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-9)


def _face_load(kind: str, body: str) -> str:
    """The cube with its x = 1 face free and loaded by a surface_load of ``kind``."""
    text = CUBE.replace(
        '    <bc name="pull" node_set="x1" type="prescribed displacement">\n      <dof>x</dof>\n'
        '      <value lc="1">0.15</value>\n      <relative>0</relative>\n    </bc>\n',
        "",
    )
    text = text.replace("  </Mesh>", '    <Surface name="right">\n      <quad4 id="1">2,3,7,6'
                        "</quad4>\n    </Surface>\n  </Mesh>")  # fmt: skip
    return text.replace(
        "  <LoadData>",
        f'  <Loads>\n    <surface_load surface="right" type="{kind}">\n{body}'
        "    </surface_load>\n  </Loads>\n  <LoadData>",
    )


def test_a_surface_force_is_the_traction_of_force_over_area(tmp_path):
    """FEBio's surface_load type="force" (FESurfaceForceUniform): scale * force / A as a dead
    traction (A = 1 here): the same cube as the traction 2 * (150, 0, 0) on the face."""
    force = _face_load("force", '      <scale lc="1">2</scale>\n      <force>150,0,0</force>\n')
    traction = _face_load("traction", '      <traction lc="1">300,0,0</traction>\n'
                          "      <linear>1</linear>\n")  # fmt: skip
    sim, ref = _run(force, tmp_path), _run(traction, tmp_path, "ref.feb")
    np.testing.assert_allclose(sim.positions, ref.positions, atol=1e-12)
    assert sim.positions[1, 0] > 1.05  # stretched


def test_facet_area_of_triangles_and_quadrilaterals():
    from tissuesim.febio.load_fields import facet_area

    points = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0], [3, 1, 0.0]])
    assert facet_area(points, np.array([[0, 1, 2, 3]])) == pytest.approx(2.0, rel=1e-14)
    assert facet_area(points, np.array([[0, 1, 4, 3]])) == pytest.approx(2.5, rel=1e-14)
    assert facet_area(points, np.array([[0, 1, 2]])) == pytest.approx(1.0, rel=1e-14)


def _with_body_load(kind: str, x: str) -> str:
    text = CUBE.replace('<value lc="1">0.15</value>', '<value lc="1">0.0</value>')
    attr = ' type="math"' if kind == "non-const" else ""
    return text.replace(
        "  <LoadData>",
        f'  <Loads>\n    <body_load type="{kind}">\n      <x lc="1"{attr}>{x}</x>\n'
        "    </body_load>\n  </Loads>\n  <LoadData>",
    )


def test_a_non_const_body_load_is_its_expression_of_the_rest_coordinates(tmp_path):
    """FEBio 3's non-const body load: f = 2 X (reference x) per unit mass, applied as -rho f
    (as a const one): the x supports (x = 0 face and the held x = 1 face) carry
    rho * int 2 X dV = 1000 N along +x; a constant expression equals the const load."""
    sim = _run(_with_body_load("non-const", "2*X"), tmp_path)
    f = sim.forces()
    assert f["sx"][0] + f["pull"][0] == pytest.approx(1000.0, rel=1e-9)
    flat = _run(_with_body_load("non-const", "3"), tmp_path, "flat.feb")
    const = _run(_with_body_load("const", "3"), tmp_path, "const.feb")
    np.testing.assert_allclose(flat.positions, const.positions, atol=1e-12)


def _connectors():
    """The rigid connector tests' two-cube model (a fixed ground, a free block)."""
    import importlib.util

    path = Path(__file__).parent / "test_febio_rigid_connectors.py"
    spec = importlib.util.spec_from_file_location("_rigid_connectors", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_force_on_a_prismatic_joint_pushes_its_bodies_apart_along_the_axis(tmp_path):
    """FEBio's prismatic joint <force> F (FERigidPrismaticJoint: F e on body a, -F e on body
    b): 6 N on the rail whose body a is the fixed ground moves the block -6 / 40 m along x
    against the 40 N/m spring, as a rigid force of -6 N on the block does."""
    rc = _connectors()
    with_force = rc.model(rc.SLIDER.replace("<force>0</force>", '<force lc="1">6</force>'))
    sim = _run(with_force, tmp_path)
    centre, R = sim.rigid_state("block")
    assert centre == pytest.approx([1.5 - 6.0 / 40.0, 0.0, 0.0], abs=1e-8)
    ref = _run(rc.model(rc.SLIDER, rc.PULL.replace('lc="1">6<', 'lc="1">-6<')), tmp_path, "r.feb")
    np.testing.assert_allclose(sim.state.x, ref.state.x, atol=1e-12)


def test_a_force_on_a_prismatic_joint_of_free_bodies_is_refused(tmp_path):
    rc = _connectors()
    text = rc.model(rc.SLIDER.replace("<force>0</force>", "<force>6</force>"))
    text = text.replace("<Ru_dof>1</Ru_dof>", "<Ru_dof>0</Ru_dof>")
    path = tmp_path / "free.feb"
    path.write_text(text)
    with pytest.raises(FebError, match="a force on a prismatic joint whose bodies may turn"):
        read_feb(path)


def _quaternion_matrix(ex: float, ey: float, ez: float) -> np.ndarray:
    """R of FEBio's quatd::SetEuler(X, Y, Z) (radians), from the unit quaternion."""
    cx, sx, cy, sy, cz, sz = (f(a / 2) for a in (ex, ey, ez) for f in (np.cos, np.sin))
    w = cz * cx * cy + sz * sx * sy
    x = cz * sx * cy - sz * cx * sy
    y = cz * cx * sy + sz * sx * cy
    z = sz * cx * cy - cz * sx * sy
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


@pytest.mark.parametrize("angles", [(0.0, 0.0, 30.0), (20.0, -35.0, 50.0)])
def test_rigid_euler_angles_turn_the_platen_by_febios_quaternion(angles, tmp_path):
    """FEBio's rigid_euler_angles (FERigidEulerAngles: Ex, Ey, Ez in degrees, each with its
    curve): the platen ends turned by the quaternion's rotation (about z alone: the plain
    rotation by Ez)."""
    rows = "".join(f'      <E{a} lc="1">{v}</E{a}>\n' for a, v in zip("xyz", angles, strict=True))
    text = _twisted(f'    <rigid_bc name="turn" type="rigid_euler_angles">\n      <rb>platen</rb>\n'
                    f"{rows}    </rigid_bc>\n")  # fmt: skip
    sim = _run(text, tmp_path)
    _, R = sim.rigid_state("platen")
    np.testing.assert_allclose(R, _quaternion_matrix(*np.radians(angles)), atol=1e-9)
    if angles[:2] == (0.0, 0.0):
        c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
        np.testing.assert_allclose(R, [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-9)


def test_a_part_of_two_pieces_meeting_at_coincident_nodes_is_two_bodies(tmp_path):
    """FEBio keeps coincident nodes apart: a part of two cubes whose shared face has its own
    nodes in each is two pieces (co01's blocks). The second cube (x in [1, 2], its x = 1
    face held along x, its x = 2 face pulled 0.15) stretches as the first: the same
    displacements, each a body of its own, one changed: line."""
    coords = {2: (1, 0, 0), 3: (1, 1, 0), 4: (0, 1, 0), 6: (1, 0, 1), 7: (1, 1, 1), 8: (0, 1, 1)}
    coords.update({1: (0, 0, 0), 5: (0, 0, 1)})
    second = "".join(f'      <node id="{n + 8}">{x + 1},{y},{z}</node>\n'
                     for n, (x, y, z) in sorted(coords.items()))  # fmt: skip
    text = CUBE.replace("    </Nodes>", second + "    </Nodes>")
    text = text.replace('<elem id="1">1,2,3,4,5,6,7,8</elem>',
                        '<elem id="1">1,2,3,4,5,6,7,8</elem>\n'
                        '      <elem id="2">9,10,11,12,13,14,15,16</elem>')  # fmt: skip
    for name, first, more in (
        ("x0", "1,4,5,8", "9,12,13,16"),
        ("y0", "1,2,5,6", "9,10,13,14"),
        ("z0", "1,2,3,4", "9,10,11,12"),
        ("x1", "2,3,6,7", "10,11,14,15"),
    ):
        text = text.replace(f'<NodeSet name="{name}">{first}</NodeSet>',
                            f'<NodeSet name="{name}">{first},{more}</NodeSet>')  # fmt: skip
    sim = _run(text, tmp_path)
    assert len(sim.bodies) == 2
    one, two = (sim.body_positions(n) for n in sim.bodies)
    np.testing.assert_allclose(two - one, np.tile([1.0, 0.0, 0.0], (8, 1)), atol=1e-9)
    assert one[1, 0] == pytest.approx(1.15)
    model = read_feb(tmp_path / "m.feb")
    from tissuesim.febio.scene import scene_bodies

    names = [n for n, _ in scene_bodies(model)]
    assert names == ["cube", "cube.2"]
    assert any("2 pieces" in line for line in model.changes)


def test_an_edge_is_the_node_set_a_condition_names(tmp_path):
    """<Edge> (line2 segments) read as the node set "@edge:name" (nl01's supports): the
    cube's y0 support given on the edge of its nodes 1, 2, 5, 6 is the same cube."""
    text = CUBE.replace(
        "  </Mesh>",
        '    <Edge name="side">\n      <line2 id="1">1,2</line2>\n      <line2 id="2">5,6</line2>\n'
        "    </Edge>\n  </Mesh>",
    ).replace('node_set="y0"', 'node_set="@edge:side"')
    sim, ref = _run(text, tmp_path), _run(CUBE, tmp_path, "ref.feb")
    np.testing.assert_allclose(sim.positions, ref.positions, atol=1e-12)
    model = read_feb(tmp_path / "m.feb")
    assert model.node_sets["@edge:side"].tolist() == [0, 1, 4, 5]


def _node_distance(rows: str) -> str:
    """The cube with a node distance constraint between nodes 3 and 7 (0, 0, 1 apart)."""
    return CUBE.replace(
        "  <LoadData>",
        '  <Constraints>\n    <constraint name="nd" type="node distance">\n'
        f"      <laugon>0</laugon>\n      <node>3,7</node>\n{rows}"
        "    </constraint>\n  </Constraints>\n  <LoadData>",
    )


@pytest.mark.parametrize(
    "rows",
    [
        "      <penalty>40</penalty>\n      <target>0</target>\n      <relative>1</relative>\n",
        '      <penalty lc="1">40</penalty>\n      <target>0</target>\n'
        "      <relative>1</relative>\n",
        "      <penalty>40</penalty>\n      <target>1</target>\n      <relative>0</relative>\n",
    ],
)
def test_a_node_distance_constraint_is_a_spring_of_its_target_length(rows, tmp_path):
    """FEBio's node distance (FEDistanceConstraint, laugon 0): the force eps (l - l0), l0 the
    target (relative: the rest distance plus the target), eps the penalty (times its curve):
    at the end of the pull the same cube as a 40 N/m linear spring between the two nodes."""
    sim = _run(_node_distance(rows), tmp_path)
    spring = CUBE.replace(
        "  </Mesh>",
        '    <DiscreteSet name="tie">\n      <delem>3,7</delem>\n    </DiscreteSet>\n  </Mesh>',
    ).replace(
        "  <LoadData>",
        '  <Discrete>\n    <discrete_material id="1" name="s" type="linear spring">\n'
        "      <E>40</E>\n    </discrete_material>\n"
        '    <discrete dmat="1" discrete_set="tie"/>\n  </Discrete>\n  <LoadData>',
    )
    ref = _run(spring, tmp_path, "ref.feb")
    np.testing.assert_allclose(sim.positions, ref.positions, atol=1e-9)
    assert abs(sim.positions[6, 2] - ref.positions[6, 2]) < 1e-9
    plain = _run(CUBE, tmp_path, "plain.feb")
    assert np.abs(sim.positions - plain.positions).max() > 1e-4  # the spring does act


def _with_globals(text: str, a: float, b: float) -> str:
    """A model with FEBio's global parameters a and b (<Globals><Variables>)."""
    globals_ = (f'  <Globals>\n    <Variables>\n      <var name="a">{a!r}</var>\n'
                f'      <var name="b">{b!r}</var>\n    </Variables>\n  </Globals>\n')  # fmt: skip
    return text.replace("  <Material>", globals_ + "  <Material>", 1)


MATH = ('type="nonlinear spring">\n      <force type="math">\n'
        "        <math>fem.a*(exp(fem.b*x)-1)</math>\n      </force>")  # fmt: skip


@pytest.mark.parametrize("anchor", [(2.0, 0.0, 0.0), (-1.0, 0.0, 0.0)])
def test_a_math_force_of_global_parameters_is_its_closed_form(anchor, plain, tmp_path):
    """FEBio's nonlinear spring with a math force of its global parameters (op05's
    fem.a*(exp(fem.b*x)-1)): the pull grows by -F(DL) = -a (exp(b DL) - 1) at DL = -+0.15."""
    a, b = 0.7, 3.0
    sim = _run(_with_globals(_with_spring(anchor, MATH), a, b), tmp_path)
    dl = -0.15 if anchor[0] > 1 else 0.15  # compressed to the right, stretched to the left
    force = a * (np.exp(b * dl) - 1.0)
    extra = -force if dl < 0 else force  # the reaction grows by |F| either way
    pull = np.asarray(sim.forces()["pull"])
    np.testing.assert_allclose(pull - plain, [extra, 0.0, 0.0], atol=1e-7 * abs(plain[0]))


def test_math_force_refusals_name_the_element(tmp_path):
    text = _with_globals(_with_spring((2.0, 0.0, 0.0), MATH), 0.7, 3.0)
    bad = {
        r"fem.c: no <var name='c'>": text.replace("fem.b*x", "fem.c*x"),
        r"<math>: .*'lgamma'": text.replace("exp(fem.b*x)", "lgamma(fem.b*x)"),
        r'<var>: expected <var name="a">value</var>': text.replace('<var name="b">', "<var>"),
    }
    for message, deck in bad.items():
        path = tmp_path / "bad.feb"
        path.write_text(deck)
        with pytest.raises(FebError, match=message):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                load_febio(path)


def _two_cubes(link: str = 'type="linear spring"><E>5</E>') -> str:
    """Two unit cubes 1 apart, the left one held at x = 0, the right one's end pulled 0.3
    along x, joined by four discrete springs of material ``link``."""
    nodes = [(x, y, z) for x0 in (0.0, 2.0) for x in (x0, x0 + 1) for y in (0, 1) for z in (0, 1)]
    node_text = "\n".join(f'      <node id="{i + 1}">{x},{y},{z}</node>'
                          for i, (x, y, z) in enumerate(nodes))  # fmt: skip
    cube = "{},{},{},{},{},{},{},{}"
    first, second = (1, 5, 7, 3, 2, 6, 8, 4), tuple(i + 8 for i in (1, 5, 7, 3, 2, 6, 8, 4))
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control><analysis>STATIC</analysis><time_steps>2</time_steps><step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="soft" type="neo-Hookean"><density>1</density><E>10</E><v>0.3</v>
    </material>
    <material id="2" name="stiff" type="neo-Hookean"><density>1</density><E>1000</E><v>0.3</v>
    </material>
  </Material>
  <Mesh>
    <Nodes name="all">
{node_text}
    </Nodes>
    <Elements type="hex8" name="left"><elem id="1">{cube.format(*first)}</elem></Elements>
    <Elements type="hex8" name="right"><elem id="2">{cube.format(*second)}</elem></Elements>
    <NodeSet name="wall">1, 2, 3, 4</NodeSet>
    <NodeSet name="end">13, 14, 15, 16</NodeSet>
    <DiscreteSet name="links"><delem>5,9</delem><delem>6,10</delem><delem>7,11</delem>
      <delem>8,12</delem></DiscreteSet>
  </Mesh>
  <MeshDomains><SolidDomain name="left" mat="soft"/><SolidDomain name="right" mat="stiff"/>
  </MeshDomains>
  <Boundary>
    <bc name="wall" node_set="wall" type="zero displacement">
      <x_dof>1</x_dof><y_dof>1</y_dof><z_dof>1</z_dof></bc>
    <bc name="end" node_set="end" type="prescribed displacement"><dof>x</dof>
      <value lc="1">0.3</value><relative>0</relative></bc>
  </Boundary>
  <Discrete>
    <discrete_material id="1" name="link" {link}</discrete_material>
    <discrete dmat="1" discrete_set="links"/>
  </Discrete>
  <LoadData><load_controller id="1" type="loadcurve"><interpolate>LINEAR</interpolate>
    <points><pt>0,0</pt><pt>1,1</pt></points></load_controller></LoadData>
</febio_spec>
"""


def test_two_parts_joined_by_springs_are_one_body_of_two_regions(tmp_path):
    """Parts that only discrete springs join (op05's model) make one body, its parts regions:
    a spring joins vertices of one body. Two unit cubes 1 apart, the second pulled by 0.3
    along x, joined by four linear springs: each spring carries E DL, and their pull along x
    is the wall's reaction."""
    text = _two_cubes()
    sim = _run(text, tmp_path)
    assert list(sim.bodies) == ["left"]  # one body, named after its first part
    body = sim.bodies["left"]
    assert body.mesh.n_cells == 2
    springs = body.springs[0]
    x = sim.body_positions("left")
    tension, direction = springs.tensions(x.ravel())
    pairs = springs.pairs
    stretch = np.linalg.norm(x[pairs[:, 1]] - x[pairs[:, 0]], axis=1) - 1.0
    np.testing.assert_allclose(tension, 5.0 * stretch, rtol=1e-12)
    pulled = float(tension @ direction[:, 0])  # the springs' pull along x on the left cube
    np.testing.assert_allclose(-sim.forces()["wall"][0], pulled, rtol=1e-6)


def test_a_global_parameter_of_a_math_spring_is_fitted(tmp_path):
    """FEBio's op05 pattern: <param name="fem.a"> (a <Globals><Variables> value) in a spring's
    math force. The left cube's free face position from our own run at a = 0.7 is fitted from
    a = 0.3 by the run's sensitivities (through the spring's law) and recovers a."""
    from tissuesim.febio.optimize.run import run_optimize
    from tissuesim.febio.optimize.task import read_optimize

    link = ('type="nonlinear spring"><force type="math"><math>fem.a*(exp(fem.b*x)-1)</math>'
            "</force>")  # fmt: skip
    model = tmp_path / "linked.feb"
    model.write_text(_with_globals(_two_cubes(link), 0.7, 2.0))
    sim = _run(model.read_text(), tmp_path, "probe.feb")
    target = float(sim.body_positions("left")[4, 0])  # node 5, (1, 0, 0) at rest
    assert target > 1.0 + 1e-3  # the springs stretch the left cube
    task = tmp_path / "fit.feb"
    task.write_text(f"""<?xml version="1.0"?>
<febio_optimize version="2.0">
  <Options type="levmar"><obj_tol>1e-12</obj_tol></Options>
  <Parameters><param name="fem.a">0.3, 0.01, 5</param></Parameters>
  <Objective type="target"><var name="fem.mesh.node.fromId(5).position.x">{target!r}</var>
  </Objective>
</febio_optimize>
""")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = run_optimize(read_optimize(task), model)
    assert fit.parameters["fem.a"] == pytest.approx(0.7, rel=1e-6)
