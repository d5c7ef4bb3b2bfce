"""The README's and the manual's promises: a two-command quick start, every Python example of
the README and of docs/ runs as shown, the TOML examples are the shipped scenes, and the user
pages speak to users."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tissuesim.cli import example_path
from tissuesim.scene.loader import build_scene

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
#: every page whose code blocks are checked: the README and every page of the manual
PAGES = [README, *sorted(DOCS.rglob("*.md"))]
#: the pages written for users (the developer pages design.md, performance.md and the method
#: pages may cite commits and measurements)
USER_PAGES = [
    README,
    DOCS / "index.md",
    DOCS / "getting-started.md",
    DOCS / "examples.md",
    *sorted((DOCS / "guide").glob("*.md")),
    *sorted((DOCS / "reference").glob("*.md")),
]


def blocks(language: str, pages: list[Path] = PAGES) -> list[str]:
    """Every ``language`` fenced block of ``pages`` (default: the README and docs/)."""
    return [
        b
        for page in pages
        for b in re.findall(rf"```{language}\n(.*?)```", page.read_text(), flags=re.S)
    ]


def block(language: str, marker: str, pages: list[Path] = PAGES) -> str:
    """The one ``language`` block of ``pages`` that contains ``marker``."""
    (found,) = [b for b in blocks(language, pages) if marker in b]
    return found


def test_quick_start_has_exactly_two_commands():
    text = README.read_text()
    section = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    fenced = re.findall(r"```\w*\n(.*?)```", section, flags=re.S)
    assert len(fenced) == 1
    commands = [line for line in fenced[0].splitlines() if line.strip()]
    assert len(commands) == 2
    assert "demo" in commands[0] and "pytest" in commands[1]


def test_python_example_runs(tmp_path):
    """Getting started's first script: the course's square, 20 steps."""
    code = block("python", "import tissuesim as ts\nfrom tissuesim.mesh import select")
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    t, iterations, min_J = map(float, result.stdout.split())
    assert abs(t - 20 * 2 * np.pi / 200) < 1e-9 and iterations >= 1 and 0 < min_J < 2
    assert (tmp_path / "out/python_example/body.pvd").is_file()


def test_frames_python_example_runs(tmp_path):
    """The README's frame-based example, shortened to 3 steps (the code is otherwise as shown)."""
    code = block("python", "Simulation.from_frames")
    assert "steps=50" in code
    result = subprocess.run(
        [sys.executable, "-c", code.replace("steps=50", "steps=3")],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    out = tmp_path / "out/frames"
    for name in ("body_surface.pvd", "body_frames.pvd", "body.pvd", "final.png", "run.gif"):
        assert (out / name).is_file(), name
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"


def test_toml_example_is_the_shipped_beam_scene():
    readme_scene = tomllib.loads(block("toml", '[mesh]\ngenerator = "box"'))
    shipped = tomllib.loads(example_path("beam_3d_gravity").read_text())
    assert readme_scene == shipped
    scene = build_scene(readme_scene, name="readme_beam")
    sim = scene.simulation
    sim.step()
    tip = np.isclose(sim.mesh.points[:, 0], 1.0)
    assert sim.displacement[tip, 2].mean() < 0  # it sags


def test_coupled_python_example_runs(tmp_path):
    """The README's organs + tissue example, as shown: the force drops to the weight after the
    cut."""
    code = block("python", "add_tissue")
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    forces = [float(line.split()[-2]) for line in result.stdout.splitlines()]
    assert len(forces) == 10
    assert max(forces[:4]) > 60.0
    assert abs(forces[-1] - 58.86) < 0.5
    out = tmp_path / "out/coupled"
    for name in ("lower.pvd", "upper.pvd", "tissue_points.pvd", "cut.pvd", "summary.json"):
        assert (out / name).is_file(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and len(summary["forces"]) == 10


def test_several_bodies_python_example_runs(tmp_path):
    """The README's two glued blocks, shortened to 2 steps: forces balance without gravity's
    effect on the grasper's horizontal pull."""
    code = block("python", 'sim.attach("fat", "muscle"')
    assert 'sim.run(10, "out/two_blocks")' in code
    code = code.replace(
        'sim.run(10, "out/two_blocks")', 'sim.run(2, "out/two_blocks", render=False)'
    )
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    out = tmp_path / "out/two_blocks"
    for name in ("fat.pvd", "muscle.pvd", "forces.csv", "summary.json"):
        assert (out / name).is_file(), name
    assert not (out / "forces.png").exists()  # render=False draws no picture at all
    f = json.loads((out / "summary.json").read_text())["forces"][-1]
    assert f["grasper"][0] > 0  # it pulls the layer along +x; the clamp holds back
    total = np.array(f["grasper"]) + np.array(f["muscle.support"])
    weight = (1060 * 0.06 * 0.04 * 0.03 + 950 * 0.06 * 0.04 * 0.02) * 9.81
    np.testing.assert_allclose(total, [0, 0, weight], atol=1e-6 * weight)


def test_the_scene_key_table_names_every_table_the_loaders_accept():
    from tissuesim.scene.loader import SCENE_KEYS
    from tissuesim.scene.tables.coupled import COUPLED_SCENE_KEYS
    from tissuesim.scene.tables.frames import FRAME_SCENE_KEYS

    page = DOCS / "reference" / "scene-keys.md"
    section = page.read_text().split("Every key of every scene:", 1)[1].split("\n## ")[0]
    assert section.count("\n| `") > 20  # the table itself, not a mention
    for table in {*SCENE_KEYS, *FRAME_SCENE_KEYS, *COUPLED_SCENE_KEYS}:
        assert f"[{table}]" in section or f"`{table}`" in section, table


def test_nearly_incompressible_python_example_runs(tmp_path):
    code = block("python", 'formulation="mean_dilatation"')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert result.returncode == 0, result.stderr
    force = float(result.stdout.split()[-1])
    # benchmarks/liver_compression.py: 6.996 N at these 4 divisions (7.05 at 3, 6.95 converged)
    assert -7.1 < force < -6.9
    assert (tmp_path / "out/liver/liver.pvd").is_file()


def test_interactive_python_example_drives_the_probe(tmp_path):
    code = block("python", "lin = sim.instrument_linearization(")
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert result.returncode == 0, result.stderr
    # pressing down, no intersection; the linearised force grows with a further press
    assert result.stdout.split()[-3:] == ["True", "False", "True"]


def _run_block(marker: str, tmp_path) -> list[str]:
    """Run the one Python block holding ``marker`` in tmp_path; its printed words."""
    result = subprocess.run(
        [sys.executable, "-c", block("python", marker)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    return result.stdout.split()


def test_contact_modes_python_example_runs(tmp_path):
    """The contact page's interactive mode: the palpation's probe pressed, every step certified."""
    words = _run_block('report = record.extra["contact"]["prediction"]', tmp_path)
    assert words[-2:] == ["certified", "True"]


def test_haptic_thread_python_example_runs(tmp_path):
    """The contact page's device thread: it renders forces while the steps run, pushed up."""
    words = _run_block('sim.haptic_contact("probe")', tmp_path)
    assert words[-2:] == ["True", "True"]


def test_active_contraction_python_example_runs(capsys):
    """docs/guide/materials.md's active contraction: at rest, half-way up its ramp, the
    mixture's stress along the fibre is T0 = 1000 Pa (the matrix is unstrained)."""
    exec(block("python", "muscle.begin_step(0.5)"), {})
    assert float(capsys.readouterr().out.split()[-1]) == pytest.approx(1000.0, rel=1e-12)


def test_growth_python_example_runs(capsys):
    """docs/guide/materials.md's fibre growth: the grown shape Fg = diag(1, 1, 1.5) is stress
    free (round-off)."""
    exec(block("python", "grown.begin_step(0.5)"), {})
    assert float(capsys.readouterr().out.split()[-1]) < 1e-9


def test_prestrain_python_example_runs(capsys):
    """docs/guide/materials.md's prestrain: stressed at rest, free at F = F0^-1."""
    exec(block("python", 'held = ts.make_material("prestrain_elastic"'), {})
    assert capsys.readouterr().out.split() == ["True", "True"]


def test_penalty_contact_python_example_runs():
    """docs/guide/contact.md's penalty contact: the press carries the top's force and the
    table's, pushing up."""
    namespace: dict = {}
    exec(block("python", "sim.add_penalty_contact("), namespace)
    forces = namespace["sim"].forces()
    assert forces["press"][2] > 1.0
    np.testing.assert_allclose(forces["press"], -np.asarray(forces["top"]), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(forces["table"], -np.asarray(forces["top"]), rtol=1e-9, atol=1e-9)


def test_contact_python_example_runs_as_shown(tmp_path):
    """The README's contact snippet, standalone: the probe presses on the clamped block."""
    code = block("python", "sim.set_contact(dhat=0.005")
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "out/probe/summary.json").read_text())
    assert summary["status"] == "completed"
    last = summary["forces"][-1]
    assert last["probe"][2] < 0.0  # the probe pushes the block down
    np.testing.assert_allclose(
        np.add(last["probe"], last["body.support"]), 0.0, atol=1e-6 * abs(last["probe"][2])
    )


def test_save_and_load_python_example_is_bit_identical(tmp_path):
    code = block("python", 'sim.save("beam.npz")')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["True"]
    assert (tmp_path / "beam.npz").is_file()


def test_toml_two_bodies_example_is_the_shipped_scene():
    shown = tomllib.loads(block("toml", "[[attachments]]"))
    assert shown == tomllib.loads(example_path("two_blocks_tied").read_text())


def test_every_toml_block_parses():
    for code in blocks("toml"):
        tomllib.loads(code)


#: words about how the project was made, not about what it does: not for users' pages
INTERNAL = re.compile(
    r"\bissues? \d+|\bsessions? \d+|\bsession's\b|field notes|field-notes|"
    r"the issue's|\bthe issue\b",
    flags=re.I,
)


def test_user_pages_speak_to_users():
    assert len(USER_PAGES) > 10
    for page in USER_PAGES:
        found = [m.group(0) for m in INTERNAL.finditer(page.read_text())]
        assert not found, f"{page.relative_to(ROOT)}: {found}"


def test_user_pages_check_catches_internal_words():
    for text in (
        "see issue 14",
        "fixed in session 7",
        "FIELD-NOTES",
        "the field notes",
        "the issue's goals",
        "an earlier session's figure",
    ):
        assert INTERNAL.search(text), text
    for text in ("connective tissue", "tissues", "Problem Session IV"):
        assert not INTERNAL.search(text), text


def test_fitting_python_example_recovers_the_parameters(tmp_path):
    """The materials guide's fitting example, as shown: the two-term Ogden law comes back, the
    Mooney-Rivlin law fits worse."""
    code = block("python", 'ts.fit_material("ogden"')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    ogden, mooney = result.stdout.splitlines()
    assert ogden.replace(" ", "").startswith("[1200.-300.][7.-2.]")
    assert float(ogden.split()[-1]) < 1e-10
    assert 0.01 < float(mooney.split()[-1]) < 0.2


#: each Python block of the README and docs/ and the test that runs it (by a text only it
#: contains)
TESTED_PYTHON_BLOCKS = {
    "import zarr\n": "test_sweep_zarr_python_example_runs",
    'out="out/fat_ray"': "test_sweep_cluster_python_examples_run",
    "def block(p):": "test_identify_python_example_recovers_the_parameters",
    "fit = ts.identify(": "test_identify_python_example_recovers_the_parameters",
    "def indent(p):": "test_identify_contact_python_example_runs",
    'regions={"soft": (left, soft)}': "test_regions_python_example_runs",
    "import tissuesim as ts\nfrom tissuesim.mesh import select": "test_python_example_runs",
    'sim.attach("fat", "muscle"': "test_several_bodies_python_example_runs",
    "Simulation.from_frames": "test_frames_python_example_runs",
    "sim.set_contact(dhat=0.005": "test_contact_python_example_runs_as_shown",
    "sim.add_penalty_contact(": "test_penalty_contact_python_example_runs",
    "muscle.begin_step(0.5)": "test_active_contraction_python_example_runs",
    "grown.begin_step(0.5)": "test_growth_python_example_runs",
    'held = ts.make_material("prestrain_elastic"': "test_prestrain_python_example_runs",
    "lin = sim.instrument_linearization(": "test_interactive_python_example_drives_the_probe",
    'report = record.extra["contact"]["prediction"]': "test_contact_modes_python_example_runs",
    'sim.haptic_contact("probe")': "test_haptic_thread_python_example_runs",
    "add_tissue": "test_coupled_python_example_runs",
    'formulation="mean_dilatation"': "test_nearly_incompressible_python_example_runs",
    'sim.save("beam.npz")': "test_save_and_load_python_example_is_bit_identical",
    'ts.fit_material("ogden"': "test_fitting_python_example_recovers_the_parameters",
    'element="hex"': "test_hexahedra_python_example_runs",
    'element="hex20"': "test_quadratic_hexahedra_python_example_runs",
    'element="wedge"': "test_wedges_python_example_runs",
    "from tissuesim.time.phases import Phase": "test_phases_python_example_runs",
    "sim.add_visual_surface(": "test_visual_surface_python_example_runs",
    "import sympy as sp\nimport tissuesim as ts": "test_energy_law_python_example_runs",
    "ts.SolidMixture([": "test_mixture_python_example_runs",
    'sim.add_logfile("node_data"': "test_logfile_python_example_runs",
    'sim.add_rigid_body(\n    "press"': "test_rigid_body_python_example_runs",
    'sim.add_rigid_joint("revolute"': "test_rigid_joint_python_example_runs",
    'out="out/fat_study"': "test_sweep_python_example_runs",
    'out="out/fat_dask"': "test_sweep_cluster_python_examples_run",
}


def test_sweep_python_example_runs(tmp_path):
    """The parameter studies page's study: 8 runs completed, the dataset's shape as printed."""
    code = block("python", 'out="out/fat_study"')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == "8 runs completed" and lines[-1] == "(8, 105, 3)"
    assert (tmp_path / "out" / "fat_study" / "runs.csv").exists()


def test_sweep_zarr_python_example_runs(tmp_path):
    """The parameter studies page's Zarr example: the study above written as Zarr, then one
    run's group opened with zarr as shown (its stiffness attribute and displacement array)."""
    pytest.importorskip("zarr")
    study = (
        block("python", 'out="out/fat_study"')
        .replace('out="out/fat_study",', 'out="out/fat_zarr", dataset_format="zarr",')
        .replace('load_dataset("out/fat_study")', 'load_dataset("out/fat_zarr")')
    )
    shown = block("python", "import zarr\n")
    last = shown.strip().splitlines()[-1]
    code = study + "\n" + shown + f"\nvalue, u = {last}\nprint(float(value), u.shape)\n"
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    value, shape = result.stdout.splitlines()[-1].split(" ", 1)
    assert 2e3 <= float(value) <= 8e3 and shape == "(105, 3)"


@pytest.mark.parametrize(("module", "marker"), [("distributed", 'out="out/fat_dask"'),
                                               ("ray", 'out="out/fat_ray"')])  # fmt: skip
def test_sweep_cluster_python_examples_run(tmp_path, module, marker):
    """The parameter studies page's Dask LocalCluster and Ray studies, as shown (indented in a
    list; Ray is in no extra: its test runs where it is installed, as in the development
    environment, and is skipped elsewhere)."""
    pytest.importorskip(module)
    code = textwrap.dedent(block("python", marker))
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[-1] == "['completed', 'completed', 'completed']"


def test_rigid_body_python_example_runs(tmp_path):
    """The rigid bodies page's platen: pressed 2 mm at t = 1 s, its centre 2 mm down."""
    code = block("python", 'sim.add_rigid_body(\n    "press"')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    centre = [float(v) for v in result.stdout.splitlines()[-1].strip("[]").split()]
    assert centre[2] == pytest.approx(0.011 - 0.002)
    assert (tmp_path / "out" / "forces.csv").exists()


def test_rigid_joint_python_example_runs(tmp_path):
    """The rigid bodies page's arm on a revolute joint: its centre (1, 0, 0.1) turned
    0.5 rad about z."""
    code = block("python", 'sim.add_rigid_joint("revolute"')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    centre = [float(v) for v in result.stdout.splitlines()[-1].strip("[]").split()]
    assert centre == pytest.approx([np.cos(0.5), np.sin(0.5), 0.1], abs=1e-6)


def test_logfile_python_example_runs(tmp_path):
    """The output page's log tables: the pulled face's ux ends at 0.2 m and its reactions sum
    to the pull's force in forces.csv."""
    code = block("python", 'sim.add_logfile("node_data"')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    ux, rx = (float(v) for v in result.stdout.split())
    assert ux == pytest.approx(0.2)
    forces = np.genfromtxt(tmp_path / "out/logfile/forces.csv", delimiter=",", names=True)
    assert rx == pytest.approx(forces["pull_x_N"][-1], rel=1e-12)
    assert (tmp_path / "out/logfile/element_data_2.csv").is_file()


def test_mixture_python_example_runs(tmp_path):
    """The materials page's solid mixture: stretched along its fibre it pulls the neo-Hookean
    matrix's P_xx plus the fibre's 2 l ksi x^(beta-1) exp(alpha x^beta), x = l^2 - 1; shortened,
    the matrix's alone."""
    code = block("python", "ts.SolidMixture([")
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    both, matrix, slack = result.stdout.split()
    x = 1.15**2 - 1.0
    fibre = 2 * 1.15 * 5e3 * x**1.5 * np.exp(2.0 * x**2.5)
    assert float(both) == pytest.approx(float(matrix) + fibre, abs=0.1)
    assert slack == "True"


def test_mixture_toml_example_runs_as_a_scene(tmp_path):
    """The materials page's mixture table, on a box whose per-cell fibre expressions it
    evaluates: the scene loads and steps."""
    from tissuesim.scene.loader import load_scene

    table = block("toml", 'model = "solid_mixture"')
    scene = (
        '[mesh]\ngenerator = "box"\nlower = [-0.5, -0.5, 0.0]\nupper = [0.5, 0.5, 0.2]\n'
        "divisions = [2, 2, 1]\n\n" + table + "\n[simulation]\ndensity = 1000.0\n"
        'integrator = "quasistatic"\ntime_step = 0.1\n\n[gravity]\n'
        "acceleration = [0.0, 0.0, -9.81]\n\n[[dirichlet]]\n"
        "vertices = { on_plane = { axis = 2, value = 0.0 } }\n\n[run]\nsteps = 1\n"
    )
    path = tmp_path / "mixture.toml"
    path.write_text(scene)
    sim = load_scene(path).simulation
    fibre = sim.body(next(iter(sim.bodies))).model.material.components[1]
    assert fibre.fibres.shape[1:] == (1, 3) and len(fibre.fibres) > 1  # one per point
    sim.step()
    assert np.all(np.isfinite(sim.positions))


def test_energy_law_python_example_runs(tmp_path):
    """The materials page's laws from their energies: their small-strain moduli are the closed
    forms (Mooney-Rivlin: mu = 2 (c1 + c2), lambda = k - 2 mu / 3; neo-Hookean: its own)."""
    pytest.importorskip("sympy")
    code = block("python", "import sympy as sp\nimport tissuesim as ts")
    code += "\nprint(law.mu, law.lam, nh.mu, nh.lam)"
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    mu, lam, mu_nh, lam_nh = map(float, result.stdout.split()[-4:])
    assert mu == pytest.approx(2400.0, rel=1e-9) and lam == pytest.approx(1e5 - 1600.0, rel=1e-9)
    assert mu_nh == pytest.approx(400.0, rel=1e-9) and lam_nh == pytest.approx(4e3, rel=1e-9)


def test_visual_surface_python_example_runs(tmp_path):
    """The output page's fine surface on a coarse liver: its series, and the shape it prints."""
    code = block("python", "sim.add_visual_surface(")
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split()[-2:] == ["(10242,", "3)"]
    out = tmp_path / "out/liver_fine"
    assert (out / "liver_fine.pvd").read_text().count("<DataSet") == 5
    assert (out / "final.png").is_file()


def test_phases_python_example_runs(tmp_path):
    """The time-integration page's run in phases: pulled, then let go (no pull force)."""
    code = block("python", "from tissuesim.time.phases import Phase")
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    time, integrator, *force = result.stdout.replace("[", " ").replace("]", " ").split()
    assert float(time) == 1.1 and integrator == "backward_euler"
    assert [float(f.strip(",")) for f in force] == [0.0, 0.0, 0.0]


def test_hexahedra_python_example_runs(tmp_path):
    """The elements page's Q1/P0 cantilever: the deflection it prints (plain Q1 locks: half)."""
    code = block("python", 'element="hex"')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    assert float(result.stdout.split()[-1]) == -0.0121


def test_wedges_python_example_runs(tmp_path):
    """The elements page's cantilever of wedges, loaded on its end's quadrilaterals and its
    top's triangles: the deflection it prints."""
    code = block("python", 'element="wedge"')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    assert float(result.stdout.split()[-1]) == -0.0168


def test_quadratic_hexahedra_python_example_runs(tmp_path):
    """The elements page's hexahedron20 Q2/P0 cantilever: the deflection it prints."""
    code = block("python", 'element="hex20"')
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    assert float(result.stdout.split()[-1]) == -0.0132


def test_every_python_block_of_the_readme_and_the_docs_is_run_by_a_test():
    assert blocks("python"), "no Python examples found"
    for code in blocks("python"):
        owners = [test for marker, test in TESTED_PYTHON_BLOCKS.items() if marker in code]
        assert len(owners) == 1, code
        assert owners[0] in globals(), owners[0]


def test_regions_python_example_runs():
    """The bodies page's bar of two regions: 4 of its 10 columns of 24 tetrahedra soft, the
    others the body's."""
    scope: dict = {}
    exec(block("python", 'regions={"soft": (left, soft)}'), scope)
    parts = scope["body"].model.parts
    assert [(p.name, p.cells.size) for p in parts] == [("soft", 96), ("default", 144)]


def test_identify_contact_python_example_runs(tmp_path):
    """docs/guide/identify.md: an indentation's force (downwards on the block) and its
    derivatives: it pushes harder for a stiffer block and a deeper press."""
    pages = [DOCS / "guide" / "identify.md"]
    head = block("python", "def block(p):", pages).split("def block(p):")[0]  # the imports
    code = head + block("python", "def indent(p):", pages)
    code += "\nprint(*run.values[-1], *run.jacobian[-1].ravel())\n"
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    push, d_E, d_depth = map(float, result.stdout.split()[-3:])
    assert push < 0 and d_E < 0 and d_depth < 0


def test_identify_python_example_recovers_the_parameters(tmp_path):
    """docs/guide/identify.md: the derivatives' shapes, then the fit within 2 % in at most 15
    runs."""
    pages = [DOCS / "guide" / "identify.md"]
    code = block("python", "def block(p):", pages) + block("python", "fit = ts.identify", pages)
    code += "\nprint(fit.parameters['E'], fit.parameters['nu'], fit.runs)\n"
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    E, nu, runs = map(float, result.stdout.split()[-3:])
    assert E == pytest.approx(5e4, rel=0.02) and nu == pytest.approx(0.35, rel=0.02)
    assert runs <= 15
