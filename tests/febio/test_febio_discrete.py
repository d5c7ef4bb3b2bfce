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
    """The wall at z = 0 under the cube's bottom face rises 0.1 against its top held in z:
    the same as the bottom nodes moved 0.1 up (free in x and y: the wall has no friction),
    to within the barrier's dhat (the wall is set dhat apart at the start)."""
    sim = _run(_walled(0.1), tmp_path)
    ref_text = _walled(0.1).replace('type="rigid_wall"', 'type="x"')
    start = ref_text.index("  <Constraints>")
    ref_text = ref_text[:start] + ref_text[ref_text.index("  <LoadData>") :]
    ref_text = ref_text.replace(
        "  </Boundary>",
        '    <bc name="lift" node_set="z0" type="prescribed displacement">\n      <dof>z</dof>\n'
        '      <value lc="1">0.1</value>\n      <relative>0</relative>\n    </bc>\n'
        "  </Boundary>",
    )
    ref = _run(ref_text, tmp_path, "ref.feb")
    dhat = 1e-3 * np.sqrt(2.0)
    x, y = sim.positions, ref.positions
    assert np.abs(x - y).max() < 2 * dhat
    assert x[:4, 2].min() > 0.1 - dhat  # above the wall (set dhat below the surface)
    top, top_ref = sim.forces()["sz"][2], ref.forces()["sz"][2]
    assert top < -1.0 and top == pytest.approx(top_ref, rel=0.05)
    model = read_feb(tmp_path / "m.feb")
    assert any("rigid wall" in line for line in model.changes)


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
