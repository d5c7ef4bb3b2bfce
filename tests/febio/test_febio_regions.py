"""FEBio parts that share nodes but not a material: one body of several regions
(febio/scene.py ``_bodies``), each region its parts' material; a deck written here."""

import warnings

import numpy as np
import pytest

from tissuesim.errors import InputError
from tissuesim.febio import load_febio, read_feb
from tissuesim.febio.scene import febio_scene

E1, E2, U = 1.0, 3.0, 1e-4  # the two blocks' Young's moduli (Pa) and the end's pull (m)


def bar(second: str = "hex8") -> str:
    """A unit-section bar of two unit cubes along x, "soft" (E1) then "stiff" (E2), sharing
    the face x = 1; symmetry planes x, y, z = 0, the end x = 2 pulled by U. ``second``: the
    stiff part's element type (a wedge pair instead of a cube mixes element types)."""
    nodes = [(x, y, z) for x in (0, 1, 2) for y in (0, 1) for z in (0, 1)]
    text = "".join(f'<node id="{i + 1}">{x},{y},{z}</node>' for i, (x, y, z) in enumerate(nodes))

    def ids(x: int) -> list[int]:  # the face at x, counter-clockwise about +x: (y, z) order
        return [4 * x + 1, 4 * x + 3, 4 * x + 4, 4 * x + 2]

    def hex_cell(x: int) -> str:
        a, b = ids(x), ids(x + 1)  # FEBio's hex8: bottom z = 0 face, then top
        return ",".join(str(n) for n in (a[0], b[0], b[1], a[1], a[3], b[3], b[2], a[2]))

    stiff = f'<Elements type="hex8" name="stiff"><elem id="2">{hex_cell(1)}</elem></Elements>'
    if second == "penta6":
        a, b = ids(1), ids(2)
        stiff = (
            '<Elements type="penta6" name="stiff">'
            f'<elem id="2">{a[0]},{b[0]},{b[1]},{a[3]},{b[3]},{b[2]}</elem>'
            f'<elem id="3">{a[0]},{b[1]},{a[1]},{a[3]},{b[2]},{a[2]}</elem></Elements>'
        )
    law = '<material id="{}" name="{}" type="neo-Hookean"><density>1</density><E>{}</E>' \
          "<v>0</v></material>"  # fmt: skip
    fix = '<bc name="{0}" node_set="{0}" type="zero displacement"><x_dof>{1}</x_dof>' \
          "<y_dof>{2}</y_dof><z_dof>{3}</z_dof></bc>"  # fmt: skip
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control><analysis>STATIC</analysis><time_steps>1</time_steps><step_size>1</step_size>
  </Control>
  <Material>{law.format(1, "soft", E1)}{law.format(2, "stiff", E2)}</Material>
  <Mesh>
    <Nodes name="bar">{text}</Nodes>
    <Elements type="hex8" name="soft"><elem id="1">{hex_cell(0)}</elem></Elements>
    {stiff}
    <NodeSet name="x0">1,2,3,4</NodeSet>
    <NodeSet name="y0">1,2,5,6,9,10</NodeSet>
    <NodeSet name="z0">1,3,5,7,9,11</NodeSet>
    <NodeSet name="x2">9,10,11,12</NodeSet>
  </Mesh>
  <MeshDomains><SolidDomain name="soft" mat="soft"/><SolidDomain name="stiff" mat="stiff"/>
  </MeshDomains>
  <Boundary>{fix.format("x0", 1, 0, 0)}{fix.format("y0", 0, 1, 0)}{fix.format("z0", 0, 0, 1)}
    <bc name="pull" node_set="x2" type="prescribed displacement"><dof>x</dof>
      <value lc="1">{U}</value><relative>0</relative></bc>
  </Boundary>
  <LoadData><load_controller id="1" type="loadcurve"><points><pt>0,0</pt><pt>1,1</pt>
  </points></load_controller></LoadData>
</febio_spec>
"""


def test_parts_of_two_materials_on_shared_nodes_are_one_body_of_two_regions(tmp_path):
    """The converter writes one body with a [[bodies.regions]] table per material (a cell set
    each), and the run is springs in series: the shared face moves by U (1/E1) / (1/E1 +
    1/E2), the stress is the same in both (small strain: within 1e-3)."""
    path = tmp_path / "two.feb"
    path.write_text(bar())
    tables, meshes = febio_scene(read_feb(path), "two")
    ((body,),) = [tables["bodies"]]
    regions = body["regions"]
    assert [r["name"] for r in regions] == ["soft", "stiff"]
    assert [r["material"]["youngs_modulus"] for r in regions] == [E1, E2]
    assert "material" not in body
    (mesh,) = meshes.values()
    np.testing.assert_array_equal(mesh.cell_sets[regions[0]["cells"]], [0])
    np.testing.assert_array_equal(mesh.cell_sets[regions[1]["cells"]], [1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(path)
    sim = scene.simulation
    for _ in range(scene.run["steps"]):
        sim.step()
    b, x, _ = sim.body_state(body["name"])
    u = x.reshape(-1, 3)[:, 0] - b.mesh.points[:, 0]
    shared = np.isclose(b.mesh.points[:, 0], 1.0)
    np.testing.assert_allclose(u[shared], U * (1 / E1) / (1 / E1 + 1 / E2), rtol=1e-3)
    sigma = b.cell_fields(x)["cauchy_stress"][:, 0, 0]
    np.testing.assert_allclose(sigma, U / (1 / E1 + 1 / E2), rtol=2e-3)
    np.testing.assert_array_equal(b.cell_fields(x)["region"], [0, 1])


def test_parts_of_two_element_types_on_shared_nodes_are_refused_in_one_line(tmp_path):
    path = tmp_path / "mixed.feb"
    path.write_text(bar("penta6"))
    with pytest.raises(InputError, match=r"mixed.feb:\d+ <Elements>: parts \['soft', 'stiff'\] "
                       r"share nodes \(or discrete springs\) but mix element types "
                       r"\['hexahedron', 'wedge'\]"):  # fmt: skip
        load_febio(path)


def test_regions_of_parts_whose_names_clash_as_set_names_get_their_own_sets(tmp_path):
    """Parts "b(1)" and "b_1" both read as the name "b_1": the second region's cell set is
    "b_1_.region", so each region keeps its own cells."""
    text = bar()
    for part, new in (("soft", "b(1)"), ("stiff", "b_1")):
        text = text.replace(f'name="{part}"><elem', f'name="{new}"><elem')
        text = text.replace(f'<SolidDomain name="{part}"', f'<SolidDomain name="{new}"')
    path = tmp_path / "clash.feb"
    path.write_text(text)
    tables, meshes = febio_scene(read_feb(path), "clash")
    regions = tables["bodies"][0]["regions"]
    assert [r["cells"] for r in regions] == ["b_1.region", "b_1_.region"]
    (mesh,) = meshes.values()
    assert [mesh.cell_sets[r["cells"]].tolist() for r in regions] == [[0], [1]]
