"""FEBio models (tests/febio/models): each runs, matches the scene it converts to bit for bit,
and the closed forms; every refusal is one line naming the XML element and its line."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from tissuesim.cli import main
from tissuesim.febio import FebError, convert_febio, febio_scene, load_febio, read_feb
from tissuesim.febio.curves import curve_expression
from tissuesim.febio.model import Curve
from tissuesim.scene.expressions import compile_expression
from tissuesim.scene.loader import load_scene

MODELS = Path(__file__).parent / "models"
ALL = sorted(p.stem for p in MODELS.glob("*.feb"))


def _run(scene, steps: int) -> np.ndarray:
    sim = scene.simulation
    for _ in range(steps):
        sim.step()
        if sim.finished:  # an adaptive model's [run] steps is an upper bound
            break
    return np.concatenate([sim.body_positions(name) for name in sim.bodies])


@pytest.fixture
def one_contact_thread(monkeypatch):
    """ipctk on one thread (TISSUESIM_CONTACT_THREADS=1): its parallel sums differ in the
    last bit from run to run, so contact runs compare bit for bit only on one thread."""
    import ipctk

    before = ipctk.get_num_threads()
    monkeypatch.setenv("TISSUESIM_CONTACT_THREADS", "1")
    yield
    ipctk.set_num_threads(before)


@pytest.mark.parametrize("name", ALL)
def test_model_matches_its_converted_scene(name, tmp_path, one_contact_thread):
    feb = MODELS / f"{name}.feb"
    written = convert_febio(feb, tmp_path / f"{name}.toml")
    assert all(p.exists() for p in written)
    steps = load_scene(written[0]).run["steps"]
    with pytest.warns(UserWarning) if read_feb(feb).notes else _nothing():
        direct = _run(load_febio(feb), steps)
    converted = _run(load_scene(written[0]), steps)
    assert np.array_equal(direct, converted)
    assert np.all(np.isfinite(direct))


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_uniaxial_neo_hookean_reaction_matches_the_closed_form():
    """FEBio's neo-Hookean, P = mu (F - F^-T) + lambda ln J F^-T, F = diag(l, t, t) with the
    lateral faces free (P_yy = 0): the pull on the unit face is P_xx."""
    scene = load_febio(MODELS / "uniaxial_neo_hookean.feb")
    sim = scene.simulation
    for _ in range(4):
        record = sim.step()
    E, nu, stretch = 1e4, 0.3, 1.2
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))

    def lateral(t):
        return mu * (t - 1 / t) + lam * np.log(stretch * t * t) / t

    t = brentq(lateral, 0.5, 1.0)
    P_xx = mu * (stretch - 1 / stretch) + lam * np.log(stretch * t * t) / stretch
    force = np.asarray(record.extra["forces"]["pull"])
    assert abs(abs(force[0]) - P_xx) < 1e-6 * P_xx
    x = sim.positions
    X = sim.body("body").mesh.points
    assert np.allclose(x[:, 1], t * X[:, 1], atol=1e-9)


def test_mooney_rivlin_block_under_a_dead_pressure():
    """The block is homogeneously compressed: its law's nominal stress is -p on the top face
    and zero on the free sides (FEBio's Mooney-Rivlin, dead pressure)."""
    scene = load_febio(MODELS / "mooney_rivlin_pressure.feb")
    x = _run(scene, 5)
    X = scene.simulation.body("body").mesh.points
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    F = np.diag(stretch)[None]
    P = scene.simulation.body("body").model.material.evaluate(F, 1).stress
    assert stretch[2] < 1.0
    assert np.allclose(np.diag(P[0]), [0.0, 0.0, -500.0], atol=1e-5 * 500)


def test_load_curves_follow_febio():
    """LINEAR, STEP (the next point's value), SMOOTH (quadratics), SMOOTH STEP, extend."""
    pts = np.array([[0.0, 0.0], [0.5, 2.0], [1.0, 1.0], [2.0, 3.0]])

    def value(curve, t):
        f = compile_expression(curve_expression(curve), "curve")
        return float(f(np.zeros((1, 3)), t)[0])

    linear = Curve(pts, "LINEAR", "CONSTANT")
    assert value(linear, 0.25) == pytest.approx(1.0)
    assert value(linear, 5.0) == pytest.approx(3.0)
    assert value(Curve(pts, "LINEAR", "EXTRAPOLATE"), 3.0) == pytest.approx(5.0)
    step = Curve(pts, "STEP", "CONSTANT")
    assert [value(step, t) for t in (0.0, 0.2, 0.5, 0.7, 2.0, 9.0)] == [0, 2, 1, 1, 3, 3]
    smooth = Curve(pts[:3], "SMOOTH", "CONSTANT")  # three points: one quadratic
    assert value(smooth, 0.25) == pytest.approx(np.polyval(np.polyfit(*pts[:3].T, 2), 0.25))
    w = 0.3
    assert value(Curve(pts, "SMOOTH STEP", "CONSTANT"), 0.15) == pytest.approx(
        2.0 * w**3 * (10 - 15 * w + 6 * w**2)
    )


def test_cli_runs_a_feb_and_converts_it(tmp_path, capsys):
    feb = MODELS / "uniaxial_neo_hookean.feb"
    out = tmp_path / "out"
    assert main(["run", str(feb), "--out", str(out), "--no-render", "--quiet"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["steps"] == 4 and "pull" in report["forces"]
    scene = tmp_path / "scene.toml"
    assert main(["convert", str(feb), str(scene)]) == 0
    assert (tmp_path / "scene.msh").exists()
    capsys.readouterr()
    assert main(["convert", str(feb), str(scene)]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["convert", str(feb), str(scene), "--force"]) == 0


REFUSALS = {
    "pyra5": ('<Elements type="pyra5" name="p">', "element type 'pyra5'"),
    "material": ('<material id="1" name="m" type="biphasic">', "material type 'biphasic'"),
    "contact": (
        '<contact type="contact potential" surface_pair="p">',
        "contact type 'contact potential'",
    ),
    "element": ("<MeshAdaptor>", "<MeshAdaptor>: this section is not supported"),
    "follower": ("<linear>0</linear>", "traction on the deformed surface"),
    "bc": (
        '<bc type="normal displacement" node_set="x0">',
        "boundary condition type 'normal displacement'",
    ),
}


@pytest.mark.parametrize("case", sorted(REFUSALS))
def test_refusals_are_one_line_naming_the_element_and_its_line(case, tmp_path):
    opening, message = REFUSALS[case]
    text = (MODELS / "mooney_rivlin_pressure.feb").read_text()
    if case == "pyra5":
        text = text.replace('<Elements type="tet4" name="cube">', opening)
    elif case == "material":
        text = text.replace('<material id="1" name="liver" type="Mooney-Rivlin">', opening)
    elif case == "contact":
        text = text.replace(
            "  <LoadData>", f"  <Contact>\n    {opening}</contact>\n  </Contact>\n  <LoadData>"
        )
    elif case == "element":
        text = text.replace("  <LoadData>", "  <MeshAdaptor/>\n  <LoadData>")
    elif case == "follower":  # a follower traction (a follower pressure runs)
        text = text.replace('type="pressure"', 'type="traction"').replace(
            '<pressure lc="1">500</pressure>', '<traction lc="1">0,0,-500</traction>'
        )
        text = text.replace("<symmetric_stiffness>1</symmetric_stiffness>", "")
        text = text.replace("<linear>1</linear>", opening)
    else:
        text = text.replace('<bc type="fix" node_set="x0">', opening)
    feb = tmp_path / "bad.feb"
    feb.write_text(text)
    tag = re.search(r"<(\w+)", opening).group(1)
    line = next(
        i
        for i, s in enumerate(text.splitlines(), 1)
        if f"<{tag}" in s and (tag != "linear" or "<linear>0" in s)
    )
    with pytest.raises(FebError) as info:
        read_feb(feb)
    said = str(info.value)
    assert "\n" not in said and message in said
    assert f"bad.feb:{line} <{tag}>" in said


def test_viscoelastic_relaxation_follows_febios_prony_series():
    """A unit cube (E = 1000, v = 0: no lateral strain) stretched to 1.2 in the first step and
    held: FEBio's S = g0 Se + sum g_i H_i with H_i = e_i H_i + gamma_i (Se - Se_prev) gives
    the pull lambda mu (1 - lambda^-2) (g0 + sum g_i gamma_i e_i^(n-1)) after step n."""
    scene = load_febio(MODELS / "viscoelastic_relaxation.feb")
    sim = scene.simulation
    stretch, mu, h = 1.2, 500.0, 0.1
    g, tau = np.array([0.5, 0.25]), np.array([0.2, 1.5])
    e = np.exp(-h / tau)
    gamma = (1 - e) / (h / tau)
    for n in range(1, 6):
        force = abs(sim.step().extra["forces"]["pull"][0])
        expected = stretch * mu * (1 - stretch**-2) * (1.0 + np.sum(g * gamma * e ** (n - 1)))
        assert force == pytest.approx(expected, rel=1e-6)
    assert np.allclose(sim.positions[:, 1:], sim.body("body").mesh.points[:, 1:], atol=1e-9)


def test_hgo_uniaxial_stretch_is_the_laws_homogeneous_state():
    """Holzapfel-Gasser-Ogden with mat_axis a = x, d = y, gamma = 30: the cube stretched 1.15
    along x deforms homogeneously with the law's lateral stresses zero (y and z contract
    differently: the fibres lie in the x-y plane) and the pull equal to P_xx."""
    from tissuesim.materials import HolzapfelGasserOgden

    scene = load_febio(MODELS / "hgo_uniaxial.feb")
    x = _run(scene, 3)
    sim = scene.simulation
    X = sim.body("body").mesh.points
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    law = HolzapfelGasserOgden(c=7640.0, k1=99660.0, k2=5.246, kappa=0.226, gamma=30.0, k=1e6)
    P = law.evaluate(np.diag(stretch)[None], 1).stress[0]
    force = abs(sim.step().extra["forces"]["pull"][0])  # held: the same state again
    assert stretch[0] == pytest.approx(1.15)
    assert abs(stretch[1] - stretch[2]) > 1e-3
    assert np.allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)
    matrix_only = HolzapfelGasserOgden(c=7640.0, k1=0.0, k2=5.246, kappa=0.226, k=1e6)
    assert P[0, 0] > 1.5 * matrix_only.evaluate(np.diag(stretch)[None], 1).stress[0, 0, 0]


def test_fibre_directions_from_mat_axis_fiber_and_element_data():
    """trans iso Mooney-Rivlin's fiber (0,1,0) in the local axes of mat_axis type="local"
    (nodes 1, 2, 4 of each element: e1 along n1 -> n2, e2 towards n4), replaced on two
    elements by ElementData var="fiber"; the uncoupled viscoelastic wrapper's k adds to the
    law's k (FEBio sums them)."""
    model = read_feb(MODELS / "trans_iso_mesh_data.feb")
    data, _ = febio_scene(model, "x")
    elastic = data["material"]["elastic"]
    assert data["material"]["model"] == "uncoupled_viscoelastic"
    assert elastic["k"] == 50000.0
    points = model.nodes
    cells = model.parts["cube"][1]
    fibres = np.array(elastic["fiber"])
    for row, cell in enumerate(cells):
        a = points[cell[1]] - points[cell[0]]
        d = points[cell[3]] - points[cell[0]]
        e3 = np.cross(a, d)
        e2 = np.cross(e3, a)
        expected = e2 / np.linalg.norm(e2)
        if row == 1:
            expected = np.array([0.0, 0.0, 1.0])
        elif row == 4:
            expected = np.array([0.0, 1.0, 1.0])
        np.testing.assert_allclose(fibres[row], expected, atol=1e-12)


def test_sliding_contact_and_rigid_wall_carry_the_load():
    """Three laterally held cubes: 'upper' pressed onto 'lower' (sliding-elastic, its base
    fixed in z) and 'puck' pressed onto a rigid_wall. The reactions balance through the
    contact (the base carries the press, the wall the puck: 1e-6), and each cube is nearly in
    uniaxial strain, its pull the law's P_zz at its mean stretch (1%: both contacts are
    penalties, FEBio's, whose penetration shortens the cubes a little)."""
    from tissuesim.materials import NeoHookean

    scene = load_febio(MODELS / "contact_stack.feb")
    sim = scene.simulation
    sim.step()
    forces = sim.step().extra["forces"]
    law = NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3)
    for body, press, support in (("upper", "press", "base"), ("puck", "press_puck", "wall2")):
        z = sim.body_positions(body)[:, 2]
        Z = sim.body(body).mesh.points[:, 2]
        top = Z > Z.mean()
        stretch = (z[top].mean() - z[~top].mean()) / (Z[top].mean() - Z[~top].mean())
        P = law.evaluate(np.diag([1.0, 1.0, stretch])[None], 1).stress[0, 2, 2]
        assert stretch < 0.97
        assert forces[press][2] == pytest.approx(P, rel=1e-2)
        assert forces[support][2] == pytest.approx(-forces[press][2], rel=1e-6)
    assert forces["contact1"][2] == pytest.approx(forces["base"][2], rel=1e-6)


NEW_REFUSALS = {
    "map": ("hgo_uniaxial", '<mat_axis type="vector">', '<mat_axis type="cylindrical">',
            "mat_axis type 'cylindrical'"),
    "data": ("trans_iso_mesh_data", '<ElementData var="fiber"',
             '<ElementData var="shell thickness"', "element data 'shell thickness'"),
    "three_field": ("viscoelastic_relaxation", 'mat="tissue"/>',
                    'mat="tissue" type="three-field-solid"/>', "three-field element"),
    "hgo_fiber": ("hgo_uniaxial", '<mat_axis type="vector">',
                  '<fiber type="vector">1,0,0</fiber>\n      <mat_axis type="vector">',
                  "takes its fibres from <mat_axis>"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(NEW_REFUSALS))
def test_fibre_and_viscoelastic_refusals_name_the_element_and_line(case, tmp_path):
    name, old, new, message = NEW_REFUSALS[case]
    text = (MODELS / f"{name}.feb").read_text()
    assert old in text
    text = text.replace(old, new)
    feb = tmp_path / "bad.feb"
    feb.write_text(text)
    tag = "SolidDomain" if case == "three_field" else re.search(r"<(\w+)", new).group(1)
    line = next(i for i, s in enumerate(text.splitlines(), 1) if new.splitlines()[0] in s)
    if tag == "SolidDomain":
        with pytest.raises(FebError) as info:
            febio_scene(read_feb(feb), "x")
    else:
        with pytest.raises(FebError) as info:
            read_feb(feb)
    said = str(info.value)
    assert "\n" not in said and message in said
    assert f"bad.feb:{line} <{tag}>" in said


def test_a_pressure_on_the_deformed_closed_surface_is_a_follower_pressure(tmp_path):
    """FEBio's default pressure (<linear>0</linear>) on the cube's whole boundary, a closed
    surface: it runs as a follower pressure, so at the end the Cauchy stress is -p I (a dead
    pressure on the reference faces would leave -p J^(-1/3) I); the converted scene says
    [[pressure]]."""
    from tissuesim.mesh.queries.boundary import boundary_facets

    text = (MODELS / "mooney_rivlin_pressure.feb").read_text()
    cells = np.array([[1, 2, 4, 8], [1, 4, 3, 8], [1, 3, 7, 8], [1, 7, 5, 8], [1, 5, 6, 8],
                      [1, 6, 2, 8]]) - 1  # fmt: skip
    points = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=float)
    facets = boundary_facets(cells)
    signed = np.einsum(
        "ki,ki->k",
        np.cross(
            points[facets[:, 1]] - points[facets[:, 0]], points[facets[:, 2]] - points[facets[:, 0]]
        ),
        points[facets].mean(axis=1) - 0.5,
    )
    assert np.all(signed > 0)  # outward, as FEBio's surfaces are
    rows = "\n".join(
        f'      <tri3 id="{k + 1}">{",".join(str(int(v) + 1) for v in f)}</tri3>'
        for k, f in enumerate(facets)
    )
    start, end = text.index('    <Surface name="top">'), text.index("    </Surface>")
    text = text[:start] + f'    <Surface name="top">\n{rows}\n' + text[end:]
    text = text.replace("<linear>1</linear>", "<linear>0</linear>")
    feb = tmp_path / "closed.feb"
    feb.write_text(text)
    with pytest.warns(UserWarning, match="symmetric_stiffness"):
        scene = load_febio(feb)
    x = _run(scene, 5)
    X = scene.simulation.body("body").mesh.points
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    F = np.diag(stretch)
    P = scene.simulation.body("body").model.material.evaluate(F[None], 1).stress[0]
    cauchy = P @ F.T / np.linalg.det(F)
    assert stretch.max() < 1.0
    assert np.allclose(cauchy, -500.0 * np.eye(3), atol=1e-5 * 500)
    written = convert_febio(feb, tmp_path / "closed.toml")
    assert "[[pressure]]" in written[0].read_text()


def test_an_uncoupled_viscoelastic_law_on_hex8_runs_febios_three_field_element(tmp_path):
    """FEBio runs an `uncoupled viscoelastic` law on hex8 with its three-field element (the
    usual ligament and tendon model); tissuesim runs it on the mean-dilatation form (the Prony
    series on the deviatoric part, the bulk term on the element's mean dilatation). Under the
    cube's homogeneous stretch and relaxation the mean dilatation is the point's, so the pull
    equals the displacement form's (the SolidDomain given as elastic-solid) step by step."""
    text = (MODELS / "viscoelastic_relaxation.feb").read_text()
    old_elastic = '<elastic type="neo-Hookean">\n        <E>1000</E>\n        <v>0</v>'
    assert old_elastic in text and 'type="viscoelastic"' in text
    text = text.replace('type="viscoelastic"', 'type="uncoupled viscoelastic"').replace(
        old_elastic,
        '<elastic type="Mooney-Rivlin">\n        <c1>200</c1>\n        <c2>50</c2>\n'
        "        <k>5000</k>",
    )
    pulls = {}
    for domain in ('mat="tissue"/>', 'mat="tissue" type="elastic-solid"/>'):
        feb = tmp_path / "uncoupled.feb"
        feb.write_text(text.replace('mat="tissue"/>', domain))
        scene = load_febio(feb)
        (body,) = scene.simulation.bodies.values()
        records = [scene.simulation.step() for _ in range(5)]
        pulls[body.model.formulation] = [r.extra["forces"]["pull"][0] for r in records]
    assert set(pulls) == {"mean_dilatation", "displacement"}
    md, disp = np.array(pulls["mean_dilatation"]), np.array(pulls["displacement"])
    assert md[0] > 0 and md[-1] < 0.9 * md[0]  # pulled, then relaxing
    np.testing.assert_allclose(md, disp, rtol=1e-9)


def test_the_uncoupled_wrappers_k_and_default_pressure_model_hold_its_laws_bulk(tmp_path):
    """FEBio's ma07 / ma16 give the uncoupled viscoelastic wrapper k and pressure_model
    "default" and its law k = 0: read as the law with that k (the same pulls as the law given
    the k itself); another pressure_model on the wrapper is refused in one line."""
    text = (MODELS / "viscoelastic_relaxation.feb").read_text()
    old_elastic = '<elastic type="neo-Hookean">\n        <E>1000</E>\n        <v>0</v>'
    text = text.replace('type="viscoelastic"', 'type="uncoupled viscoelastic"')
    own = text.replace(old_elastic, '<elastic type="Mooney-Rivlin">\n        <c1>200</c1>\n'
                       "        <c2>50</c2>\n        <k>5000</k>")  # fmt: skip
    wrapped = text.replace(
        "      <density>1000</density>",
        "      <density>1000</density>\n      <k>5000</k>\n"
        "      <pressure_model>default</pressure_model>",
    ).replace(old_elastic, '<elastic type="Mooney-Rivlin">\n        <c1>200</c1>\n'
              "        <c2>50</c2>\n        <k>0</k>")  # fmt: skip
    pulls = []
    for version in (own, wrapped):
        feb = tmp_path / "v.feb"
        feb.write_text(version)
        sim = load_febio(feb).simulation
        pulls.append([sim.step().extra["forces"]["pull"][0] for _ in range(3)])
    assert pulls[0] == pulls[1] and pulls[0][0] > 0
    feb.write_text(wrapped.replace(">default<", ">1<"))
    with pytest.raises(FebError, match="pressure_model '1' on the 'uncoupled viscoelastic'"):
        read_feb(feb)


@pytest.mark.parametrize("extend", ["REPEAT", "REPEAT_OFFSET"])
@pytest.mark.parametrize("interpolate", ["LINEAR", "SMOOTH"])
def test_repeating_curves_follow_febios_point_curve(extend, interpolate):
    """extend REPEAT / REPEAT_OFFSET as FEBio's PointCurve::value: t shifted by whole periods
    (a loop, as FEBio's) into the curve's range, the offset adding (fN - f0) per period."""
    from tissuesim.febio.curves import curve_expression
    from tissuesim.febio.model import Curve
    from tissuesim.scene.expressions import compile_expression

    points = np.array([[0.5, 0.0], [1.0, 1.0], [1.5, 0.25], [2.5, 0.5]])
    inside = compile_expression(curve_expression(Curve(points, interpolate)), "inside")
    repeating = compile_expression(curve_expression(Curve(points, interpolate, extend)), "x")
    origin = np.zeros((1, 3))
    period, jump = 2.0, 0.5
    for t in np.linspace(-3.0, 9.0, 97):
        tau, n = t, 0
        while tau < 0.5:
            tau, n = tau + period, n - 1
        while tau > 2.5:
            tau, n = tau - period, n + 1
        expected = inside(origin, tau)[0] + (n * jump if extend == "REPEAT_OFFSET" else 0.0)
        assert repeating(origin, t)[0] == pytest.approx(expected, abs=1e-12), t
