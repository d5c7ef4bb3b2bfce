"""FEBio's optimisation files (``<febio_optimize>``, febio/optimize/): read as FEBio reads them,
each objective's Jacobian from the run's sensitivities against central differences of whole
runs, a fit to data of our own model recovers its parameters with the converged objective 0,
the command line writes its report, and bad input is refused in one line."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from tissuesim.errors import InputError
from tissuesim.febio.optimize import read_optimize, run_optimize
from tissuesim.febio.optimize.model import ModelBuilder
from tissuesim.febio.optimize.run import _Objective
from tissuesim.identification.observations import EnclosedVolume
from tissuesim.scene.expressions import compile_named


def _model(path: Path, E: float = 1.0, v: float = 0.3) -> Path:
    """A 2 x 1 x 1 hex8 bar (2 x 1 x 1), neo-Hookean, its x = 0 face held by symmetry
    conditions, its x = 2 face pulled by a pressure of -0.2 ramped over 4 static steps."""
    nodes, nid = [], {}
    for k in range(2):
        for j in range(2):
            for i in range(3):
                nid[i, j, k] = len(nodes) + 1
                nodes.append(f'<node id="{len(nodes) + 1}">{i},{j},{k}</node>')
    elems = "".join(
        f'<elem id="{i + 1}">' + ",".join(str(nid[c]) for c in (
            (i, 0, 0), (i + 1, 0, 0), (i + 1, 1, 0), (i, 1, 0),
            (i, 0, 1), (i + 1, 0, 1), (i + 1, 1, 1), (i, 1, 1))) + "</elem>"
        for i in range(2)
    )  # fmt: skip
    end = nid[2, 0, 0], nid[2, 1, 0], nid[2, 1, 1], nid[2, 0, 1]
    x0 = ",".join(str(nid[0, j, k]) for j in range(2) for k in range(2))
    y0 = ",".join(str(nid[i, 0, k]) for i in range(3) for k in range(2))
    z0 = ",".join(str(nid[i, j, 0]) for i in range(3) for j in range(2))
    path.write_text(f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control><analysis>STATIC</analysis><time_steps>4</time_steps><step_size>0.25</step_size>
  </Control>
  <Material><material id="1" name="tissue" type="neo-Hookean">
    <density>1</density><E>{E}</E><v>{v}</v></material></Material>
  <Mesh><Nodes name="n">{"".join(nodes)}</Nodes>
    <Elements type="hex8" name="bar">{elems}</Elements>
    <NodeSet name="x0">{x0}</NodeSet><NodeSet name="y0">{y0}</NodeSet>
    <NodeSet name="z0">{z0}</NodeSet>
    <Surface name="end"><quad4 id="1">{",".join(map(str, end))}</quad4></Surface></Mesh>
  <MeshDomains><SolidDomain name="bar" mat="tissue"/></MeshDomains>
  <Boundary>
    <bc name="sx" node_set="x0" type="zero displacement"><x_dof>1</x_dof></bc>
    <bc name="sy" node_set="y0" type="zero displacement"><y_dof>1</y_dof></bc>
    <bc name="sz" node_set="z0" type="zero displacement"><z_dof>1</z_dof></bc></Boundary>
  <Loads><surface_load name="pull" surface="end" type="pressure">
    <pressure lc="1">-0.2</pressure></surface_load></Loads>
  <LoadData><load_controller id="1" type="loadcurve"><interpolate>LINEAR</interpolate>
    <points><pt>0,0</pt><pt>1,1</pt></points></load_controller></LoadData>
</febio_spec>
""")
    return path


def _optimisation(path: Path, objective: str, params: str, method: str = "levmar",
                  tol: float = 1e-6) -> Path:  # fmt: skip
    path.write_text(f"""<?xml version="1.0"?>
<febio_optimize version="2.0">
  <Options type="{method}"><obj_tol>{tol}</obj_tol><f_diff_scale>0.001</f_diff_scale>
    <print_level>PRINT_ITERATIONS</print_level></Options>
  <Parameters>{params}</Parameters>
  {objective}
</febio_optimize>
""")
    return path


TWO = ("<param name=\"fem.material('tissue').E\">1.5, 0.5, 5</param>"
       '<param name="fem.material[0].v">0.25, 0, 0.45</param>')  # fmt: skip
OBJECTIVES = {
    "data-fit against time": """<Objective type="data-fit"><fnc type="parameter">
        <param name="fem.element_data('sx', 2)"/></fnc>
        <data><point>0.1, 0.05</point><point>0.6, 0.1</point><point>1, 0.2</point></data>
        </Objective>""",
    "data-fit against a strain": """<Objective type="data-fit"><fnc type="parameter">
        <ordinate name="fem.element_data('Ex', 1)"/><param name="fem.element_data('sx', 1)"/>
        </fnc><data><point>0.01, 0.05</point><point>0.05, 0.1</point></data></Objective>""",
    "filter_sum of an expression": """<Objective type="data-fit"><fnc type="filter_sum">
        <element_data data="=sx+sy+2*sz" elem_set="bar"/></fnc>
        <data><pt>0.5, 0.2</pt><pt>1.0, 0.4</pt></data></Objective>""",
    "a surface's volume": """<Objective type="data-fit"><fnc type="parameter">
        <param name="fem.surface_data('volume', 'end')"/></fnc>
        <data><pt>0.5, 0.7</pt><pt>1.0, 0.8</pt></data></Objective>""",
    "target": """<Objective type="target">
        <var name="fem.mesh.node.fromId(3).position.x">2.2</var>
        <var name="fem.mesh.node[11].position.y">0.95</var></Objective>""",
    "node-data": """<Objective type="node-data"><var type="ux;uy"/><data>
        <node id="6">0.1, -0.02</node><node id="12">0.1, -0.02</node></data></Objective>""",
    "element-data": """<Objective type="element-data"><var type="sx"/><data>
        <elem id="1">0.2</elem><elem id="2">0.2</elem></data></Objective>""",
}


@pytest.mark.parametrize("kind", list(OBJECTIVES))
def test_each_objectives_jacobian_is_the_whole_runs_central_difference(tmp_path, kind):
    model = _model(tmp_path / "bar.feb")
    task = read_optimize(_optimisation(tmp_path / "opt.feb", OBJECTIVES[kind], TWO))
    builder = ModelBuilder(model, task)
    try:
        objective = _Objective(task, builder, "sensitivities")
        a = np.array([1.5, 0.25])
        r, J = objective(a)
        y = r + (task.data[:, 1] if task.data is not None else [v for _, v in task.targets])
        for i in range(2):
            h = 1e-5 * a[i]
            up = objective._residuals(a + h * np.eye(2)[i], False)[0]
            down = objective._residuals(a - h * np.eye(2)[i], False)[0]
            fd = (up - down) / (2 * h)
            # the derivative's own scale: the values over the parameter (a stress that does
            # not depend on E, as the pulled bar's, is then checked to be ~0)
            scale = max(np.abs(fd).max(), np.abs(y).max() / a[i])
            assert np.abs(J[:, i] - fd).max() <= 1e-6 * scale, kind
    finally:
        builder.close()


STRETCH = """<Objective type="data-fit"><fnc type="parameter">
    <param name="fem.mesh.node.fromId(3).position.x"/></fnc>
    <data><point>0.1, 2</point><point>0.6, 2</point><point>1, 2</point></data></Objective>"""


def _data_of_our_own(tmp_path: Path, E: float, v: float) -> str:
    """A data-fit objective of the bar's end position against time, from our model at E, v."""
    truth = _optimisation(tmp_path / "truth.feb", STRETCH, TWO)
    task = read_optimize(truth)
    builder = ModelBuilder(_model(tmp_path / "truth_model.feb", E, v), task)
    try:
        r, _ = _Objective(task, builder, "differences")._residuals(np.array([E, v]), False)
    finally:
        builder.close()
    x = r + task.data[:, 1]
    points = "".join(f"<point>{float(t)!r}, {float(y)!r}</point>"
                     for t, y in zip(task.data[:, 0], x, strict=True))  # fmt: skip
    return STRETCH.replace(STRETCH[STRETCH.index("<data>"):STRETCH.index("</data>")],
                           f"<data>{points}")  # fmt: skip


def test_a_fit_to_data_of_our_own_model_recovers_its_modulus_and_converges_to_zero(tmp_path):
    objective = _data_of_our_own(tmp_path, 3.0, 0.3)
    one = "<param name=\"fem.material('tissue').E\">1.5, 0.5, 5</param>"
    task = read_optimize(_optimisation(tmp_path / "opt.feb", objective, one, tol=1e-14))
    model = _model(tmp_path / "bar.feb", 1.0, 0.3)
    fit = run_optimize(task, model)
    assert fit.converged
    assert fit.parameters["fem.material('tissue').E"] == pytest.approx(3.0, rel=1e-6)
    assert fit.objective < 1e-14 * float(np.sum(task.data[:, 1] ** 2))
    assert fit.runs == fit.iterations + 1  # one differentiated run per evaluation
    # FEBio's forward differences: the same fit, with one more run per evaluation
    fd = run_optimize(task, model, gradients="differences")
    assert fd.parameters["fem.material('tissue').E"] == pytest.approx(3.0, rel=1e-4)
    assert fd.runs >= 2 * (fd.iterations + 1)
    # the model's steps by FEBio's quasi-Newton: its loose stopping points, the same fit
    febio = run_optimize(task, model, febio_solver=True)
    assert febio.parameters["fem.material('tissue').E"] == pytest.approx(3.0, rel=1e-3)


def test_a_bound_holds_the_parameter_as_febio_does(tmp_path):
    objective = _data_of_our_own(tmp_path, 3.0, 0.3)
    capped = "<param name=\"fem.material('tissue').E\">1.5, 0.5, 2.5</param>"
    task = read_optimize(_optimisation(tmp_path / "opt.feb", objective, capped,
                                       "constrained levmar"))  # fmt: skip
    fit = run_optimize(task, _model(tmp_path / "bar.feb"))
    assert fit.parameters["fem.material('tissue').E"] == pytest.approx(2.5)
    assert fit.objective > 0


def test_the_command_line_runs_an_optimisation_and_writes_its_report(tmp_path):
    objective = _data_of_our_own(tmp_path, 2.0, 0.3)
    one = "<param name=\"fem.material('tissue').E\">1.5, 0.5, 5</param>"
    opt = _optimisation(tmp_path / "opt.feb", objective, one)
    model = _model(tmp_path / "bar.feb")
    out = tmp_path / "out"
    command = [sys.executable, "-m", "tissuesim", "run", str(opt), "--model", str(model)]
    done = subprocess.run([*command, "--out", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    report = json.loads((out / "optimize.json").read_text())
    assert report["parameters"]["fem.material('tissue').E"] == pytest.approx(2.0, rel=1e-4)
    assert report["converged"] and report["runs"] >= 2
    rows = (out / "fit.csv").read_text().splitlines()
    assert rows[0] == "x,measured,simulated,quantity" and len(rows) == 4
    assert "final objective value" in done.stderr
    missing = subprocess.run([sys.executable, "-m", "tissuesim", "run", str(opt)],
                             capture_output=True, text=True)  # fmt: skip
    assert missing.returncode != 0
    lines = missing.stderr.strip().splitlines()
    assert len(lines) == 1 and "--model MODEL.feb" in lines[0]


@pytest.mark.parametrize(
    ("params", "objective", "message"),
    [
        (
            '<param name="fem.material[3].E">1, 0, 2</param>',
            OBJECTIVES["target"],
            "the model has 1 materials",
        ),
        (
            "<param name=\"fem.material('tissue').c9\">1, 0, 2</param>",
            OBJECTIVES["target"],
            "has no <c9>",
        ),
        (
            '<param name="fem.a">1, 0, 2</param>',
            OBJECTIVES["target"],
            r"'fem.a': the model has no <var name='a'> in <Globals><Variables>",
        ),
        (
            "<param name=\"fem.material('tissue').relaxation.tau1.points[1].y\">1, 0, 2</param>",
            OBJECTIVES["target"],
            "has no <relaxation>",
        ),
        (
            "<param name=\"fem.load_controller('lc').points[1].y\">1, 0, 2</param>",
            OBJECTIVES["target"],
            "not of load curves",
        ),
        (
            "<param name=\"fem.material('tissue').E\">3, 0, 2</param>",
            OBJECTIVES["target"],
            "not within its bounds",
        ),
        (
            TWO,
            '<Objective type="target"><var name="fem.mesh.node.fromId(99).position.x">1'
            "</var></Objective>",
            "no node with id 99",
        ),
        (
            TWO,
            '<Objective type="target"><var name="fem.rigidbody(\'plate\').Fz">1</var></Objective>',
            "no rigid body 'plate'",
        ),
        (
            TWO,
            '<Objective type="target"><var name="fem.nonsense">1</var></Objective>',
            "is not a quantity",
        ),
        (
            TWO,
            '<Objective type="data-fit"><fnc type="filter_sum"><element_data data="=sx+q" '
            'elem_set="bar"/></fnc><data><pt>1,1</pt></data></Objective>',
            "unknown name 'q'",
        ),
    ],
)
def test_bad_input_is_refused_in_one_line(tmp_path, params, objective, message):
    model = _model(tmp_path / "bar.feb")
    with pytest.raises(InputError, match=None) as caught:
        task = read_optimize(_optimisation(tmp_path / "opt.feb", objective, params))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            run_optimize(task, model)
    text = str(caught.value)
    assert message in text and "\n" not in text


def test_an_enclosed_volume_is_febios_formula_on_quads_and_triangles():
    from types import SimpleNamespace

    # the unit cube's six faces, outward, as quads and as triangles
    x = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], dtype=float)
    quads = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2],
                      [1, 3, 7, 5]])  # fmt: skip
    tris = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    mesh = SimpleNamespace(n_points=8, facet_sets={})
    body = SimpleNamespace(kind="fem", mesh=mesh, dim=3)
    system = SimpleNamespace(names=["b"], config_slices=[slice(0, 24)])
    sim = SimpleNamespace(bodies={"b": body}, system=system)
    stretched = (x * [2.0, 1.0, 1.5]).ravel()
    for facets in (quads, tris):
        assert EnclosedVolume(facets).values(sim, x.ravel())[0] == pytest.approx(1.0)
        assert EnclosedVolume(facets).values(sim, stretched)[0] == pytest.approx(3.0)


def test_element_expressions_are_read_safely():
    """FEBio's element expressions go through the scene's safe expressions (named variables)."""
    data = {"sx": np.array([1.0, 2.0]), "sy": np.array([3.0, 4.0])}
    evaluate, names = compile_named("sx + 2*sy**2 - sqrt(abs(sx))", ("sx", "sy", "sz"), "test")
    assert names == ["sx", "sy"]
    got = evaluate(data)
    assert np.allclose(got, data["sx"] + 2 * data["sy"] ** 2 - np.sqrt(data["sx"]))
    for bad in ("__import__('os')", "sx.real", "sx if sy else 1", "'a'", "sx[0]", ""):
        with pytest.raises(InputError):
            compile_named(bad, ("sx", "sy"), "test")


def test_the_models_solver_note_goes_when_febios_solver_runs_it(tmp_path):
    model = _model(tmp_path / "bar.feb")
    model.write_text(model.read_text().replace(
        "<step_size>0.25</step_size>",
        "<step_size>0.25</step_size><solver><dtol>0.001</dtol></solver>"))  # fmt: skip
    task = read_optimize(_optimisation(tmp_path / "opt.feb", OBJECTIVES["target"], TWO))
    for febio_solver, expected in ((False, 1), (True, 0)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            builder = ModelBuilder(model, task, febio_solver=febio_solver)
        builder.close()
        said = [n for n in builder.notes if "<solver>" in n]
        assert len(said) == expected, builder.notes


def test_a_rigid_platens_force_is_fitted_by_febios_differences_and_by_sensitivities(tmp_path):
    """FEBio's usual indentation fit (op01, op03: fem.rigidbody(...).Fz): the platen model of
    tests/febio/models, its force curve from our own run at E = 1e4, fitted from E = 6e3 by
    forward differences and by the run's sensitivities (fewer runs), to the same E."""
    model = tmp_path / "platen.feb"
    model.write_text((Path(__file__).parent / "models" / "rigid_platen.feb").read_text())
    force = """<Objective type="data-fit"><fnc type="parameter">
        <param name="fem.rigidbody('platen').Fz"/></fnc><data>{}</data></Objective>"""
    one = "<param name=\"fem.material('tissue').E\">{}, 1000, 50000</param>"
    probe = read_optimize(_optimisation(tmp_path / "probe.feb",
                                        force.format("<pt>0.5, 0</pt><pt>1, 0</pt>"),
                                        one.format(10000)))  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        builder = ModelBuilder(model, probe)
    try:
        r, _ = _Objective(probe, builder, "differences")._residuals(np.array([1e4]), False)
    finally:
        builder.close()
    assert np.all(np.abs(r) > 0)  # the platen carries a force
    points = "".join(f"<pt>{t}, {float(y)!r}</pt>" for t, y in zip((0.5, 1.0), r, strict=True))
    task = read_optimize(_optimisation(tmp_path / "opt.feb", force.format(points),
                                       one.format(6000), tol=1e-12))  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = run_optimize(task, model, gradients="differences")
        assert fit.parameters["fem.material('tissue').E"] == pytest.approx(1e4, rel=1e-4)
        exact = run_optimize(task, model)
    assert exact.parameters["fem.material('tissue').E"] == pytest.approx(1e4, rel=1e-4)
    assert exact.runs < fit.runs


def _sliding_stack(tmp_path: Path, E_low: float) -> Path:
    """tests/febio/models/contact_stack.feb without its puck and friction: a block pressed
    0.1 onto another through FEBio's sliding-elastic penalty contact (current-area weights),
    the lower block of its own material "firm" of modulus E_low."""
    import re

    text = (Path(__file__).parent / "models" / "contact_stack.feb").read_text()
    text = re.sub(r'\s*<Nodes name="puck">.*?</Nodes>', "", text, flags=re.S)
    text = re.sub(r'\s*<Elements type="hex8" name="puck">.*?</Elements>', "", text, flags=re.S)
    text = re.sub(r'\s*<NodeSet name="puck_(all|top)">[^<]*</NodeSet>', "", text)
    text = re.sub(r'\s*<Surface name="puck_bottom">.*?</Surface>', "", text, flags=re.S)
    text = re.sub(r'\s*<SolidDomain name="puck" mat="soft"/>', "", text)
    text = re.sub(r'\s*<bc name="puck_xy".*?</bc>', "", text, flags=re.S)
    text = re.sub(r'\s*<bc name="press_puck".*?</bc>', "", text, flags=re.S)
    text = re.sub(r'\s*<contact type="rigid_wall".*?</contact>', "", text, flags=re.S)
    text = text.replace("<fric_coeff>0.01</fric_coeff>", "<fric_coeff>0</fric_coeff>")
    text = text.replace('<SolidDomain name="lower" mat="soft"/>',
                        '<SolidDomain name="lower" mat="firm"/>')  # fmt: skip
    text = text.replace("  </Material>", '    <material id="2" name="firm" type="neo-Hookean">'
                        f"<density>1000</density><E>{E_low!r}</E><v>0.3</v></material>\n"
                        "  </Material>")  # fmt: skip
    path = tmp_path / f"stack_{E_low:g}.feb"
    path.write_text(text)
    return path


def test_a_modulus_under_febios_sliding_elastic_contact_is_fitted_by_sensitivities(tmp_path):
    """A block pressed onto another through FEBio's sliding-elastic contact (penalty, its
    points weighted by their current areas): the lower block's top from our own run at
    E = 2e4 is fitted from E = 1e4 by the run's sensitivities (through the contact's Hessian
    and its weights' derivative) back to 2e4, in fewer model runs than FEBio's differences."""
    from tissuesim.febio import load_febio

    truth = _sliding_stack(tmp_path, 2e4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(truth)
        (pair,) = scene.simulation.system.penalty_contacts
        assert pair.area == "current" and not pair.augmented
        sim = scene.simulation
        for _ in range(scene.run["steps"]):
            sim.step()
    top = float(sim.body_positions("lower")[4, 2])  # node 5, at z = 1 at rest
    assert top < 1.0 - 1e-3
    one = "<param name=\"fem.material('firm').E\">10000, 1000, 100000</param>"
    objective = ('<Objective type="target"><var name="fem.mesh.node.fromId(5).position.z">'
                 f"{top!r}</var></Objective>")  # fmt: skip
    task = read_optimize(_optimisation(tmp_path / "fit.feb", objective, one, tol=1e-12))
    model = _sliding_stack(tmp_path, 1e4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = run_optimize(task, model)
        fd = run_optimize(task, model, gradients="differences")
    assert fit.parameters["fem.material('firm').E"] == pytest.approx(2e4, rel=1e-6)
    assert fd.parameters["fem.material('firm').E"] == pytest.approx(2e4, rel=1e-4)
    assert fit.runs < fd.runs


def test_a_point_of_a_materials_curve_is_fitted(tmp_path):
    """FEBio's op09 names points of a material's curves (``...recruitment.function.points[1].y``):
    the point's y is set in the model's <point>x,y</point>; a recruitment curve's point is
    fitted back from data of our own model, by the run's sensitivities (through the
    recruitment's lag at FEBio's fixed point) and by FEBio's forward differences."""
    source = Path(__file__).parent / "models" / "reactive_viscoelastic_relaxation.feb"
    curve = ('<recruitment type="recruitment user"><function type="point"><interpolate>LINEAR'
             "</interpolate><points><point>0,1</point><point>0.05,{y}</point><point>0.5,1"
             "</point></points></function></recruitment>")  # fmt: skip
    model = tmp_path / "model.feb"
    model.write_text(source.read_text().replace("</relaxation>", "</relaxation>" + curve))
    name = "fem.material('tissue').recruitment.function.points[1].y"
    objective = """<Objective type="data-fit"><fnc type="parameter">
        <param name="fem.element_data('sx', 1)"/></fnc><data>{}</data></Objective>"""
    times = (0.2, 0.5, 1.0, 1.5, 2.0)
    task = read_optimize(_optimisation(
        tmp_path / "truth.feb", objective.format("".join(f"<pt>{t}, 0</pt>" for t in times)),
        f'<param name="{name}">1.5, 0.5, 4</param>'))  # fmt: skip
    text = model.read_text()
    model.write_text(text.replace("{y}", "2.5"))
    builder = ModelBuilder(model, task)
    try:
        r, _ = _Objective(task, builder, "differences")._residuals(np.array([2.5]), False)
    finally:
        builder.close()
    data = "".join(f"<pt>{t}, {float(v)!r}</pt>" for t, v in zip(times, r, strict=True))
    task = read_optimize(
        _optimisation(
            tmp_path / "opt.feb",
            objective.format(data),
            f'<param name="{name}">1.5, 0.5, 4</param>',
            tol=1e-12,
        )
    )
    model.write_text(text.replace("{y}", "1.0"))  # the model's own value is not the start
    fit = run_optimize(task, model)
    assert fit.gradients == "sensitivities" and fit.runs == fit.iterations + 1
    assert fit.parameters[name] == pytest.approx(2.5, rel=1e-6)
    fd = run_optimize(task, model, gradients="differences")
    assert fd.parameters[name] == pytest.approx(2.5, rel=1e-5)
    assert np.ptp(r) > 0.1 * np.abs(r).max()  # the data are a curve, not one value


def test_where_sensitivities_are_not_taken_febios_differences_are_said_and_used(tmp_path):
    """The sliding stack with FEBio's augmented Lagrangian (whose multipliers the
    sensitivities do not follow): the default optimisation says so in its log, uses FEBio's
    forward differences and still fits the modulus to data of its own."""
    from tissuesim.febio import load_febio

    def augmented(E_low: float) -> Path:
        path = _sliding_stack(tmp_path, E_low)
        text = path.read_text()
        assert "<penalty>" in text
        path.write_text(text.replace("<penalty>", "<laugon>AUGLAG</laugon><penalty>", 1))
        return path

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(augmented(2e4))
        sim = scene.simulation
        for _ in range(scene.run["steps"]):
            sim.step()
    top = float(sim.body_positions("lower")[4, 2])
    one = "<param name=\"fem.material('firm').E\">10000, 1000, 100000</param>"
    objective = ('<Objective type="target"><var name="fem.mesh.node.fromId(5).position.z">'
                 f"{top!r}</var></Objective>")  # fmt: skip
    task = read_optimize(_optimisation(tmp_path / "fit.feb", objective, one, tol=1e-12))
    lines = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = run_optimize(task, augmented(1e4), log=lines.append)
    assert fit.gradients == "differences"
    said = [line for line in lines if "forward differences are used" in line]
    assert len(said) == 1 and "augmented" in said[0] and "\n" not in said[0]
    assert fit.parameters["fem.material('firm').E"] == pytest.approx(2e4, rel=1e-4)
