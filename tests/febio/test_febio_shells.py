"""FEBio's shells (quad4, tri3) read as the solids they are (febio/shells.py): a cantilever
plate of quad4 shells against the beam's closed form, the same plate built with
``solid_shell`` in the API, a tri3 strip in tension against the exact uniaxial stretch, the
back face's geometry (thickness, directors) and the one-line refusals."""

import warnings
from pathlib import Path

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.febio import load_febio, read_feb

MODELS = Path(__file__).parent / "models"
CANTILEVER = MODELS / "shell_cantilever_quad4.feb"
TENSION = MODELS / "shell_tension_tri3.feb"
L, W, H, E = 1.0, 0.2, 0.1, 1000.0  # the models' plate and law (neo-Hookean, v = 0)


def run(path: Path, text: str | None = None, tmp_path: Path | None = None):
    """(model, final positions of its nodes, the scene) of a model, or of ``text`` written
    next to it."""
    if text is not None:
        path = tmp_path / path.name
        path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = read_feb(path)
        scene = load_febio(path)
        sim = scene.simulation
        for _ in range(scene.run["steps"]):
            sim.step()
    assert sim.time == pytest.approx(1.0)
    return model, sim.body_positions("body"), scene


def test_quad4_cantilever_against_the_beam_with_the_locking_factor():
    """Tip deflection of the 80 x 2 plate: the Timoshenko beam P L^3 / (3 E I) + P L / (k G A)
    (0.002012), times the fully integrated bilinear element's shear-locking factor in pure
    bending, 1 / (1 + (1 - v)/2 (a/h)^2) = 0.99225 for a = L / 80, h = 0.1 (one hexahedron
    through the thickness, as FEBio's shell). tissuesim (and FEBio's element) gives 0.99111 of
    the beam: within 0.12 % of the locking-corrected value; 20 elements would give 0.89."""
    model, x, scene = run(CANTILEVER)
    assert scene.simulation.mesh.cell_type == "hexahedron"
    tip = np.isclose(model.nodes[:, 0], L)
    assert tip.sum() == 2 * 3  # the front and the back face's nodes
    deflection = (x - model.nodes)[tip, 2].mean()
    P, I, G = 1e-4, W * H**3 / 12, E / 2
    beam = P * L**3 / (3 * E * I) + P * L / (5 / 6 * G * W * H)
    locking = 1.0 / (1.0 + 0.5 * (L / 80 / H) ** 2)
    assert deflection == pytest.approx(beam * locking, rel=2e-3)
    assert deflection == pytest.approx(beam, rel=1e-2)
    assert not deflection == pytest.approx(beam, rel=5e-3)  # the locking is there


def plate_points():
    nx, ny = 80, 2
    gx, gy = np.meshgrid(np.linspace(0, L, nx + 1), np.linspace(0, W, ny + 1), indexing="xy")
    points = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    idx = np.arange(len(points)).reshape(ny + 1, nx + 1)
    quads = np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], -1)
    return points, quads.reshape(-1, 4)


def test_quad4_plate_equals_the_solid_shell_built_in_the_api():
    """The same plate through the API: solid_shell(reference="top") (FEBio's nodes are the
    shell's top face), clamped, the end load ramped on the top face's tip vertices over the
    same two steps: the same displacement to round-off."""
    model, x, _ = run(CANTILEVER)
    points, quads = plate_points()
    mesh = ts.mesh.solid_shell(points, quads, H, reference="top", normalize=False)
    n = len(points)
    np.testing.assert_allclose(mesh.points[:n], model.nodes[:n], atol=1e-15)
    np.testing.assert_allclose(mesh.points[n:], model.nodes[n:], atol=1e-15)  # same back nodes
    sim = ts.Simulation(
        mesh, ts.NeoHookean(youngs_modulus=E, poisson_ratio=0.0), integrator="quasistatic",
        time_step=0.5,
    )  # fmt: skip
    sim.add_dirichlet(np.flatnonzero(np.isclose(mesh.points[:, 0], 0.0)))
    tip = np.flatnonzero(np.isclose(mesh.points[:n, 0], L))
    sim.add_nodal_forces(tip, lambda t: np.tile([0.0, 0.0, 1e-4 * t / 3], (len(tip), 1)))
    sim.step()
    sim.step()
    np.testing.assert_allclose(mesh.points + sim.displacement, x, rtol=0, atol=1e-12)


def test_tri3_strip_in_tension_is_exact(tmp_path):
    """tri3 shells (wedges) in uniaxial tension, half the force on the back face (shell_bottom):
    with v = 0 FEBio's neo-Hookean stretches as mu (lam - 1/lam) = F / (W h), lam = golden
    ratio for F = 10, and the linear elements hold that state exactly."""
    model, x, scene = run(TENSION)
    assert scene.simulation.mesh.cell_type == "wedge"
    u = x - model.nodes
    end = np.isclose(model.nodes[:, 0], L)
    lam = (1 + 5**0.5) / 2
    np.testing.assert_allclose(u[end, 0], lam - 1, rtol=1e-8)
    np.testing.assert_allclose(u[:, 0], model.nodes[:, 0] * (lam - 1), atol=1e-8)
    np.testing.assert_allclose(u[:, 1:], 0.0, atol=1e-9)
    # all of it on the front face: the strip bends, so shell_bottom reached the back nodes
    text = TENSION.read_text().replace("<shell_bottom>1<", "<shell_bottom>0<")
    model, x, _ = run(TENSION, text, tmp_path)
    assert abs((x - model.nodes)[:, 2]).max() > 1e-3


def test_back_face_geometry_from_the_thickness_and_the_directors(tmp_path):
    """The back nodes sit at X - D: D the mean unit corner normal times the thickness (from
    <ElementData type="shell thickness">), here -0.1 z everywhere; one per shell node."""
    model = read_feb(CANTILEVER)
    n = 81 * 3
    assert model.nodes.shape == (2 * n, 3)
    np.testing.assert_allclose(model.nodes[n:, :2], model.nodes[:n, :2], atol=1e-15)
    np.testing.assert_allclose(model.nodes[n:, 2], -H, atol=1e-15)
    path = tmp_path / "var.feb"  # FEBio 3 names the data var=
    path.write_text(
        CANTILEVER.read_text().replace('type="shell thickness"', 'var="shell thickness"')
    )
    np.testing.assert_array_equal(read_feb(path).nodes, model.nodes)
    cells = model.parts["plate"][1]
    assert model.parts["plate"][0] == "hexahedron" and cells.shape == (160, 8)
    assert (cells[:, :4] >= n).all() and (cells[:, 4:] < n).all()  # back face first
    # a curved strip: the directors follow the surface (a crease of 90 degrees at x = 0.5)
    bent = bent_model(tmp_path / "bent.feb")
    k = np.flatnonzero(np.isclose(bent.nodes[:n, 0], 0.5) & np.isclose(bent.nodes[:n, 2], 0))
    d = bent.nodes[:n][k] - bent.nodes[n:][k]
    np.testing.assert_allclose(d, np.tile([-H / 2, 0, H / 2], (len(k), 1)), atol=1e-12)


def bent_model(path: Path):
    """The cantilever's model with its nodes past x = 0.5 turned up (a crease), read."""
    import re

    def turn(match):
        x, y, z = (float(v) for v in match.group(2).split(","))
        if x > 0.5:
            x, z = 0.5, x - 0.5
        return f'<node id="{match.group(1)}">{x!r},{y!r},{z!r}</node>'

    path.write_text(re.sub(r'<node id="(\d+)">([^<]+)</node>', turn, CANTILEVER.read_text()))
    return read_feb(path)


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ('<Elements type="quad4"', '<Elements type="quad9"', r":\d+ <Elements>: element type "
         r"'quad9' is not supported by tissuesim; .*shells quad4, tri3, quad8 .*quadratic "
         r"shells quad9"),
        ('<ShellDomain name="plate" mat="plate">',
         '<ShellDomain name="plate" mat="plate" type="elastic-shell-eas">',
         r"<ShellDomain>: shell domain type 'elastic-shell-eas' is not supported"),
        ('<bc name="clamp" node_set="clamped" type="zero displacement">',
         '<bc name="clamp" node_set="clamped" type="zero shell displacement">',
         r"<x_dof>: this parameter of <bc> is not supported"),
        ("<shell_thickness>0</shell_thickness>",
         "<shell_thickness>0</shell_thickness><shell_normal_nodal>0</shell_normal_nodal>",
         r"<shell_normal_nodal>: shell_normal_nodal = 0"),
        ('<elem id="1">1, 2, 83, 82</elem>', '<elem id="1">1, 2, 2, 82</elem>',
         r"<ElementData>: shell face 0 has a corner of zero area"),
    ],
)  # fmt: skip
def test_refused_in_one_line_naming_the_element_and_its_line(old, new, match, tmp_path):
    text = CANTILEVER.read_text()
    assert old in text
    path = tmp_path / "shell.feb"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(InputError, match=match) as info:
        load_febio(path)
    assert "\n" not in str(info.value) and "shell.feb:" in str(info.value)


def test_a_shell_without_thickness_is_refused(tmp_path):
    text = CANTILEVER.read_text()
    start, end = text.index("  <MeshData>"), text.index("  </MeshData>") + len("  </MeshData>\n")
    path = tmp_path / "thin.feb"
    path.write_text(text[:start] + text[end:])
    with pytest.raises(InputError, match=r"<ShellDomain>: shell part 'plate' has no thickness"):
        load_febio(path)


def with_block(material: str) -> str:
    """The cantilever with a hex8 block under its first element (nodes 1, 2, 83, 82), of a
    second material: a neo-Hookean or a rigid body."""
    text = CANTILEVER.read_text()
    below = [(0.0, 0.0), (0.0125, 0.0), (0.0125, 0.1), (0.0, 0.1)]
    nodes = "".join(f'<node id="{301 + k}">{x},{y},-0.5</node>' for k, (x, y) in enumerate(below))
    text = text.replace("    </Nodes>", f"{nodes}\n    </Nodes>")
    block = '<Elements type="hex8" name="block"><elem id="1000">301,302,303,304,1,2,83,82</elem>'
    text = text.replace("    <NodeSet", f"    {block}</Elements>\n    <NodeSet", 1)
    law = "<E>1</E><v>0</v>" if material == "rigid body" else "<E>10</E><v>0.3</v>"
    text = text.replace(
        "  </Material>", f'<material id="2" name="block" type="{material}">{law}</material>\n'
        "  </Material>",
    )  # fmt: skip
    return text.replace(
        "  </MeshDomains>", '<SolidDomain name="block" mat="block"/>\n  </MeshDomains>'
    )


def test_a_shell_on_a_rigid_part_is_clamped_to_it_and_on_a_solid_attached(tmp_path):
    """FEBio clamps a deformable shell node's back face to the rigid body the node joins
    (RIGID_CLAMP): the back nodes of the shared nodes become a rigid node set; a deformable
    solid behind the shell takes its back nodes (FEBio's shell-solid interface,
    test_febio_shells_solids.py), refused when its material is another."""
    path = tmp_path / "on_rigid.feb"
    path.write_text(with_block("rigid body"))
    model = read_feb(path)
    ((set_name, body, _),) = model.rigid_nodes
    assert body == "block"
    shells = model._shells
    np.testing.assert_array_equal(
        np.sort(model.node_sets[set_name]), sorted(shells.back[i] for i in (0, 1, 81, 82))
    )
    path.write_text(with_block("neo-Hookean"))
    model = read_feb(path)  # the block behind the shell takes its back face
    np.testing.assert_array_equal(
        model.parts["block"][1][0, 4:], [shells.back[i] for i in (0, 1, 82, 81)]
    )
    with warnings.catch_warnings():  # one body: the plate and the block its two regions
        warnings.simplefilter("ignore")
        body = load_febio(path).simulation.body("plate")
    assert [p.name for p in body.model.parts] == ["plate", "block"]


def test_three_field_shell_augmentation_off_is_read_and_on_refused(tmp_path):
    """FE3FieldElasticShellDomain's laugon = 0 (its default) reads, its atol / minaug / maxaug
    then unused notes; laugon = 1 (the augmented dilatation) is refused in one line."""
    text = CANTILEVER.read_text().replace(
        '<ShellDomain name="plate" mat="plate">',
        '<ShellDomain name="plate" mat="plate" type="three-field-shell"><laugon>0</laugon>'
        "<atol>0.01</atol><minaug>0</minaug><maxaug>0</maxaug>",
    )
    path = tmp_path / "augmented.feb"
    path.write_text(text)
    model = read_feb(path)
    assert model.domains["plate"][1] == "mean_dilatation"
    assert sum("augmentation, off" in n for n in model.notes) == 3
    path.write_text(text.replace("<laugon>0</laugon>", "<laugon>1</laugon>"))
    with pytest.raises(InputError, match=r"augmented.feb:\d+ <laugon>: laugon = 1"):
        read_feb(path)


def test_secant_options_read_as_febio_defaults(tmp_path):
    """secant_stress 0 and secant_tangent (FEBio's Newton tangent only) read; secant_stress 1
    is refused in one line."""
    text = CANTILEVER.read_text().replace(
        '<ShellDomain name="plate" mat="plate">',
        '<ShellDomain name="plate" mat="plate"><secant_stress>0</secant_stress>'
        "<secant_tangent>1</secant_tangent>",
    )
    path = tmp_path / "secant.feb"
    path.write_text(text)
    assert any("Newton tangent" in n for n in read_feb(path).notes)
    path.write_text(text.replace("<secant_stress>0<", "<secant_stress>1<"))
    with pytest.raises(InputError, match=r"secant.feb:\d+ <secant_stress>: secant_stress = 1"):
        read_feb(path)


def test_a_shell_condition_on_a_surface_holds_the_back_nodes_of_its_facets(tmp_path):
    """A "zero shell displacement" on "@surface:name" holds the back nodes of every node of
    the surface's facets, as on a node set of those nodes (it had been dropped without a
    word: FEBio's sh61 buckled where FEBio's plate stays flat). The cantilever's back face
    held on its first column of cells: the same positions as with the node set, stiffer at
    the tip than with the clamped edge alone."""
    text = CANTILEVER.read_text()
    column = '<quad4 id="1">1,2,83,82</quad4><quad4 id="2">82,83,164,163</quad4>'
    mesh = (
        f'    <Surface name="root">{column}</Surface>\n'
        '    <NodeSet name="root_nodes">1, 2, 82, 83, 163, 164</NodeSet>\n  </Mesh>'
    )
    text = text.replace("  </Mesh>", mesh)
    back = '<bc name="clamp_back" node_set="clamped" type="zero shell displacement">'
    assert back in text
    tips = {}
    for name, held in (("edge", "clamped"), ("set", "root_nodes"), ("surface", "@surface:root")):
        path = tmp_path / f"{name}.feb"
        model, x, _ = run(path, text.replace(back, back.replace('"clamped"', f'"{held}"')),
                          tmp_path)  # fmt: skip
        tips[name] = x
        if name == "surface":
            back_rows = model.node_sets["@surface:root.back"]
            assert len(back_rows) == 6
            np.testing.assert_allclose(x[back_rows], model.nodes[back_rows], atol=1e-15)
    np.testing.assert_array_equal(tips["surface"], tips["set"])
    tip = np.isclose(model.nodes[:, 0], L)
    assert (tips["surface"] - model.nodes)[tip, 2].mean() < 0.999 * (tips["edge"] - model.nodes)[
        tip, 2
    ].mean()


def test_a_condition_the_converter_places_in_no_body_is_an_error(monkeypatch):
    """A displacement condition on nodes of a body that no body's mesh took is an error, never
    dropped: the converter's guard, with its set's name lost on purpose."""
    from tissuesim.febio import scene as febio_scene_module

    model = read_feb(CANTILEVER)
    real, asked = febio_scene_module._node_set_name, []

    def losing(m, name):  # the point set is written as "tip", then looked for as "lost"
        asked.append(name)
        return "lost" if name == "tip" and asked.count("tip") > 1 else real(m, name)

    monkeypatch.setattr(febio_scene_module, "_node_set_name", losing)
    with pytest.raises(
        InputError, match=r"placed the nodal condition on node set 'tip' in no body"
    ):
        febio_scene_module.febio_scene(model, "cantilever")
