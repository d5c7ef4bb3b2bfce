"""FEBio shells that share nodes with a deformable solid (febio/shells.py ``attach_solid``,
FEBio's FESSIShellDomain::FindSSI): a solid behind the shell takes the shell's back face
(its cells renumbered to the back nodes, at X - D), a solid in front shares u; and the body
names the converter makes valid ("Part3(2)" -> "Part3_2")."""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.febio import load_febio, read_feb
from tissuesim.febio.scene import body_name

MODELS = Path(__file__).parent / "models"
CANTILEVER = MODELS / "shell_cantilever_quad4.feb"
L, H, E = 1.0, 0.1, 1000.0  # the plate's length, thickness and law (neo-Hookean, v = 0)
#: the first shell element's nodes (ids 1, 2, 83, 82): the face a block is put on
FIRST = [0, 1, 82, 81]


def with_block(side: str, material: str = "plate") -> str:
    """The cantilever with a hex8 block 0.5 deep under (``side`` "below": behind the shell,
    whose normal is +z) or on (``"above"``) its first element, of the plate's material or
    of a second one."""
    text = CANTILEVER.read_text()
    z = -0.5 if side == "below" else 0.5
    corners = [(0.0, 0.0), (0.0125, 0.0), (0.0125, 0.1), (0.0, 0.1)]
    nodes = "".join(f'<node id="{301 + k}">{x},{y},{z}</node>' for k, (x, y) in enumerate(corners))
    text = text.replace("    </Nodes>", f"{nodes}\n    </Nodes>")
    cell = "301,302,303,304,1,2,83,82" if side == "below" else "1,2,83,82,301,302,303,304"
    block = f'<Elements type="hex8" name="block"><elem id="1000">{cell}</elem>'
    text = text.replace("    <NodeSet", f"    {block}</Elements>\n    <NodeSet", 1)
    if material != "plate":
        text = text.replace(
            "  </Material>", f'<material id="2" name="{material}" type="neo-Hookean">'
            "<E>10</E><v>0.3</v></material>\n  </Material>",
        )  # fmt: skip
    return text.replace(
        "  </MeshDomains>", f'<SolidDomain name="block" mat="{material}"/>\n  </MeshDomains>'
    )


def test_a_solid_behind_the_shell_takes_its_back_face_and_one_in_front_its_nodes(tmp_path):
    """Below the plate (the solid face's outward normal along the shell's normal) the block's
    four shared nodes are the shell's back nodes (at z = -H); above it they stay the
    shell's nodes; the block's other nodes are untouched either way."""
    path = tmp_path / "below.feb"
    path.write_text(with_block("below"))
    model = read_feb(path)
    back = model._shells.back
    cells = model.parts["block"][1]
    np.testing.assert_array_equal(cells[0, 4:], [back[i] for i in FIRST])
    np.testing.assert_allclose(model.nodes[cells[0, 4:], 2], -H, atol=1e-15)
    np.testing.assert_allclose(model.nodes[cells[0, :4], 2], -0.5)
    path.write_text(with_block("above"))
    model = read_feb(path)
    np.testing.assert_array_equal(model.parts["block"][1][0, :4], FIRST)


def run_scene(path: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = read_feb(path)
        scene = load_febio(path)
        sim = scene.simulation
        for _ in range(scene.run["steps"]):
            sim.step()
    return model, sim.body_positions("body")


def api_plate_on_block(on_back: bool) -> np.ndarray:
    """Final positions of the API's mesh: solid_shell(reference="top") of the plate plus the
    block's hexahedron on the back nodes of the first element (``on_back``) or on its front
    nodes, clamped and loaded as the deck (the clamp on the front and back nodes at x = 0,
    not on the block); rows front, back, the block's four."""
    n = 81 * 3
    gx, gy = np.meshgrid(np.linspace(0, L, 81), np.linspace(0, 0.2, 3), indexing="xy")
    points = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    idx = np.arange(n).reshape(3, 81)
    quads = np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], -1).reshape(-1, 4)
    shell = ts.mesh.solid_shell(points, quads, H, reference="top", normalize=False)
    below = np.array([[0, 0, -0.5], [0.0125, 0, -0.5], [0.0125, 0.1, -0.5], [0, 0.1, -0.5]])
    top = np.array(FIRST) + (n if on_back else 0)
    block = np.concatenate([2 * n + np.arange(4), top])
    mesh = ts.mesh.Mesh(
        np.vstack([shell.points, below]), np.vstack([shell.cells, block[None]]), source="api"
    )
    sim = ts.Simulation(
        mesh, ts.NeoHookean(youngs_modulus=E, poisson_ratio=0.0), integrator="quasistatic",
        time_step=0.5,
    )  # fmt: skip
    sim.add_dirichlet(np.flatnonzero(np.isclose(mesh.points[: 2 * n, 0], 0.0)))
    ends = np.flatnonzero(np.isclose(mesh.points[:n, 0], L))
    sim.add_nodal_forces(ends, lambda t: np.tile([0.0, 0.0, 1e-4 * t / 3], (len(ends), 1)))
    sim.step()
    sim.step()
    return mesh.points + sim.displacement


def test_a_plate_on_a_block_runs_as_the_solid_built_in_the_api(tmp_path):
    """The plate with the block of its own material under its first element (one body) runs
    as the API's mesh with the block on the back nodes, to round-off; with the block on the
    front nodes (as a solid in front would be) the positions differ by far more."""
    path = tmp_path / "below.feb"
    path.write_text(with_block("below"))
    model, x = run_scene(path)
    n = 81 * 3
    assert model.nodes.shape == (2 * n + 4, 3)
    # the deck's rows: its nodes (front, the block's four), then the back nodes
    x = np.concatenate([x[:n], x[n + 4 :], x[n : n + 4]])
    np.testing.assert_allclose(api_plate_on_block(True), x, rtol=0, atol=1e-12)
    assert abs(api_plate_on_block(False) - x).max() > 1e-6


def test_a_solid_of_another_material_is_a_region_of_the_shell_body(tmp_path):
    """A shell on a solid of another law is one body of two regions (FEBio's sh17 ... sh50
    are): the plate's cells of its law, the block's of the other, on shared nodes."""
    path = tmp_path / "two.feb"
    path.write_text(with_block("below", "block"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        body = load_febio(path).simulation.body("plate")
    plate, block = body.model.parts
    assert (plate.name, block.name) == ("plate", "block")
    assert block.cells.size == 1 and plate.cells.size == body.mesh.n_cells - 1
    assert block.material.mu == pytest.approx(10 / 2.6)  # E 10, v 0.3
    assert np.intersect1d(plate.mesh.cells, block.mesh.cells).size == 4


def test_body_names_are_made_valid_and_unique():
    """FEBio's part names that name no file are written with '_' for the other characters,
    kept unique; valid names are kept."""
    assert body_name("Part3(2)", set()) == "Part3_2"
    assert body_name("Part3(2)", {"Part3_2"}) == "Part3_2.2"
    assert body_name("(x)", set()) == "x"
    assert body_name("()", set()) == "part"
    assert re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]*", body_name("_a b", set()))


def test_a_part_named_with_brackets_runs_under_a_valid_name(tmp_path):
    """Two bodies, one of them "plate(2)": the scene names it "plate_2" and says so in the
    converted scene's changes."""
    text = with_block("above", "block").replace('name="block"', 'name="block(2)"')
    text = text.replace('mat="block(2)"', 'mat="block"').replace(
        'name="block(2)" type="neo-Hookean"', 'name="block" type="neo-Hookean"'
    )
    text = text.replace("1,2,83,82,301,302,303,304", "301,302,303,304,1001,1002,1003,1004")
    extra = "".join(
        f'<node id="{1001 + k}">{x},{y},1.0</node>'
        for k, (x, y) in enumerate([(0.0, 0.0), (0.0125, 0.0), (0.0125, 0.1), (0.0, 0.1)])
    )
    text = text.replace("    </Nodes>", f"{extra}\n    </Nodes>")
    path = tmp_path / "named.feb"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(path)
    assert "block_2" in scene.simulation.bodies


def pressed_block(thickness: float, domain: str = "") -> str:
    """A unit hex8 block (neo-Hookean), its bottom held, under a rigid quad4 shell on its top
    face (sharing its four nodes) pushed down 0.1 by a rigid_displacement: the rigid shell
    of ``thickness`` (0: none, as FEBio's sh01) and ``domain`` the ShellDomain's type."""
    corners = [(0, 0), (1, 0), (1, 1), (0, 1)]
    nodes = "".join(
        f'<node id="{k + 1 + 4 * z}">{x},{y},{z}</node>' for z in (0, 1)
        for k, (x, y) in enumerate(corners)
    )  # fmt: skip
    kind = f' type="{domain}"' if domain else ""
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control><analysis>STATIC</analysis><time_steps>2</time_steps><step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="block" type="neo-Hookean"><density>1</density><E>1000</E><v>0.3</v>
    </material>
    <material id="2" name="plate" type="rigid body"><density>1</density>
      <center_of_mass>0.5,0.5,1</center_of_mass></material>
  </Material>
  <Mesh>
    <Nodes name="all">{nodes}</Nodes>
    <Elements type="hex8" name="block"><elem id="1">1,2,3,4,5,6,7,8</elem></Elements>
    <Elements type="quad4" name="plate"><elem id="2">5,6,7,8</elem></Elements>
    <NodeSet name="bottom">1, 2, 3, 4</NodeSet>
  </Mesh>
  <MeshDomains>
    <SolidDomain name="block" mat="block"/>
    <ShellDomain name="plate" mat="plate"{kind}><shell_thickness>{thickness}</shell_thickness>
    </ShellDomain>
  </MeshDomains>
  <Boundary>
    <bc name="hold" node_set="bottom" type="zero displacement">
      <x_dof>1</x_dof><y_dof>1</y_dof><z_dof>1</z_dof>
    </bc>
  </Boundary>
  <Rigid>
    <rigid_bc name="fix" type="rigid_fixed"><rb>plate</rb><Rx_dof>1</Rx_dof><Ry_dof>1</Ry_dof>
      <Rz_dof>0</Rz_dof><Ru_dof>1</Ru_dof><Rv_dof>1</Rv_dof><Rw_dof>1</Rw_dof></rigid_bc>
    <rigid_bc name="push" type="rigid_displacement"><rb>plate</rb><dof>z</dof>
      <value lc="1">-0.1</value><relative>0</relative></rigid_bc>
  </Rigid>
  <LoadData>
    <load_controller id="1" name="LC1" type="loadcurve"><interpolate>LINEAR</interpolate>
      <points><pt>0,0</pt><pt>1,1</pt></points></load_controller>
  </LoadData>
</febio_spec>
"""


def test_a_rigid_shell_without_thickness_makes_no_body_and_pushes_its_nodes(tmp_path):
    """FEBio takes a rigid shell of no thickness (sh01): here it makes no FEM body (a line in
    the changes says so), its nodes shared with the block move with the rigid body, and the
    block ends as under the same rigid shell 0.05 thick (the rigid body's motion is
    prescribed: its mass plays no part), its top 0.1 down."""
    runs = {}
    for h in (0.0, 0.05):
        path = tmp_path / f"pressed{h}.feb"
        path.write_text(pressed_block(h))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene = load_febio(path)
            sim = scene.simulation
            for _ in range(scene.run["steps"]):
                sim.step()
        runs[h] = sim.body_positions("block")
        if h == 0.0:
            model = read_feb(path)
            assert "plate" not in sim.bodies and len(sim.bodies) == 1
    np.testing.assert_allclose(runs[0.0], runs[0.05], rtol=0, atol=1e-12)
    np.testing.assert_allclose(runs[0.0][4:, 2], 0.9, atol=1e-12)
    assert abs(runs[0.0][4:, :2] - model.nodes[4:8, :2]).max() < 1e-12


def test_a_rigid_shell_domain_takes_a_rigid_material_only(tmp_path):
    """type="rigid-shell" (FERigidShellDomain) on a rigid body material reads as the default
    shell does; on a deformable law it is refused in one line."""
    path = tmp_path / "rigid.feb"
    path.write_text(pressed_block(0.05, "rigid-shell"))
    assert read_feb(path).domains["plate"][0] == "plate"
    text = pressed_block(0.05, "rigid-shell").replace('mat="plate" type', 'mat="block" type')
    path.write_text(text)
    with pytest.raises(InputError, match=r"rigid.feb:\d+ <ShellDomain>: a rigid-shell domain "
                       r"takes a rigid body material, not 'neo-Hookean'"):  # fmt: skip
        read_feb(path)


def plate_over_block(thickness: float) -> str:
    """The pressed block's deck with its rigid shell apart from the block (its own four nodes,
    0.01 above the top face) and a sliding-elastic contact between the block's top and it."""
    text = pressed_block(thickness)
    above = "".join(
        f'<node id="{9 + k}">{x},{y},1.01</node>'
        for k, (x, y) in enumerate([(0, 0), (1, 0), (1, 1), (0, 1)])
    )
    text = text.replace("</Nodes>", f"{above}</Nodes>").replace(
        '<elem id="2">5,6,7,8</elem>', '<elem id="2">9,10,11,12</elem>'
    )
    surfaces = (
        '<Surface name="top"><quad4 id="1">5,6,7,8</quad4></Surface>'
        '<Surface name="plate"><quad4 id="1">9,12,11,10</quad4></Surface>'
        '<SurfacePair name="pair"><primary>top</primary><secondary>plate</secondary></SurfacePair>'
    )
    text = text.replace("</Mesh>", f"{surfaces}</Mesh>")
    contact = (
        '<Contact><contact name="c" surface_pair="pair" type="sliding-elastic">'
        "<fric_coeff>0</fric_coeff></contact></Contact>"
    )
    return text.replace("  <Rigid>", f"  {contact}\n  <Rigid>")


def test_a_rigid_shell_without_thickness_carrying_a_contact_surface_gets_one(tmp_path):
    """A rigid shell of no thickness that carries a contact surface (FEBio's sh29) keeps a
    body, given 1e-3 of its size as a thickness in a static analysis (a line in the changes
    says so; its front face, the contact surface, is exact); one that shares nodes with a
    deformable shell, or in a dynamic analysis, makes no body as before."""
    from tissuesim.febio.scene import febio_scene

    path = tmp_path / "contact.feb"
    path.write_text(plate_over_block(0.0))
    model = read_feb(path)
    tables, meshes = febio_scene(model, "contact")
    assert len(meshes) == 2 and any("is given 0.00141" in line for line in model.changes)
    shells = model._shells
    np.testing.assert_allclose(shells.thickness["plate"], 1e-3 * 2**0.5)
    back = [shells.back[i] for i in range(8, 12)]
    np.testing.assert_allclose(model.nodes[back, 2], 1.01 - 1e-3 * 2**0.5)
    path.write_text(
        plate_over_block(0.0).replace("<analysis>STATIC</analysis>", "<analysis>DYNAMIC</analysis>")
    )
    model = read_feb(path)
    from tissuesim.febio.shells import check_thickness

    assert check_thickness(model) == {"plate"}
